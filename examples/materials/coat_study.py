"""The coat-layering study of docs/materials-coat.md (openpbr-bsdf PR #30): view-side, symmetric and reciprocal
albedo scaling of a GGX coat (exact dielectric Fresnel) over white bases, across coat roughness and IOR.

    PYTHONPATH=src python examples/materials/coat_study.py docs/img   # ~15 min on one core

Writes coat_study.json (every number) and materials-coat.png into the folder given, and prints the markdown tables.
"""

import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import brdfnorm as bn  # noqa: E402
from brdfnorm.materials.furnace import coat_study  # noqa: E402

ROUGHNESS = (0.1, 0.3, 0.6)
IOR = (1.3, 1.5, 2.0)
THETA = np.radians([0.0, 15.0, 30.0, 45.0, 55.0, 65.0, 72.0, 78.0, 82.0, 85.0, 87.0, 89.0])


def main(folder: Path) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    rows = []
    for base in ("lambert", "metal"):
        for r in ROUGHNESS:
            for eta in IOR:
                rows += coat_study(bn.load, (r,), (eta,), base=base, theta=THETA)
                print(f"# {base} r={r} ior={eta}: " + ", ".join(f"{row['layering']} min {row['E_min']:.6f}"
                                                                for row in rows[-3:]), file=sys.stderr, flush=True)
    (folder / "coat_study.json").write_text(json.dumps({"theta_deg": list(np.degrees(THETA)), "rows": rows},
                                                       indent=1))
    for base in ("lambert", "metal"):
        print(f"\n{base} base\n\n| coat roughness | coat IOR | E view (min) | E symmetric (min) | loss symmetric "
              "(max, at θ) | E reciprocal (min) | loss reciprocal (max, at θ) |\n|---|---|---|---|---|---|---|")
        for r in sorted({row["coat_roughness"] for row in rows}):
            for eta in sorted({row["coat_ior"] for row in rows}):
                by = {row["layering"]: row for row in rows if row["base"] == base and row["coat_roughness"] == r
                      and row["coat_ior"] == eta}
                s, q = by["symmetric"], by["reciprocal"]
                print(f"| {r:g} | {eta:g} | {by['view']['E_min']:.6f} | {s['E_min']:.6f} | "
                      f"{s['loss_vs_view']:.6f} at {s['argmax_theta_deg']:g}° | {q['E_min']:.6f} | "
                      f"{q['loss_vs_view']:.2e} at {q['argmax_theta_deg']:g}° |")
    figure, axes = plt.subplots(1, 2, figsize=(11, 4), sharey=True)
    for axis, base in zip(axes, ("lambert", "metal"), strict=True):
        for row in rows:
            if row["base"] != base or row["coat_ior"] != 1.5:
                continue
            style = {"view": "-", "symmetric": "--", "reciprocal": ":"}[row["layering"]]
            axis.plot(np.degrees(THETA), row["E"], style, label=f"{row['layering']}, r={row['coat_roughness']:g}")
        axis.set_title(f"white {base} base under a GGX coat, IOR 1.5")
        axis.set_xlabel("view angle θ_o (degrees)")
        axis.grid(alpha=0.3)
    axes[0].set_ylabel("directional albedo E(θ_o)")
    axes[1].legend(fontsize=7, ncol=2)
    figure.tight_layout()
    figure.savefig(folder / "materials-coat.png", dpi=110)


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "docs/img"))
