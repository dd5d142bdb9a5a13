"""Smoke test of benchmarks/run.py --quick: the structure of its results, and that every error is computed.

No timing is asserted (shared machines are noisy); the numbers checked are errors against references that the
benchmark computes independently (mpmath, closed forms), plus two facts a broken harness would get wrong: the
peers agree with brdfnorm where they are known to converge, and dblquad is the one that misses the grazing
n = 1e4 lobe (seed 002's warning) without saying so.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"
sys.path.insert(0, str(BENCH))

import peers  # noqa: E402
import run as bench  # noqa: E402


@pytest.fixture(scope="module")
def quick(tmp_path_factory) -> tuple[dict, Path]:
    out = tmp_path_factory.mktemp("bench")
    workloads = ["single", "table90", "norm-table", "fit", "eval", "work-precision", "memory"]
    return bench.run(quick=True, only=workloads, out_dir=out), out


@pytest.mark.slow
def test_outputs_written(quick):
    results, out = quick
    assert json.loads((out / "latest.json").read_text())["meta"]["quick"] is True
    text = (out / "latest.md").read_text()
    assert "## targets" in text and "speed-up" in text.lower()
    assert set(results["plots"]) == {"cost_vs_n.png", "work_precision.png"}
    for name in results["plots"]:
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.slow
def test_every_method_has_a_finite_error(quick):
    results, _ = quick
    measured = [w for w in results["workloads"].values() if "methods" in w]
    assert {"single", "table90", "norm-table"} <= {k for k, w in results["workloads"].items() if "methods" in w}
    for workload in measured:
        for name, line in workload["methods"].items():
            assert line["points"] > 0, name
            assert math.isfinite(line["max_rel_error"]), (workload["title"], name)
            assert line["time_s"] > 0
    for workload in ("single", "table90", "norm-table"):
        methods = results["workloads"][workload]["methods"]
        assert {"brdfnorm", "dblquad", "cubature", "mc float32", "mc float64"} <= set(methods)
        assert all(line["speedup_of_brdfnorm"] > 0 for m, line in methods.items() if m != "brdfnorm")
    for panel in results["workloads"]["work-precision"]["panels"].values():
        for points in panel["lines"].values():
            assert all(math.isfinite(p["rel_error"]) for p in points)


@pytest.mark.slow
def test_errors_are_real(quick):
    """brdfnorm and cubature at rtol 1e-9 land within 1e-8 of the mpmath / closed-form references."""
    results, _ = quick
    table = results["workloads"]["table90"]
    assert table["methods"]["brdfnorm"]["max_rel_error"] < 1e-8
    assert table["methods"]["cubature"]["max_rel_error"] < 1e-8
    # The 1e-13 quadrature that fills in the reference agrees with mpmath at 30 digits.
    assert table["cross_check"] and max(table["cross_check"].values()) < 1e-12
    # Quick MC uses 1e5 samples: a few digits at most, but not garbage at moderate angles.
    assert 0 < results["workloads"]["single"]["methods"]["mc float64"]["max_rel_error"] < 1e-2
    norm = results["workloads"]["norm-table"]
    assert norm["methods"]["brdfnorm"]["max_rel_error"] < 1e-8
    # dblquad silently misses the n = 1e4 lobe at θ_o = 89° (true albedo 1.26e-6, mpmath): a large error.
    assert norm["methods"]["dblquad"]["max_rel_error"] > 0.5


@pytest.mark.slow
def test_targets_and_memory(quick):
    results, _ = quick
    names = " ".join(t["target"] for t in results["targets"])
    assert "dblquad" in names and "MC float32" in names and "RSS" in names
    # Issue 13's goals carry where their verdict is explained, and that place exists.
    engine = [t for t in results["targets"] if "brdfnorm quadrature: ≥ 100× faster than dblquad" in t["target"]]
    assert engine and all(t["why"] == bench.ENGINE_WHY for t in engine)
    readme = (Path(bench.__file__).parent / "README.md").read_text(encoding="utf-8")
    assert "### Issue 13's speed goals: the verdict" in readme and "issue 13's speed goals" in bench.ENGINE_WHY
    memory = results["workloads"]["memory"]
    assert memory["peak_rss_mib"] >= memory["baseline_rss_mib"] > 0


def test_hammersley_and_mc_against_closed_forms():
    # Radical inverse: 1 -> 0.5, 2 -> 0.25, 3 -> 0.75, 6 -> 0.375 (bit reversal).
    assert peers.radical_inverse_base2(np.array([1, 2, 3, 6])).tolist() == [0.5, 0.25, 0.75, 0.375]
    directions = peers.hammersley_cosine(4096)
    assert np.allclose(np.linalg.norm(directions, axis=1), 1.0) and directions[:, 2].min() >= 0
    # A Lambertian f = 1 integrates exactly to π with cosine-weighted sampling: the estimator is π·mean(1).
    lambert = peers.PeerLobe("one", lambda *a: 1.0, lambda L, V: np.ones(L.shape[:-1], dtype=L.dtype))
    assert peers.mc_albedo(lambert, 0.3, directions).value == pytest.approx(math.pi, rel=1e-15)
    # Blinn-Phong n = 512 at normal incidence: seed 000's closed form.
    exact = peers.blinn_phong_closed_form(512.0)
    assert exact == pytest.approx(8 * math.pi * (2**-256 + 512) / (514 * 516), rel=1e-15)
    lobe = peers.blinn_phong(512.0)
    assert peers.dblquad_albedo(lobe, 0.0, 1e-10).value == pytest.approx(exact, rel=1e-9)
    assert peers.cubature_albedo(lobe, 0.0, 1e-10).value == pytest.approx(exact, rel=1e-9)


def test_mpmath_reference_matches_closed_form_limit():
    # Seed 002's ₂F₁ form at a tiny view angle tends to seed 000's normal-incidence value.
    near = peers.blinn_phong_reference(64.0, 1e-6, dps=20)
    assert near == pytest.approx(peers.blinn_phong_closed_form(64.0), rel=1e-9)


def test_extrapolation_is_stratified():
    # Two sampled angles standing for 3 and 2 table angles, constant cost 1 s: 5 s per row, 3 rows.
    per_point = np.ones((2, 2))
    total = bench._extrapolate(per_point, np.array([1.0, 100.0]), np.array([1.0, 10.0, 100.0]), np.array([0.0, 4.0]),
                               np.arange(5.0))
    assert total == pytest.approx(15.0)
