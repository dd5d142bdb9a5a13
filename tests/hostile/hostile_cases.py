"""Red-team cases for the command line and the API (issue 35), as data: each case makes its hostile input in a
fresh directory and names the command that reads it; ``test_hostile_cases.py`` runs every one the same way.

A case says what it expects: ``exit`` 2 with one ``error:`` line naming ``names`` (by default the input file),
or ``exit`` 0 with ``stderr`` containing a note. Every case must end within ``seconds`` under a 4 GB address-space
limit, with at most 1 GB resident, nothing on stdout (unless ``stdout_ok``) and nothing written beside its inputs.
Add the next surface's cases here; each class of the issue has at least one case that failed before its fix.
"""

from __future__ import annotations

import io
import json
import os
import re
import socket
import struct
import subprocess
import sys
import threading
import zipfile
import zlib
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from brdfnorm.lut.formats import dumps
from brdfnorm.lut.table import Lut

PYTHON_API = """
import sys
import numpy as np
import brdfnorm as bn
from brdfnorm.errors import BrdfnormError
try:
    {body}
except BrdfnormError as error:
    print(f"error: {{error}}", file=sys.stderr)
    sys.exit(2)
"""


@dataclass(frozen=True)
class Case:
    """``make(directory)`` writes the input and returns the command's arguments after ``python -m brdfnorm``
    (or, with ``api``, the body of a Python script)."""

    name: str
    make: Callable[[Path], list[str]]
    names: str = "INPUT"  # the text the error line must contain; INPUT is the case's input path
    exit: int = 2
    seconds: float = 30.0
    slow: bool = False
    api: bool = False
    stderr: str = ""  # text stderr must contain (an exit-0 case's note)
    stdout_ok: bool = False
    cpu_seconds: float | None = None  # the child's CPU time (user + system), where the issue sets a bound
    extra: dict = field(default_factory=dict)


def small_lut() -> Lut:
    mu, alpha = np.array([0.25, 0.5, 1.0]), np.array([0.1, 0.3, 0.6, 1.0])
    values = 0.5 + 0.1 * mu[:, None] * alpha[None, :]
    meta = {"model": "ggx", "axes": ["mu", "alpha"], "tables": {"E": ["mu", "alpha"]}}
    return Lut({"E": values}, {"mu": mu, "alpha": alpha}, meta, {"E": ("mu", "alpha")})


def _fit(path: Path) -> list[str]:
    return ["fit", "--lut", str(path)]


def _npy(shape: tuple | str, dtype: str = "<f8", payload: bytes = b"") -> bytes:
    """A .npy member; ``shape`` as text is written as it is (a number too long for ``repr``)."""
    shown = shape if isinstance(shape, str) else repr(shape)
    header = (f"{{'descr': '{dtype}', 'fortran_order': False, 'shape': {shown}, }}").encode()
    header += b" " * (63 - (len(header) + 10) % 64) + b"\n"
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header + payload


def _npz(path: Path, members: dict[str, bytes]) -> Path:
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, data in members.items():
            archive.writestr(name + ".npy", data)
    return path


def _npz_of(values: np.ndarray, directory: Path) -> Path:
    """A valid npz table whose E is ``values`` (any dtype)."""
    lut = small_lut()
    buffer = io.BytesIO()
    meta = json.dumps({"model": "ggx", "axes": ["mu", "alpha"], "tables": {"E": ["mu", "alpha"]}})
    np.savez(buffer, meta=np.array(meta), E=values, mu=lut.axes["mu"], alpha=lut.axes["alpha"])
    path = directory / "t.npz"
    path.write_bytes(buffer.getvalue())
    return path


def npz_declares_1e12(directory: Path) -> list[str]:
    meta = json.dumps({"model": "ggx", "axes": ["mu"], "tables": {"E": ["mu"]}})
    members = {"meta": _npy((), f"<U{len(meta)}", meta.encode("utf-32-le")), "E": _npy((10**12,)),
               "mu": _npy((2,), payload=np.array([0.5, 1.0]).tobytes())}
    return _fit(_npz(directory / "t.npz", members))


