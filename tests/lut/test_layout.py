"""Table files as engines load them (issue 31 item 4): x = N·V along the image's columns, y = roughness along its
rows, R/G/B/A channels with the mapping in the metadata, E_avg as its own image, only the tables asked for, θ in
the degrees it was given in, the precision the file holds — and lut.load indexing every array in the --axis
order again."""

from __future__ import annotations

import json
import struct
import zlib

import numpy as np
import pytest

from brdfnorm import lut
from brdfnorm.errors import ArgumentError
from brdfnorm.lut import formats
from brdfnorm.lut.fitting import table_samples


def _exr_parts(path):
    OpenEXR = pytest.importorskip("OpenEXR")  # noqa: N806
    with OpenEXR.File(str(path), separate_channels=True) as image:
        return [(part.name(), part.header.get("brdfnorm"), {c: np.array(v.pixels) for c, v in part.channels.items()})
                for part in image.parts]


def test_exr_columns_are_mu_rows_are_the_next_axis_channels_rgba(bp_table, tmp_path):
    path = lut.save(bp_table, tmp_path / "t.exr")
    (name, header, grid), (avg_name, _, average) = _exr_parts(path)
    meta = json.loads(header)
    assert meta["layout"]["x"] == "mu" and meta["layout"]["y"] == "n" and meta["layout"]["v"] == "down"
    assert meta["exr"]["parts"][0]["channels"] == {"R": "E", "G": "DFG_f0", "B": "DFG_f90"}
    assert meta["exr"]["parts"][1] == {"name": "E_avg", "axes": ["n"], "channels": {"R": "E_avg"}}
    assert sorted(grid) == ["B", "G", "R"] and grid["R"].shape == (3, 4)  # 3 rows (n), 4 columns (μ)
    assert np.array_equal(grid["R"], bp_table["E"].T.astype(np.float32))  # pixel (row j, column i) = E(μ_i, n_j)
    assert np.array_equal(grid["B"], bp_table["DFG_f90"].T.astype(np.float32))
    assert avg_name == "E_avg" and average["R"].shape == (1, 3)  # one row, not broadcast over μ
    assert np.array_equal(average["R"][0], bp_table["E_avg"].astype(np.float32))
    back = lut.load(path)
    assert list(back.axes) == ["mu", "n"] and back["E"].shape == (4, 3) and back["E_avg"].shape == (3,)
    assert np.array_equal(back["E"], bp_table["E"].astype(np.float32)) and back["E"].dtype == np.float32


def test_exr_v_up_channel_names_and_broadcast(bp_table, tmp_path):
    path = lut.save(bp_table, tmp_path / "t.exr", tables=["E", "E_avg"], layout="v=up", channel_names="brdfnorm",
                    broadcast_average=True)
    ((_, header, grid),) = _exr_parts(path)
    assert sorted(grid) == ["E", "E_avg"] and json.loads(header)["layout"]["v"] == "up"
    assert np.array_equal(grid["E"], bp_table["E"].T[::-1].astype(np.float32))  # the last row holds n[0]
    assert np.array_equal(grid["E_avg"][:, 2], bp_table["E_avg"][::-1].astype(np.float32))  # repeated along μ
    back = lut.load(path)
    assert np.array_equal(back["E"], bp_table["E"].astype(np.float32))
    assert np.array_equal(back["E_avg"], bp_table["E_avg"].astype(np.float32))
    assert list(back.axes["n"]) == list(bp_table.axes["n"])
    axes_order = _exr_parts(lut.save(bp_table, tmp_path / "a.exr", tables=["E"], layout="axes"))[0][2]["R"]
    assert axes_order.shape == (4, 3)  # --layout axes: the --axis order, μ down the rows


def test_png_columns_are_mu(bp_table, tmp_path):
    data = formats.dumps(bp_table, "png", tables=["E"])
    width, height = struct.unpack(">II", data[16:24])
    assert (width, height) == (4, 3)
    meta = _png_meta(data)
    assert meta["layout"]["x"] == "mu" and meta["png"]["channels"]["R"]["table"] == "E"
    back = lut.load(lut.save(bp_table, tmp_path / "t.png", tables=["E"]))
    assert back["E"].shape == (4, 3)


