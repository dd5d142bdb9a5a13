"""Speed of the GLSL evaluator against the hand-written numpy Blinn-Phong lobe (issue 3, item 7).

Run: ``.venv/bin/python benchmarks/bench_glsl.py [pairs] [repeats]``. The two routes run alternately on
the same random direction pairs in the upper hemisphere (so that load from other processes hits both
alike); the best time of each is reported with their ratio (the requirement is ≤ 3).
"""

from __future__ import annotations

import sys
import time

import numpy as np

from brdfnorm.glsl import compile_shader
from brdfnorm.models.blinn_phong import BlinnPhong

SHADER = """
vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)
{
    vec3 H = normalize(L + V);
    float val = pow(max(0, dot(N, H)), n);
    return vec3(val);
}
"""


def hemisphere(rng: np.random.Generator, count: int) -> np.ndarray:
    d = rng.normal(size=(count, 3))
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    d[:, 2] = np.abs(d[:, 2])
    return d


def main(count: int = 1_000_000, repeats: int = 15) -> None:
    rng = np.random.default_rng(0)
    L, V = hemisphere(rng, count), hemisphere(rng, count)
    N, X, Y = np.eye(3)[[2, 0, 1]]
    Nb, Xb, Yb = (np.broadcast_to(v, L.shape) for v in (N, X, Y))
    program = compile_shader(SHADER, uniforms={"n": "float"})
    model = BlinnPhong(n=32.0)
    reference = model.evaluate(L, V, model.params)[..., 0]
    ours = program.brdf(L, V, Nb, Xb, Yb, {"n": 32.0})
    assert np.allclose(ours, reference[:, None], rtol=1e-13, atol=0)
    routes = {
        "numpy lobe": lambda: model.evaluate(L, V, model.params),
        "GLSL, N/X/Y as (3,) vectors": lambda: program.brdf(L, V, N, X, Y, {"n": 32.0}),
        "GLSL, N/X/Y as (count, 3) arrays": lambda: program.brdf(L, V, Nb, Xb, Yb, {"n": 32.0}),
    }
    best = dict.fromkeys(routes, np.inf)
    for _ in range(repeats):
        for name, route in routes.items():
            start = time.perf_counter()
            route()
            best[name] = min(best[name], time.perf_counter() - start)
    base = best["numpy lobe"]
    print(f"{count} direction pairs, best of {repeats}:")
    for name, seconds in best.items():
        print(f"  {name:34s} {seconds * 1e3:7.1f} ms   ratio {seconds / base:.2f}")


if __name__ == "__main__":
    main(*(int(float(a)) for a in sys.argv[1:3]))