def npz_5000_digit_shape(directory: Path) -> list[str]:
    return _fit(_npz(directory / "t.npz", {"E": _npy("(" + "9" * 5000 + ",)")}))


def npz_on_dev_zero(directory: Path) -> list[str]:
    (directory / "t.npz").symlink_to("/dev/zero")
    return _fit(directory / "t.npz")


def npz_fifo(directory: Path) -> list[str]:
    os.mkfifo(directory / "t.npz")
    return _fit(directory / "t.npz")


def npz_nan(directory: Path) -> list[str]:
    values = small_lut()["E"].copy()
    values[1, 2] = np.nan
    return _fit(_npz_of(values, directory))


def npz_complex(directory: Path) -> list[str]:
    return _fit(_npz_of(small_lut()["E"] + 0.5j, directory))


def json_nested(directory: Path) -> list[str]:
    path = directory / "t.json"
    path.write_text('{"format": "brdfnorm-lut", "tables": {"E": ' + "[" * 100_000 + "]" * 100_000 + "}}")
    return _fit(path)


def json_nan(directory: Path) -> list[str]:
    text = dumps(small_lut(), "json").replace("0.5", "NaN", 1)
    path = directory / "t.json"
    path.write_text(text)
    return _fit(path)


def csv_header_only(directory: Path) -> list[str]:
    lines = dumps(small_lut(), "csv").splitlines()
    path = directory / "t.csv"
    path.write_text("\n".join(lines[:2]) + "\n")
    return _fit(path)


def csv_junk_cell(directory: Path) -> list[str]:
    lines = dumps(small_lut(), "csv").splitlines()
    lines[4] = lines[4].rsplit(",", 1)[0] + ",1+2j"
    path = directory / "t.csv"
    path.write_text("\n".join(lines) + "\n")
    return _fit(path)


