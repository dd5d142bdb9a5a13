"""Bounded memory and work from small hostile ``.brdf`` files (issue 14, class 3).

Each case runs ``brdfnorm albedo FILE --theta 0`` in a subprocess under a 2 GiB address-space limit
(``resource.setrlimit(RLIMIT_AS)``, Linux): a bound of :mod:`brdfnorm.glsl.limits` (or the reader's file-size cap)
must refuse it with exit status 2 and a one-line ``FILE:LINE:COL`` error — no signal, no MemoryError, no
traceback — and the peak resident memory the child reports must stay under 1 GiB. Evaluating a shader
with large variables over a million directions must succeed under the same limit (lanes are chunked).
"""

from __future__ import annotations

import os
import random
import re
import subprocess
import sys
from pathlib import Path

import pytest
from helpers.brdf_files import brdf_text
from helpers.paths import SRC

pytestmark = pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="needs Linux (/proc, RLIMIT_AS)")

SIGNATURE = "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)"
ADDRESS_SPACE = 2 * 1024**3
PEAK_RSS = 1024**3

# The child limits its own address space, reports its peak RSS when it exits, and runs the CLI.
RUNNER = f"""
import atexit, resource, sys
resource.setrlimit(resource.RLIMIT_AS, ({ADDRESS_SPACE}, {ADDRESS_SPACE}))
def report():  # VmHWM: this process's own high-water mark (ru_maxrss would include the forking parent's)
    peak = next(line.split()[1] for line in open("/proc/self/status") if line.startswith("VmHWM:"))
    sys.stderr.write("\\npeak-rss-kib %s\\n" % peak)
atexit.register(report)
if sys.argv[1] == "--eval":
    exec(sys.argv[2])
else:
    from brdfnorm.cli import main
    sys.argv = ["brdfnorm", *sys.argv[1:]]
    main()
"""


def run_limited(*args: str, timeout: float = 300) -> tuple[int, str, int]:
    """(exit status, stderr, peak RSS in bytes) of the CLI (or ``--eval CODE``) under the address-space limit."""
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(SRC), env.get("PYTHONPATH")]))
    done = subprocess.run(
        [sys.executable, "-c", RUNNER, *args], capture_output=True, text=True, timeout=timeout, env=env
    )
    peak = re.search(r"peak-rss-kib (\d+)", done.stderr)
    return done.returncode, done.stderr, int(peak.group(1)) * 1024 if peak else -1


def junk(size: int, seed: int) -> str:
    """``size`` characters of C-like tokens in random order: a syntax error tree-sitter must recover from."""
    rng = random.Random(seed)
    tokens = ["(", ")", "{", "}", "[", "]", "x", "+", ";", ",", "=", "float", "if", "else", "1.0", "vec3", "*", "\n"]
    out, length = [], 0
    while length < size:
        token = rng.choice(tokens)
        out.append(token)
        length += len(token) + 1
    return " ".join(out)[:size]


def doubling_calls(levels: int) -> str:
    functions = "float f0(float x) { return x + 1.0; }\n" + "".join(
        f"float f{k}(float x) {{ return f{k - 1}(x) + f{k - 1}(x); }}\n" for k in range(1, levels + 1)
    )
    return functions + SIGNATURE + f" {{ return vec3(f{levels}(1.0)); }}"


def doubling_macro(levels: int) -> str:
    macros = "#define A0 1.0\n" + "".join(f"#define A{k} (A{k - 1} + A{k - 1})\n" for k in range(1, levels + 1))
    return macros + SIGNATURE + f" {{ return vec3(A{levels}); }}"


CASES = {
    "junk-100KB": (lambda: brdf_text(junk(100_000, 1)), "syntax error"),
    "junk-1MB": (lambda: brdf_text(junk(1_000_000, 2)), "syntax error"),
    "nested-parentheses-1MB": (
        lambda: brdf_text(SIGNATURE + " { return vec3(" + "(" * 500_000 + "1.0" + ")" * 500_000 + "); }"),
        "nested too deeply",
    ),
    "file-60MB": (lambda: "analytic\n" + "# filler comment line\n" * (60 * 1024**2 // 22), "more than the 16 MiB"),
    "shader-2MB": (lambda: brdf_text(SIGNATURE + " { return vec3(1.0); }\n" + "//" + "x" * 2 * 1024**2), "too large"),
    "mat4[1024]-local": (lambda: brdf_text(SIGNATURE + " { mat4 m[1024]; return vec3(m[7][1].x); }"), "components"),
    "doubling-call-tree": (lambda: brdf_text(doubling_calls(40)), "calls inlined"),
    "doubling-macro": (lambda: brdf_text(doubling_macro(40)), "macro expansions"),
    "loop-calling-a-large-function": (
        lambda: brdf_text(
            doubling_calls(13).replace(
                "return vec3(f13(1.0));",
                "float s = 0.0; for (int i = 0; i < 10000; i++) s += f13(1.0); return vec3(s);",
            )
        ),
        "loops ran more than",
    ),
}


@pytest.mark.slow
@pytest.mark.parametrize("case", list(CASES))
def test_hostile_file_is_refused_with_bounded_memory(tmp_path, case):
    make, message = CASES[case]
    path = tmp_path / f"{case}.brdf"
    path.write_text(make(), encoding="utf-8")
    status, stderr, peak = run_limited("albedo", str(path), "--theta", "0")
    print(f"{case}: exit {status}, peak RSS {peak / 1024**2:.0f} MiB")
    assert status == 2, f"exit {status} (negative: killed by a signal)\n{stderr[-2000:]}"
    error = [line for line in stderr.splitlines() if line.startswith("error:")]
    assert len(error) == 1 and message in error[0], stderr[-2000:]
    assert re.match(rf"error: {re.escape(str(path))}:\d+:\d+: ", error[0]) or case == "file-60MB", error[0]
    assert "Traceback" not in stderr
    assert 0 < peak < PEAK_RSS, f"peak RSS {peak} bytes"


def test_a_million_directions_through_large_variables_stay_in_bounded_memory(tmp_path):
    # 2 048 components per lane: unchunked, a million lanes would need 16 GB for one copy of the variables.
    shader = (
        SIGNATURE
        + """ {
    vec4 a[512];
    for (int i = 0; i < 4; i++) a[i * 100] = vec4(L.x * float(i), V.y, n, 1.0);
    return vec3(a[100].x + a[300].x, a[200].y, a[0].z);
}"""
    )
    path = tmp_path / "large.brdf"
    path.write_text(brdf_text(shader), encoding="utf-8")
    code = f"""
import numpy as np
from brdfnorm.brdffile import load_brdf, random_hemisphere
model = load_brdf({str(path)!r})
rng = np.random.default_rng(0)
L = random_hemisphere(rng, 1_000_000)
V = random_hemisphere(rng, 1_000_000)
f = model.eval(L, V)
expected = np.stack([L[:, 0] * 4.0, V[:, 1], np.full(len(L), 10.0)], axis=-1)
assert model.program.chunk < 10_000, model.program.chunk
np.testing.assert_array_equal(f, expected)
"""
    status, stderr, peak = run_limited("--eval", code)
    print(f"a million directions: exit {status}, peak RSS {peak / 1024**2:.0f} MiB")
    assert status == 0, stderr[-3000:]
    assert 0 < peak < PEAK_RSS, f"peak RSS {peak} bytes"
