"""The geometric-mean lookup of anisotropic GGX/Beckmann energy audited (issue #45): prints the Markdown tables of
docs/anisotropy.md — for each lobe, over (aspect a, α_g = √(α_x α_y)) and μ, the isotropic table's value at α_g
minus the lobe's albedo averaged over the view azimuth, the furnaces of the compensations built on that read
(Turquin: Ē/E_iso; Kulla & Conty: Ē + 1 − E_iso) at μ = 1, and the spread of E over φ_v at μ = 0.5.

    PYTHONPATH=src python benchmarks/anisotropy_audit.py > audit.md
"""

from __future__ import annotations

import numpy as np

from brdfnorm.lut.anisotropy_audit import geometric_mean_audit

MU = (0.1, 0.5, 1.0)
ASPECTS = (0.5, float(np.sqrt(0.1)), 0.1)
ALPHAS = (0.1, 0.3, 0.6, 1.0)


def table(distribution: str, shadowing: str) -> str:
    rows = geometric_mean_audit(distribution, shadowing, MU, ASPECTS, ALPHAS, rtol=1e-6)
    cell = {(r.aspect, r.alpha, r.mu): r for r in rows}
    lines = [f"**{distribution}, {shadowing}**", "",
             "| aspect | α_g | E_iso − Ē, μ = 0.1 | μ = 0.5 | μ = 1 | Turquin furnace, μ = 1 | Kulla–Conty furnace, "
             "μ = 1 | E over φ_v, μ = 0.5 |", "|---|---|---|---|---|---|---|---|"]
    for a in ASPECTS:
        for g in ALPHAS:
            one, half = cell[(a, g, 1.0)], cell[(a, g, 0.5)]
            errors = " | ".join(f"{cell[(a, g, m)].error:+.3f}" for m in MU)
            spread = f"{half.spread[0]:.3f}–{half.spread[1]:.3f}"
            lines.append(f"| {a:.3g} | {g:g} | {errors} | {one.turquin:.3f} | {one.kulla_conty:.3f} | {spread} |")
    return "\n".join(lines)


if __name__ == "__main__":
    for name in ("ggx", "beckmann"):
        for shadowing in ("height-correlated", "separable"):
            print(table(name, shadowing))
            print()