def csv_100mb(directory: Path) -> list[str]:
    lines = dumps(small_lut(), "csv").splitlines()[:2]
    row = "0.123456789012345,0.123456789012345,0.123456789012345\n"
    path = directory / "t.csv"
    with open(path, "w") as handle:
        handle.write("\n".join(lines) + "\n")
        block = row * 10_000
        for _ in range(100 * 1024**2 // len(block)):
            handle.write(block)
        handle.write("1,2\n")  # a short last row: the file is refused after it is streamed
    return _fit(path)


def header_5000_digit_size(directory: Path) -> list[str]:
    # whatever the layout's [y][x] sizes are (engine layout: [4][3]), the declaration's sizes become one 5000-digit size
    text, found = re.subn(r"lut_E(?:\[[0-9]+\])+", "lut_E[" + "9" * 5000 + "]", dumps(small_lut(), "h"), count=1)
    assert found == 1, "no lut_E declaration to damage"
    path = directory / "t.h"
    path.write_text(text)
    return _fit(path)


def header_unterminated(directory: Path) -> list[str]:
    head = dumps(small_lut(), "h").split("static const float", 1)[0]
    path = directory / "t.h"
    path.write_text(head + "const float a[1]=" * 30_000)
    return _fit(path)


def glsl_nan_token(directory: Path) -> list[str]:
    text = dumps(small_lut(), "glsl")
    start = text.index("float[12](") + len("float[12](")
    path = directory / "t.glsl"
    path.write_text(text[:start] + "nan " + text[start:])  # 'nan 0.5', read as 0.5 before
    return _fit(path)


def glsl_junk_token(directory: Path) -> list[str]:
    text = dumps(small_lut(), "glsl")
    start = text.index("float[12](") + len("float[12](")
    path = directory / "t.glsl"
    path.write_text(text[:start] + "junk" + text[start:])  # 'junk0.5': the old reader took the 0.5 silently
    return _fit(path)


def png_ihdr_short(directory: Path) -> list[str]:
    data = dumps(small_lut(), "png")
    body = b"\x00\x00\x00\x04\x00\x00\x00\x03\x10\x00\x00\x00"  # 12 bytes, not 13
    chunk = struct.pack(">I", len(body)) + b"IHDR" + body + struct.pack(">I", zlib.crc32(b"IHDR" + body))
    path = directory / "t.png"
    path.write_bytes(data[:8] + chunk + data[8 + 25:])
    return _fit(path)


def png_width_zero(directory: Path) -> list[str]:
    data = dumps(small_lut(), "png")
    body = struct.pack(">IIBBBBB", 0, 2**30, 16, 0, 0, 0, 0)
    ihdr = struct.pack(">I", 13) + b"IHDR" + body + struct.pack(">I", zlib.crc32(b"IHDR" + body))
    packer, zero, chunks = zlib.compressobj(1), bytes(2**24), []
    for _ in range(2**30 // 2**24):  # 1 GiB of filter bytes, inflated by the old reader before its size check
        chunks.append(packer.compress(zero))
    chunks.append(packer.flush())
    idat = b"".join(chunks)
    text_at = data.index(b"tEXt") - 4
    idat_at = data.index(b"IDAT") - 4
    path = directory / "t.png"
    path.write_bytes(data[:8] + ihdr + data[text_at:idat_at] + struct.pack(">I", len(idat)) + b"IDAT" + idat
                     + struct.pack(">I", zlib.crc32(b"IDAT" + idat)) + data[-12:])
    return _fit(path)


def exr_truncated(directory: Path) -> list[str]:
    data = dumps(small_lut(), "exr")
    path = directory / "t.exr"
    path.write_bytes(data[: len(data) - 40])
    return _fit(path)


def brdf_junk(unit: str) -> Callable[[Path], list[str]]:
    """A .brdf of 1 MiB: the BRDF's header, then ``unit`` repeated."""
    def make(directory: Path) -> list[str]:
        head = "analytic\n::begin shader\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) {\n"
        path = directory / "junk.brdf"
        path.write_text(head + unit * ((1024**2 - 200) // len(unit)) + "}\n::end shader\n")
        return ["albedo", str(path)]
    return make


def _silent_server(reply: bytes | None) -> int:
    """A server on 127.0.0.1 (a daemon thread of the test process) that accepts connections and then stays silent
    or sends ``reply``; its port."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(16)
    held = []

    def serve() -> None:
        while True:
            connection, _ = server.accept()
            held.append(connection)
            if reply is not None:
                connection.sendall(reply)

    threading.Thread(target=serve, daemon=True).start()
    return server.getsockname()[1]


def scheduler_silent(directory: Path) -> list[str]:
    return ["albedo", "ggx", "--theta", "0:60:7", "--scheduler", f"tcp://127.0.0.1:{_silent_server(None)}",
            "--connect-timeout", "3"]


def scheduler_http(directory: Path) -> list[str]:
    port = _silent_server(b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n")
    return ["albedo", "ggx", "--theta", "0:60:7", "--scheduler", f"tcp://127.0.0.1:{port}"]


def scheduler_empty(directory: Path) -> list[str]:
    return ["albedo", "ggx", "--theta", "0:60:7", "--scheduler", ""]


CHECKPOINTED = ["albedo", "ggx", "-p", "alpha=0.5", "--theta", "0:80:8", "--chunk-cells", "4", "--workers", "1"]


def checkpoint_tampered(directory: Path) -> list[str]:
    """A complete checkpoint whose first chunk says a NaN value converged (its digest still the job's)."""
    args = [*CHECKPOINTED, "--checkpoint", str(directory / "c")]
    subprocess.run([sys.executable, "-m", "brdfnorm", *args], check=True, capture_output=True)
    chunk = directory / "c" / "chunk-000000.npz"
    with np.load(chunk, allow_pickle=False) as data:
        arrays = {name: data[name] for name in data.files}
    arrays["value"] = arrays["value"].copy()
    arrays["value"][1, 0] = np.nan
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    chunk.write_bytes(buffer.getvalue())
    return args


def checkpoint_foreign(directory: Path) -> list[str]:
    (directory / "c").mkdir()
    (directory / "c" / "notes.txt").write_text("mine")
    return [*CHECKPOINTED, "--checkpoint", str(directory / "c")]


def lut_two_axes_1e6(directory: Path) -> list[str]:
    return ["lut", "ggx", "--axis", "mu=0.01:1:1000000", "--axis", "alpha=0.01:1:1000000", "-o",
            str(directory / "out.npz")]


def budget_half_eval(directory: Path) -> list[str]:
    return ["check", "lambert", "--budget", "0.5evals"]


def api_albedo_1e6(directory: Path) -> list[str]:
    return ["bn.albedo(bn.load('lambert'), np.linspace(0, 1.5, 10**6))"]


CASES = [
    Case("npz-declares-1e12-elements", npz_declares_1e12),
    Case("npz-5000-digit-shape", npz_5000_digit_shape),
    Case("npz-symlink-to-dev-zero", npz_on_dev_zero),
    Case("npz-fifo", npz_fifo, seconds=10),
    Case("npz-nan-cell", npz_nan, extra={"contains": "cell [1, 2]"}),
    Case("npz-complex-table", npz_complex, extra={"contains": "complex"}),
    Case("json-nested-1e5-deep", json_nested),
    Case("json-nan-cell", json_nan, extra={"contains": "NaN"}),
    Case("csv-header-only", csv_header_only),
    Case("csv-complex-cell", csv_junk_cell, extra={"contains": "1+2j"}),
    Case("csv-100-mb", csv_100mb, slow=True),
    Case("h-5000-digit-size", header_5000_digit_size),
    Case("h-30000-unterminated-declarations", header_unterminated),
    Case("glsl-nan-token", glsl_nan_token, extra={"contains": "'nan'"}),
    Case("glsl-junk-glued-to-a-number", glsl_junk_token, extra={"contains": "'junk0"}),
    Case("png-ihdr-12-bytes", png_ihdr_short),
    Case("png-width-0-height-2^30", png_width_zero, slow=True),
    Case("exr-truncated", exr_truncated),
    Case("brdf-1-mib-mismatched-brackets", brdf_junk("{ ; ( ] }\n"), cpu_seconds=5, slow=True),
    Case("brdf-1-mib-balanced-junk", brdf_junk("{ ; ( ) }\n"), cpu_seconds=5, slow=True),  # was SIGSEGV
    Case("brdf-1-mib-identifiers", brdf_junk("a b c "), cpu_seconds=5, slow=True),  # was 11 s
    Case("brdf-1-mib-operators", brdf_junk("+ - * / "), cpu_seconds=5, slow=True),
    Case("checkpoint-nan-marked-converged", checkpoint_tampered, exit=0, stdout_ok=True,
         stderr="chunk-000000.npz: a converged cell with a non-finite value (cell 1 of the chunk); computing that "
                "chunk again"),
    Case("checkpoint-holding-foreign-files", checkpoint_foreign, names="--checkpoint"),
    Case("scheduler-accepts-never-answers", scheduler_silent, names="--scheduler", seconds=15),
    Case("scheduler-answers-http", scheduler_http, names="--scheduler", seconds=15),
    Case("scheduler-empty-address", scheduler_empty, names="--scheduler", seconds=15),
    Case("lut-two-axes-1e6-each", lut_two_axes_1e6, names="--axis"),
    Case("check-budget-half-eval", budget_half_eval, names="--budget", extra={"contains": "0.5evals"}),
    Case("api-albedo-1e6-angles", api_albedo_1e6, names="theta", api=True),
]
