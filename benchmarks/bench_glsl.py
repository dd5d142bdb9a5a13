"""Speed of the GLSL evaluator against the hand-written numpy Blinn-Phong lobe (issue 3, item 7).

Run: ``.venv/bin/python benchmarks/bench_glsl.py [pairs]``. Prints the best-of-5 time of each route on
random direction pairs in the upper hemisphere and their ratio (the requirement is ≤ 3).
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


def best_of(fn, repeats: int = 5) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def main(count: int = 1_000_000) -> None:
    rng = np.random.default_rng(0)
    L, V = hemisphere(rng, count), hemisphere(rng, count)
    N, X, Y = np.eye(3)[[2, 0, 1]]
    Nb, Xb, Yb = (np.broadcast_to(v, L.shape) for v in (N, X, Y))
    program = compile_shader(SHADER, uniforms={"n": "float"})
    model = BlinnPhong(n=32.0)
    reference = model.evaluate(L, V, model.params)[..., 0]
    assert np.allclose(program.brdf(L, V, Nb, Xb, Yb, {"n": 32.0})[..., 0], reference, rtol=1e-13, atol=0)
    t_numpy = best_of(lambda: model.evaluate(L, V, model.params))
    t_glsl = best_of(lambda: program.brdf(L, V, N, X, Y, {"n": 32.0}))
    t_glsl_full = best_of(lambda: program.brdf(L, V, Nb, Xb, Yb, {"n": 32.0}))
    print(f"{count} pairs: numpy lobe {t_numpy * 1e3:.1f} ms")
    print(f"  GLSL, N/X/Y as (3,) vectors:      {t_glsl * 1e3:.1f} ms  ratio {t_glsl / t_numpy:.2f}")
    print(f"  GLSL, N/X/Y as (count, 3) arrays: {t_glsl_full * 1e3:.1f} ms  ratio {t_glsl_full / t_numpy:.2f}")


if __name__ == "__main__":
    main(int(float(sys.argv[1])) if len(sys.argv) > 1 else 1_000_000)
