"""The pointwise checks: reciprocity, positivity and finiteness of f on sampled direction pairs."""

from __future__ import annotations

import numpy as np

from ..engine.machinery.directions import random_hemisphere
from .core import CheckResult, count_text, direction_text, direction_tuple, params_text, values_text
from .space import Points, bind_case, params_at


def _pairs(count: int, seed: int) -> tuple[np.ndarray, np.ndarray, int]:
    """Direction pairs: ``count`` uniform in solid angle (the share is measured on these), as many with
    log-uniform N·ω down to 1e-7 (grazing), and a structured grid (normal, mirror, retro, horizon)."""
    rng = np.random.default_rng(seed)
    L, V = random_hemisphere(rng, count), random_hemisphere(rng, count)

    def grazing(n: int) -> np.ndarray:
        z = 10.0 ** rng.uniform(-7.0, 0.0, n)
        phi = rng.uniform(0.0, 2 * np.pi, n)
        r = np.sqrt(1.0 - z * z)
        return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)

    theta = np.radians([0.0, 30.0, 60.0, 85.0, 89.99])
    phi = np.radians([0.0, 90.0, 180.0, 270.0])
    grid = np.array([[np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)] for t in theta
                     for p in (phi if t > 0 else [0.0])])
    gL, gV = np.meshgrid(np.arange(len(grid)), np.arange(len(grid)), indexing="ij")
    L = np.vstack([L, grazing(count), rng.permutation(random_hemisphere(rng, count)), grid[gL.ravel()]])
    V = np.vstack([V, random_hemisphere(rng, count), grazing(count), grid[gV.ravel()]])
    return L, V, count


def check_pointwise(model, space, points: Points, checks, tolerance, pairs, seed, meter) -> tuple[dict, dict]:
    L, V, uniform = _pairs(pairs, seed)
    M = L.shape[0]
    worst = {"reciprocity": (-1.0, None), "positivity": (0.0, None), "finiteness": (0.0, None)}
    bad_counts = {"positivity": [0, 0], "finiteness": [0, 0]}  # [all pairs, uniform pairs]
    done = 0
    for p in range(len(points)):
        if done and meter.spent(0.15):
            break
        bound = bind_case(model, space, points, points.combo[p], np.array([p]))
        with np.errstate(all="ignore"):
            forward = bound.eval(L, V)
            backward = bound.eval(V, L) if "reciprocity" in checks else forward
        meter.evaluations += (2 if "reciprocity" in checks else 1) * M
        done += 1
        finite = np.isfinite(forward) & np.isfinite(backward)
        # The lobe's scale per channel: the largest |f| sampled at these parameters, either way round.
        scale = np.max(np.abs(np.where(finite, np.maximum(np.abs(forward), np.abs(backward)), 0.0)), axis=0)
        scale = np.where(scale > 0, scale, 1.0)
        nonfinite = ~np.all(np.isfinite(forward), axis=1)
        negative = np.any(forward < 0, axis=1)
        for name, mask in (("finiteness", nonfinite), ("positivity", negative)):
            bad_counts[name][0] += int(mask.sum())
            bad_counts[name][1] += int(mask[:uniform].sum())
        if nonfinite.any() and worst["finiteness"][1] is None:
            i = int(np.flatnonzero(nonfinite)[0])
            worst["finiteness"] = (1.0, (p, i, forward[i]))
        relative_negative = np.max(np.where(finite, -forward / scale, 0.0), axis=1)
        i = int(np.argmax(relative_negative))
        if relative_negative[i] > max(worst["positivity"][0], 0.0):
            worst["positivity"] = (float(relative_negative[i]), (p, i, forward[i]))
        asymmetry = np.max(np.where(finite, np.abs(forward - backward) / scale, 0.0), axis=1)
        i = int(np.argmax(asymmetry))
        if asymmetry[i] > worst["reciprocity"][0]:
            worst["reciprocity"] = (float(asymmetry[i]), (p, i, forward[i], backward[i]))
    sampled = {"parameter_points": done, "pairs_per_point": M, "uniform_pairs_per_point": uniform,
               "evaluations": done * M * (2 if "reciprocity" in checks else 1)}
    results = {}
    for name in ("reciprocity", "positivity", "finiteness"):
        if name not in checks:
            continue
        amount, at = worst[name]
        share_all, share_uniform = bad_counts.get(name, (0, 0))
        share = share_uniform / max(done * uniform, 1) if name != "reciprocity" else None
        if at is None:
            what = {"reciprocity": "reciprocal", "positivity": "no negative value",
                    "finiteness": "every value finite"}[name]
            results[name] = CheckResult(name, "pass", max(amount, 0.0), f"{what} on {done * M} direction pairs at "
                                        f"{count_text(done, 'parameter point')}", share=share, sampled=sampled)
            continue
        p, i = at[0], at[1]
        params = params_at(model, space, points, p)
        where = f"at {params_text(params)}, L={direction_text(L[i])} V={direction_text(V[i])}"
        if name == "reciprocity":
            status = "fail" if amount > tolerance else "pass"
            message = (f"{'not reciprocal' if status == 'fail' else 'reciprocal'}: largest |f(L,V) − f(V,L)| "
                       f"{amount:.3g} of the lobe's scale (tolerance {tolerance:g}) {where}: f(L,V)="
                       f"{values_text(at[2])}, f(V,L)={values_text(at[3])}")
        elif name == "positivity":
            status = "fail"
            message = (f"negative: f = {values_text(at[2])} ({amount:.3g} of the lobe's scale) {where}; "
                       f"{share_all} of {done * M} pairs negative, {100 * share:.3g}% of the domain")
        else:
            status = "fail"
            amount = share
            message = (f"not finite: f = {values_text(at[2])} {where}; {share_all} of {done * M} pairs, "
                       f"{100 * share:.3g}% of the domain")
        results[name] = CheckResult(name, status, float(amount), message, params=params, L=direction_tuple(L[i]),
                                    V=direction_tuple(V[i]), share=share, sampled=sampled)
    return results, sampled
