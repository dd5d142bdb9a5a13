"""Seed 002's last one-dimensional form of the Blinn-Phong albedo, in mpmath: the independent reference of the
series route's tests (tests/engine/test_series.py) and of the error-bound property tests
(tests/engine/test_error_bounds.py)."""

from __future__ import annotations

import mpmath as mp


def seed_form(n: float, theta: float, dps: int = 30) -> mp.mpf:
    """Seed 002's last one-dimensional form (S1), at ``dps`` digits, with breakpoints at the mirror peak."""
    with mp.workdps(dps):
        n, th = mp.mpf(n), mp.mpf(theta)
        co, so = mp.cos(th), mp.sin(th)

        def f(p):
            ci, si = mp.cos(p), mp.sin(p)
            z = (so * si / (co * ci + 1)) ** 2
            return ((co + ci) / mp.sqrt(co * ci + 1)) ** n * ci * si * mp.hyp2f1(n / 4, n / 4 + mp.mpf(1) / 2, 1, z)

        width = 2 * mp.sqrt(2) / mp.sqrt(n + 1)
        points = sorted(
            {mp.mpf(0), mp.pi / 2, *(min(max(th + k * width, 0), mp.pi / 2) for k in (-8, -3, -1, 0, 1, 3, 8))}
        )
        return 2 * mp.pi * 2 ** (-n / 2) * mp.quad(f, points)
