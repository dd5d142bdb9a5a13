"""brdfnorm audit (issue 42): a table of E with the exact conductor Fresnel factor at η + ik (``E_conductor``,
pinned with ``--as eta=… --as k=…``), its geometry searched.

Independent route: the worst cell is recomputed by composite Gauss-Legendre over the half vector (helpers/references.py)
of the Fresnel-free lobe times the conductor reflectance written out here from Snell's law in complex arithmetic,
which shares no code with brdfnorm's Fresnel or integrators; the table is made by ``lut.compute``."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.references import half_vector_gauss_legendre

import brdfnorm as bn
from brdfnorm import lut
from brdfnorm.audit import audit
from brdfnorm.errors import ArgumentError

GGX = bn.load("ggx")
T = (np.arange(8) + 0.5) / 8
ETA, K = 0.2, 3.9  # gold-like at 600 nm
_TABLE = None


def _table() -> np.ndarray:
    global _TABLE
    if _TABLE is None:
        model = GGX.with_params(fresnel="conductor", eta=ETA, k=K)
        _TABLE = lut.compute(model, {"mu": T, "alpha": T * T}, rtol=1e-10, average=False)["E"]
    return _TABLE


def _reflectance(cos: np.ndarray, n: complex) -> np.ndarray:
    """Unpolarized reflectance of an interface to a medium of complex index n: (|r_s|² + |r_p|²)/2, Snell's law
    in complex arithmetic."""
    cos = np.asarray(cos, dtype=complex)
    cos_t = np.sqrt(1.0 - (1.0 - cos * cos) / (n * n))
    rs = (cos - n * cos_t) / (cos + n * cos_t)
    rp = (n * cos - cos_t) / (n * cos + cos_t)
    return 0.5 * (np.abs(rs) ** 2 + np.abs(rp) ** 2)


class _Conductor:
    def __init__(self, alpha: float) -> None:
        self.lobe = GGX.with_params(alpha=alpha)

    def eval(self, L: np.ndarray, V: np.ndarray) -> np.ndarray:
        H = (L + V) / np.linalg.norm(L + V, axis=-1, keepdims=True)
        return self.lobe.eval(L, V) * _reflectance(np.sum(H * V, axis=-1), complex(ETA, K))[:, None]


@pytest.mark.slow
def test_conductor_table_is_named_and_checked_by_quadrature():
    r = audit(_table(), "ggx", dense=False, sweep=False, eta=str(ETA), k=str(K))
    c, fit = r.best.convention, r.best.channels[0]
    assert r.passes and c.meanings == ("E_conductor",) and (c.eta, c.k) == (ETA, K)
    assert (c.direction, c.roughness, c.shadowing) == ("mu-texel", "r2-texel", "height-correlated")
    assert fit.max < 1e-7
    mu, alpha = fit.worst_at["mu"], fit.worst_at["r"] ** 2
    V = np.array([np.sqrt(1.0 - mu * mu), 0.0, mu])
    exact = float(half_vector_gauss_legendre(_Conductor(alpha), V, 48, 128))
    assert abs(_table()[fit.worst] - exact) < 1e-7
    wrong = audit(_table(), "ggx", dense=False, sweep=False, eta=str(ETA), k="3.5")
    assert not wrong.fits and wrong.best.convention.k == 3.5


def test_conductor_pins_are_checked(tmp_path, run_cli):
    with pytest.raises(ArgumentError, match="eta"):
        audit(_table(), "ggx", dense=False, sweep=False, k="3.9")
    with pytest.raises(ArgumentError, match="E_conductor"):
        audit(_table(), "ggx", dense=False, sweep=False, channels="E_conductor")
    np.save(tmp_path / "c.npy", _table())
    np.savez(tmp_path / "c.npz", E=_table())
    code, out, err = run_cli("audit", str(tmp_path / "c.npz"), "--as", "eta=0.2", "--as", "k=-1")
    assert code == 2 and err.startswith("error:") and err.count("\n") == 1
