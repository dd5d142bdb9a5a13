"""`brdfnorm audit` of F_avg tables (brdfnorm.audit.fresnel_average): the artistic conductor's over (r, g), Schlick's
over f0, the dielectric's over η; OSPRay's Kulla–Conty fits named with their error against the exact F_avg.

Every exact value is checked against an independent route: scipy's adaptive quad over μ of 2μF(μ), with F the
unpolarized Fresnel reflectance of a complex index written here from the s and p amplitudes (no brdfnorm code),
or a closed form (Schlick's f0 + (1 − f0)/21; F = 0 for the index-matched r = 0 conductor)."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest
from helpers import paths
from scipy import integrate

from brdfnorm.audit import audit
from brdfnorm.errors import ArgumentError

SRC = str(paths.SRC)

#: OSPRay's FresnelConductorArtistic_evalAvg constants (modules/cpu/render/bsdfs/Fresnel.ih, Apache-2.0), restated
#: here from the source so that the fit is not read back from the module under test: 1, g, g², g³, r, r², r³, gr,
#: g²r, gr².
OSPRAY = (0.087237, 0.0230685, -0.0864902, 0.0774594, 0.782654, -0.136432, 0.278708, 0.19744, 0.0360605, -0.2586)


def ospray_cubic(r, g):
    r = np.minimum(r, 0.99)  # FresnelConductorArtistic_create clamps the reflectivity
    c = OSPRAY
    return (c[0] + c[1] * g + c[2] * g**2 + c[3] * g**3 + c[4] * r + c[5] * r**2 + c[6] * r**3 + c[7] * g * r
            + c[8] * g**2 * r + c[9] * g * r**2)


def fresnel(mu: float, index: complex) -> float:
    """Unpolarized reflectance at cos θ = μ of a complex relative index (s and p amplitudes)."""
    n2 = complex(index) ** 2
    w = np.sqrt(n2 - (1.0 - mu * mu) + 0j)
    rs = (mu - w) / (mu + w)
    rp = (n2 * mu - w) / (n2 * mu + w)
    return float((abs(rs) ** 2 + abs(rp) ** 2) / 2)


def favg_quad(index: complex) -> float:
    eta = complex(index)
    breaks = [float(np.sqrt(1 - eta.real**2))] if eta.imag == 0 and eta.real < 1 else None
    value, _ = integrate.quad(lambda mu: 2 * mu * fresnel(mu, index), 0, 1, points=breaks, epsabs=1e-14,
                              epsrel=1e-13, limit=200)
    return value


def artistic_quad(r: float, g: float) -> float:
    if r >= 1:
        return 1.0
    n = g * (1 - r) / (1 + r) + (1 - g) * (1 + np.sqrt(r)) / (1 - np.sqrt(r))
    k = np.sqrt(max((r * (n + 1) ** 2 - (n - 1) ** 2) / (1 - r), 0.0))
    return favg_quad(complex(n, k))


def test_independent_quadrature_knows_its_limits():
    assert favg_quad(1.0) == pytest.approx(0.0, abs=1e-14)  # index-matched: nothing reflected
    assert favg_quad(1.5) == pytest.approx(0.0918, abs=1e-4)  # the glass value every paper quotes
    assert artistic_quad(0.0, 1.0) == pytest.approx(0.0, abs=1e-14)  # r = 0 is an index-matched conductor


def _grid(n: int = 9):
    return np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n), indexing="ij")


def test_the_exact_artistic_table_is_named_and_passes():
    from brdfnorm.models.fresnel import Fresnel

    r, g = _grid()
    exact, _ = Fresnel("artistic", r=np.minimum(r, 1 - 1e-15), g=g).average()
    exact[r == 1] = 1.0
    for i, j in [(1, 1), (4, 8), (7, 2), (8, 5)]:  # every value checked at probe cells against scipy's quad
        assert exact[i, j] == pytest.approx(artistic_quad(r[i, j], g[i, j]), abs=1e-11)
    result = audit(exact.T, "ggx", dense=False, sweep=False, pins={"channels": "F_avg"})  # stored g-major
    assert result.passes and result.approximation is None
    assert result.best.convention.roles == ("g", "r") and result.best.convention.r_max == 1.0
    assert result.best.channels[0].max < 1e-12


def test_a_defect_in_an_exact_table_is_listed_and_fixed():
    from brdfnorm.models.fresnel import Fresnel

    r, g = _grid()
    exact, _ = Fresnel("artistic", r=np.minimum(r, 1 - 1e-15), g=g).average()
    exact[r == 1] = 1.0
    table = exact.copy()
    table[3:5, 5:7] += 2e-3
    result = audit(table, "ggx", dense=False, sweep=False, pins={"axes": "r,g"})
    assert result.fits and not result.passes
    wrong = result.wrong_cells["0"]
    assert sorted(tuple(c["index"]) for c in wrong["cells"]) == [(3, 5), (3, 6), (4, 5), (4, 6)]
    assert len(wrong["regions"]) == 1
    cell = wrong["cells"][0]
    assert cell["exact"] == pytest.approx(artistic_quad(cell["at"]["r"], cell["at"]["g"]), abs=1e-11)
    assert cell["error"] == pytest.approx(2e-3, abs=1e-12)
    assert np.allclose(result.fixed[..., 0], exact, atol=1e-15, rtol=0)


def test_the_pinned_ospray_cubic_is_named():
    r, g = _grid(17)
    table = ospray_cubic(g, r)  # stored g-major
    result = audit(table, "ggx", dense=False, sweep=False, pins={"channels": "F_avg"})
    assert not result.passes and result.approximation["within"] == 17 * 17
    assert result.best.convention.roles == ("g", "r") and result.best.convention.r_max == 0.99
    channel = result.approximation["channels"][0]
    assert tuple(channel["worst_cell"]) == (16, 0) and channel["worst_at"] == {"g": 1.0, "r": 0.0}
    i, j = 16, 9  # r = 9/16: the largest error away from r = 0, against scipy's quad
    assert result.best.channels[0].residual[i, j] == pytest.approx(table[i, j] - artistic_quad(9 / 16, 1.0),
                                                                   abs=1e-11)


@pytest.mark.slow
def test_the_ospray_cubic_is_named_with_its_error_against_the_exact_average(tmp_path):
    """A C header of OSPRay's cubic over 33 × 33 (r, g) nodes, float32, audited through the CLI (unpinned: the
    microfacet conventions are searched first, ~10 s)."""
    r, g = _grid(33)
    values = ospray_cubic(r, g).astype(np.float32)
    path = tmp_path / "favg.h"
    rows = ",\n".join(", ".join(f"{v:.9g}f" for v in row) for row in values)
    path.write_text(f"static const float favg[33 * 33] = {{\n{rows}\n}};\n")
    run = subprocess.run([sys.executable, "-m", "brdfnorm", "audit", str(path), "--json", "--no-sweep"],
                         capture_output=True, text=True, timeout=600,
                         env={**os.environ, "PYTHONPATH": SRC + os.pathsep + os.environ.get("PYTHONPATH", "")})
    assert run.returncode == 1, run.stderr
    payload = json.loads(run.stdout)
    approx = payload["approximation"]
    assert approx["name"] == "OSPRay's Kulla–Conty cubic fit of the artistic conductor's F_avg"
    assert approx["within"] == approx["cells"] == 33 * 33
    assert payload["best"]["convention"]["r_max"] == 0.99
    channel = approx["channels"][0]
    # the worst cell: r = 0, g = 1, where the exact conductor is index-matched (F_avg = 0) and the cubic is the sum
    # of its constants in g: 0.1012747
    assert tuple(channel["worst_cell"]) == (0, 32)
    assert channel["max"] == pytest.approx(float(np.float32(sum(OSPRAY[:4]))), abs=1e-7)
    # away from r = 0 the largest error is 0.0498 at g = 1, r = 18/32 (each value against scipy's quad)
    inner = [(abs(float(values[i, j]) - artistic_quad(min(r[i, j], 0.99), g[i, j])), i, j)
             for i in range(2, 33, 4) for j in (0, 16, 32)] + [
        (abs(float(values[18, 32]) - artistic_quad(18 / 32, 1.0)), 18, 32)]
    top = max(inner)
    assert (top[1], top[2]) == (18, 32)
    assert top[0] == pytest.approx(0.0498, abs=2e-4)
    assert payload["best"]["channels"][0]["max"] == pytest.approx(channel["max"], abs=1e-12)


def test_schlick_average_over_f0_is_f0_plus_a_21st():
    f0 = (np.arange(16) + 0.5) / 16
    table = f0 + (1 - f0) / 21
    for x in (f0[0], f0[9]):
        quad, _ = integrate.quad(lambda mu, x=x: 2 * mu * (x + (1 - x) * (1 - mu) ** 5), 0, 1, epsabs=1e-15)
        assert x + (1 - x) / 21 == pytest.approx(quad, abs=1e-15)
    result = audit(table[::-1], "ggx", dense=False, sweep=False, pins={"axes": "f0"})
    assert result.passes and result.best.convention.positions == ("texel",) and result.best.convention.flips == (True,)


@pytest.mark.parametrize("layout", ["eta-cycles", "eta-moonray-exiting"])
def test_dielectric_average_over_an_eta_axis_in_its_layout(layout):
    from brdfnorm.audit.fresnel_average import AverageConvention, exact_average

    c = AverageConvention(("eta",), (layout,), (False,), meanings=("F_avg",))
    eta = c.stored_values((17,), [np.arange(17)])["eta"]
    if layout == "eta-moonray-exiting":
        assert eta[0] == pytest.approx(1 / 1.05) and eta[-1] == pytest.approx(1 / 3.05)
    table, _ = exact_average("dielectric", {"eta": eta})
    for i in (1, 8, 16):  # with total internal reflection below the critical angle where η < 1
        assert table[i] == pytest.approx(favg_quad(eta[i]), abs=1e-11)
    result = audit(table, "ggx", dense=False, sweep=False, pins={"channels": "F_avg"})
    assert result.passes and result.best.convention.positions == (layout,)


@pytest.mark.parametrize("exiting, largest", [(False, 6.52e-3), (True, 7.51e-4)])
def test_the_ospray_dielectric_fit_is_named(exiting, largest):
    eta = 1.05 + 2 * np.linspace(0, 1, 17)  # MoonRay's η layout
    if exiting:  # Kulla & Conty's fit below 1, as OSPRay's fresnelDielectricAvg (written for interior/exterior)
        eta = 1 / eta
        table = 0.997118 + 0.1014 * eta - 0.965241 * eta**2 - 0.130607 * eta**3
    else:
        table = (eta - 1) / (4.08567 + 1.00071 * eta)
    result = audit(table, "ggx", dense=False, sweep=False, pins={"axes": "eta"})
    assert result.approximation["name"] == "OSPRay's Kulla–Conty fit of the dielectric's F_avg"
    worst = result.approximation["channels"][0]
    i = worst["worst_cell"][0]
    assert worst["worst_at"]["eta"] == pytest.approx(eta[i])
    assert worst["max"] == pytest.approx(abs(table[i] - favg_quad(eta[i])), abs=1e-11)
    assert worst["max"] == pytest.approx(largest, abs=1e-5)


def test_bad_pins_are_refused_naming_the_argument():
    with pytest.raises(ArgumentError, match="F_avg table has one axis"):
        audit(np.zeros((4, 4, 4)) + 0.5, "ggx", dense=False, sweep=False, pins={"channels": "F_avg"})
    with pytest.raises(ArgumentError, match="r and g axes are node or texel"):
        audit(np.zeros((4, 4)) + 0.5, "ggx", dense=False, sweep=False, pins={"channels": "F_avg"},
              axes={"alpha": np.linspace(0, 1, 4)})
    with pytest.raises(ArgumentError, match="name no axis of an F_avg table of 2 axes"):
        audit(np.zeros((4, 4)) + 0.5, "ggx", dense=False, sweep=False, pins={"channels": "F_avg"},
              axes={"eta": np.linspace(1.1, 2, 4)})
    with pytest.raises(ArgumentError, match="axes=f0,g"):
        audit(np.zeros((4, 4)) + 0.5, "ggx", dense=False, sweep=False, pins={"channels": "F_avg", "axes": "f0,g"})


def test_a_bad_f_avg_pin_is_one_line_exit_2(tmp_path, capsys):
    from brdfnorm.cli import main

    path = tmp_path / "favg.csv"
    path.write_text("0.1,0.2,0.3\n0.2,0.3,0.4\n0.3,0.4,0.5\n")
    with pytest.raises(SystemExit) as done:  # in-process: the same entry point as the console script
        main(["audit", str(path), "--as", "channels=F_avg", "--as", "axes=f0,eta"])
    out, err = capsys.readouterr()
    assert done.value.code == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:") and "axes=f0,eta" in lines[0], err


def test_fix_of_an_f_avg_header_touches_only_the_wrong_cells(tmp_path, capsys):
    from brdfnorm.cli import main
    from brdfnorm.models.fresnel import Fresnel

    r, g = _grid(9)
    exact, _ = Fresnel("artistic", r=np.minimum(r, 1 - 1e-15), g=g).average()
    exact[r == 1] = 1.0
    rows = [[f"{v:.9g}f" for v in row] for row in exact.astype(np.float32)]
    rows[4][3] = "0.5f"  # one wrong cell
    source = tmp_path / "favg.h"
    source.write_text("static const float favg[9 * 9] = {\n" + ",\n".join(", ".join(row) for row in rows) + "\n};\n")

    def run(*argv):
        try:
            main(["audit", *argv, "--as", "channels=F_avg"])
            code = 0
        except SystemExit as done:
            code = done.code or 0
        return code, capsys.readouterr()

    code, _ = run(str(source), "--fix", "-o", str(tmp_path / "fixed.h"))
    assert code == 1
    before = source.read_text().splitlines()
    after = (tmp_path / "fixed.h").read_text().splitlines()[1:]  # a comment line with the fix's metadata first
    changed = [(a, b) for a, b in zip(before, after, strict=True) if a != b]
    assert len(changed) == 1 and changed[0][0].replace("0.5f", f"{np.float32(exact[4, 3]):.9g}f") == changed[0][1]
    assert float(f"{np.float32(exact[4, 3]):.9g}") == pytest.approx(artistic_quad(0.5, 3 / 8), abs=1e-7)
    code, (out, _) = run(str(tmp_path / "fixed.h"))
    assert code == 0 and "PASS" in out
