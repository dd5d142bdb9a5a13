"""`brdfnorm lut` through the parallel layer: local processes and checkpoints give the in-process table, bit for
bit (a BSDF's E_R and E_T included), and a resumed job computes nothing again."""

from __future__ import annotations

import numpy as np

import brdfnorm as bn
from brdfnorm.lut import compute

AXES = {"mu": [0.2, 0.6, 1.0], "alpha": [0.1, 0.5]}


def test_lut_on_two_processes_with_a_checkpoint_equals_the_in_process_table(tmp_path):
    model = bn.load("ggx-dielectric", eta=1.5)
    serial = compute(model, AXES, rtol=1e-8, average=False)
    spread = compute(model, AXES, rtol=1e-8, average=False, workers=2, checkpoint=str(tmp_path / "ck"))
    for name in ("E", "E_error", "E_R", "E_T", "1-E"):
        assert np.array_equal(serial[name], spread[name]), name
    assert (tmp_path / "ck" / "E").is_dir()
    again = compute(model, AXES, rtol=1e-8, average=False, workers=1, checkpoint=str(tmp_path / "ck"))
    assert np.array_equal(again["E"], serial["E"]) and again.meta["evaluations"] == serial.meta["evaluations"]