def _png_meta(data: bytes) -> dict:
    position = 8
    while position < len(data):
        (length,) = struct.unpack(">I", data[position:position + 4])
        kind, body = data[position + 4:position + 8], data[position + 8:position + 8 + length]
        if kind == b"tEXt":
            assert zlib.crc32(kind + body) == struct.unpack(">I", data[position + 8 + length:position + 12 + length])[0]
            return json.loads(body.split(b"\x00", 1)[1])
        position += 12 + length
    raise AssertionError("no tEXt")


def test_three_axes_laid_out_and_restored(tmp_path):
    rng = np.random.default_rng(3)
    axes = {"f0": [0.02, 0.05], "mu": [0.2, 0.6, 1.0], "alpha": [0.1, 0.5, 0.9, 1.0]}
    tables = {"E": rng.random((2, 3, 4)), "E_avg": rng.random((2, 4))}
    cube = lut.Lut(tables, axes, {}, {"E": ["f0", "mu", "alpha"], "E_avg": ["f0", "alpha"]})
    code = formats.dumps(cube, "h")
    assert "lut_E[2][4][3]" in code and "lut_E_avg[2][4]" in code  # [f0][alpha = y][mu = x]
    for fmt in ("h", "npz", "csv"):
        back = lut.load(lut.save(cube, tmp_path / f"c.{fmt}", layout="x=mu,y=alpha,v=up"))
        assert list(back.axes) == list(axes) and back.table_axes == cube.table_axes
        for name in tables:
            expected = tables[name].astype(np.float32) if fmt == "h" else tables[name]
            assert np.array_equal(back[name], expected), (fmt, name)


def test_data_formats_keep_the_axis_order(bp_table):
    document = json.loads(formats.dumps(bp_table, "json"))
    assert np.array(document["tables"]["E"]).shape == (4, 3) and "layout" not in document["meta"]
    assert set(document["tables"]) == set(bp_table)  # every table, errors included


def test_layout_refusals(bp_table):
    for spec, message in [("x=alpha", "no axis"), ("x=mu,y=mu", "both"), ("v=sideways", "down"),
                          ("rows=mu", "expected")]:
        with pytest.raises(ArgumentError, match=message):
            formats.dumps(bp_table, "h", layout=spec)
    with pytest.raises(ArgumentError, match="identifier"):
        formats.dumps(bp_table, "h", prefix="9bad")
    with pytest.raises(ArgumentError, match="at most 4"):
        formats.dumps(bp_table, "png", tables=["E", "E_error", "1-E", "DFG_f0", "DFG_f90"])


def test_cli_header_prefix_tables_and_theta_degrees(tmp_path, run_cli):
    code, stdout, stderr = run_cli("lut", "lambert", "--axis", "theta=0,30,60", "-o", "-", "--format", "h",
                                   "--prefix", "my_", "--tables", "E,E_avg")
    assert code == 0, stderr
    assert "static const float my_E[3] = {" in stdout and "static const float my_E_avg[1]" in stdout
    assert "lut_" not in stdout and "_error" not in stdout and "one_minus" not in stdout
    assert "theta: 3 values from 0 to 60" in stdout
    out = tmp_path / "E.h"
    code, _, stderr = run_cli("lut", "lambert", "--axis", "theta=0,30,60", "--clamp", "theta=10", "-o",
                              str(out))
    assert code == 0, stderr
    back = lut.load(out)
    assert list(back.axes["theta"]) == [0.0, 30.0, 60.0] and back.meta["units"]["theta"] == "degrees"
    assert back.meta["clamp"] == {"theta": 10.0} and back["E"].dtype == np.float32
    assert set(back) == {"E", "E_avg"}  # the values an engine samples: no error tables unless asked
    code, _, stderr = run_cli("lut", "lambert", "--axis", "theta=0,30", "-o", str(out), "--layout", "y=mu")
    assert code == 2 and stderr.count("\n") == 1 and "--layout" in stderr


def test_fit_reads_a_theta_axis_in_degrees():
    table = lut.Lut({"E": np.ones((2, 2))}, {"theta": [0.0, 60.0], "n": [1.0, 2.0]},
                    {"units": {"theta": "degrees"}})
    x, _, _, names = table_samples(table)
    assert np.allclose(x, [1.0, 1.0, 0.5, 0.5]) and names == ("mu", "n")
