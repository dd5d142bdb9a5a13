"""engine/machinery/directions: the angle between directions written out component by component gives the bits of
atan2(|np.cross(a, b)|, a·b) with numpy's own cross product and norm, which it replaced (the lobe search's widths,
and so every pole and panel after them, are bit-identical); and the rounding probe's directions, taken for a subset
of its angles (the survey), are the whole probe's at those angles."""

from __future__ import annotations

import numpy as np
import pytest

from brdfnorm.engine.machinery import directions, rounding
from brdfnorm.engine.routes.hemisphere import lobe_frame


def _reference(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.einsum("...i,...i->...", *np.broadcast_arrays(a, b)))


@pytest.mark.parametrize("shapes", [((40, 257, 3), (40, 1, 3)), ((500, 3), (500, 3)), ((3,), (3,)),
                                    ((7, 1, 3), (1, 9, 3)), ((50, 3), (3,))])
def test_angle_between_is_numpys_cross_and_norm(shapes):
    rng = np.random.default_rng(17)
    for scale in (1.0, 1e-9, 1e9):
        a, b = rng.normal(size=shapes[0]) * scale, rng.normal(size=shapes[1])
        a.flat[:3] = b.flat[:3]  # some parallel and nearly parallel pairs: angles far below √ε
        got = directions.angle_between(a, b)
        assert got.shape == _reference(a, b).shape and np.array_equal(got, _reference(a, b))
        assert np.array_equal(np.stack(directions.cross(a, b), axis=-1), np.cross(a, b))
        assert np.array_equal(directions.norm(a), np.linalg.norm(a, axis=-1))


def test_angle_between_subsets_are_the_whole():
    """An angle depends on its own pair alone: a gathered subset has the whole array's bits (the lobe search takes
    angles only where they are read)."""
    rng = np.random.default_rng(19)
    a = rng.normal(size=(30, 300, 3))
    b = rng.normal(size=(30, 3))
    whole = directions.angle_between(a, b[:, None, :])
    row, sample = np.nonzero(rng.random((30, 300)) < 0.3)
    assert np.array_equal(directions.angle_between(a[row, sample], b[row]), whole[row, sample])


def test_the_survey_directions_are_the_probes():
    rng = np.random.default_rng(23)
    poles = rng.normal(size=(9, 3))
    poles[:, 2] = np.abs(poles[:, 2])
    poles /= np.linalg.norm(poles, axis=-1, keepdims=True)
    frame = lobe_frame(poles)
    widths, supports = 10.0 ** rng.uniform(-6, 0, 9), np.full(9, np.pi)
    probe = rounding._probe_rays(frame, widths, supports)
    alpha, radial = rounding._probe_angles(frame, widths, supports)
    part = alpha[:, :, [0, 1]][:, :, :, [1]][:, :, :, :, :12]
    assert np.array_equal(rounding._rays(frame[0], part, radial), probe[:, :, [0, 1]][:, :, :, [1]][:, :, :, :, :12])
