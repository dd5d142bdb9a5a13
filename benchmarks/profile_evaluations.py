"""Where the evaluations of a generic albedo go (issue 39, item 5: "evaluations per generic albedo (Blinn-Phong)
≤ 5 000", and its "Done when": each miss measured and explained with the profile).

Per view, the lobe-aligned global rule's path (:class:`brdfnorm.engine.machinery.tensor_rule.LobeAlignedGrid`, run
by :mod:`brdfnorm.engine.machinery.global_driver`): at every level the grid M × (N − 1), the plain deviations along
β and u (d₁ + min(d₂, 9 d₁)), the estimates the driver used (after :mod:`brdfnorm.engine.machinery.grid_estimate`'s
extrapolation), each over its share of the tolerance, the direction(s) doubled next ("β½": β doubled and u
measured on the azimuths already there, the half-azimuth check of ``global_driver._refine_half``), and — where a
reference is given — the grid's true error. The grid is nested and refined as a whole (no local refinement along β
or u), so a view's evaluations are its final grid, the nodes of its half-azimuth check (``check``) and the per-call
probes (lobe search, isotropy test, the rounding-noise survey or probe, heavy-tail test). Views that
another route or grid settles (the half-vector rectangle, tried first for broad lobes, or the adaptive panels after
the global rule) are not profiled: their ``levels`` are empty, or end where the lobe-aligned rule gave them up.

``oracle=True`` replaces each estimate by the grid's true error (split over β and u in the estimates'
proportions, so the driver's choice of direction is kept): the evaluations the same rule and coordinates need to
*reach* the tolerance, against those they spend to *prove* it.

The profile observes the driver through three of its internals (the grid's ``estimate`` and the driver's
``_directions`` and ``_halves``), patched for the call only; ``tests/engine/test_profile_evaluations.py`` checks
that what it records adds up to the evaluations and estimates the call reports.

Run alone: ``.venv/bin/python benchmarks/profile_evaluations.py [--n 100] [--rtol 1e-9] [--oracle]``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from unittest import mock

import numpy as np

import brdfnorm as bn
from brdfnorm.engine.machinery import global_driver, tensor_rule

HERE = Path(__file__).resolve().parent


def profile(n: float, theta: np.ndarray, rtol: float, *, truth: np.ndarray | None = None, oracle: bool = False,
            backend: str = "numpy") -> dict:
    """The per-view profile of generic Blinn-Phong (exponent ``n``) albedos at the views ``theta`` (radians) in one
    call at ``rtol``: ``levels`` per view (dicts, in order), and the call's ``evaluations``, ``value`` and
    ``error``. ``truth`` (the albedos) adds each level's true error; ``oracle`` needs it."""
    if oracle and truth is None:
        raise ValueError("oracle needs truth")
    levels: dict[int, list[dict]] = {}
    estimate = tensor_rule.LobeAlignedGrid.estimate
    directions, halves = global_driver._directions, global_driver._halves

    def observed_estimate(grid, group, F, q, e_b, e_u, magnitude):
        plain_b, plain_u = e_b[:, 0].copy(), e_u[:, 0].copy()
        e_b, e_u, floor, noise, total = estimate(grid, group, F, q, e_b, e_u, magnitude)
        true = None if truth is None else np.abs(q[:, 0] - truth[group.case])
        if oracle:
            both = e_b + e_u
            part_b = np.where(both > 0, e_b / np.where(both > 0, both, 1.0), 0.5)
            e_b, e_u = true[:, None] * part_b, true[:, None] * (1.0 - part_b)
            total = e_b + e_u + floor + noise
        for i, case in enumerate(group.case):
            levels.setdefault(int(case), []).append({
                "M": 2**group.level_b, "N": 2**group.level_u - 1, "plain_b": float(plain_b[i]),
                "plain_u": float(plain_u[i]), "e_b": float(e_b[i, 0]), "e_u": float(e_u[i, 0]),
                "estimate": float(total[i, 0]), "true": None if true is None else float(true[i]),
                "check": 0 if group.check is None else 2**group.check_b * 2**group.level_u})
        return e_b, e_u, floor, noise, total

    def observed_directions(grid, group, short, e_b, e_u, share):
        out = directions(grid, group, short, e_b, e_u, share)
        if not isinstance(grid, tensor_rule.LobeAlignedGrid):  # (the half-vector rectangle: not profiled)
            return out
        more_b, more_u, ratio_b, ratio_u = out[:4]
        for i, case in enumerate(group.case):
            level = levels[int(case)][-1]
            level.update(ratio_b=float(ratio_b[i]), ratio_u=float(ratio_u[i]),
                         next=("β" if more_b[i] else "") + ("u" if more_u[i] else ""))
        return out

    def observed_halves(grid, group, more_b, more_u, short, needed_u):
        half = halves(grid, group, more_b, more_u, short, needed_u)
        if half is not None and isinstance(grid, tensor_rule.LobeAlignedGrid):
            for i, case in enumerate(group.case):
                if half[i]:
                    levels[int(case)][-1]["next"] = "β½"
        return half

    with mock.patch.object(tensor_rule.LobeAlignedGrid, "estimate", observed_estimate), \
            mock.patch.object(global_driver, "_directions", observed_directions), \
            mock.patch.object(global_driver, "_halves", observed_halves):
        result = bn.albedo(bn.load("blinn-phong", n=n), theta, method="quadrature", rtol=rtol, backend=backend)
    return {"levels": [levels.get(k, []) for k in range(theta.size)], "evaluations": np.asarray(result.evaluations),
            "value": np.ravel(result.value), "error": np.ravel(result.error)}


def _table(theta_deg: np.ndarray, p: dict) -> str:
    lines = ["| θ_o | evaluations | final grid | path: M × (N − 1): estimate/share β, u → doubled | true error / "
             "estimate |", "|---|---|---|---|---|"]
    for k, t in enumerate(theta_deg):
        path = p["levels"][k]
        steps = ", ".join(f"{s['M']}×{s['N']}: {s['ratio_b']:.1e}, {s['ratio_u']:.1e} → {s['next'] or '–'}"
                          for s in path[:-1])
        last = path[-1] if path else None
        final = f"{last['M']} × {last['N']}" if last else "—"
        true = "" if not last or last["true"] is None else f"{last['true'] / p['error'][k]:.1e}"
        lines.append(f"| {t:g}° | {int(p['evaluations'][k])} | {final} | {steps} | {true} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=float, default=100.0)
    parser.add_argument("--rtol", type=float, default=1e-9)
    parser.add_argument("--oracle", action="store_true", help="estimates replaced by the true errors")
    parser.add_argument("--backend", default="numpy")
    args = parser.parse_args(argv)
    sys.path.insert(0, str(HERE))
    import peers

    theta_deg = np.arange(90.0)
    theta = np.radians(theta_deg)
    truth = np.array([peers.blinn_phong_reference(args.n, t) for t in theta])
    p = profile(args.n, theta, args.rtol, truth=truth, oracle=args.oracle, backend=args.backend)
    print(_table(theta_deg, p))
    print(f"\nmean {p['evaluations'].mean():.1f}, max {p['evaluations'].max()} evaluations per albedo "
          f"(Blinn-Phong n = {args.n:g}, rtol {args.rtol:g}, {args.backend}{', oracle' if args.oracle else ''})",
          file=sys.stderr)


if __name__ == "__main__":
    main()
