"""Shared pieces of the certified route: Arb integration at a working precision, the reported enclosure, and the
analytic-checked elementary functions (see the package docstring, :mod:`brdfnorm.engine.routes.certified`)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from decimal import ROUND_CEILING, ROUND_FLOOR, Context, Decimal

import numpy as np

from ....errors import ArgumentError

#: Default number of significant decimal digits asked of an enclosure.
DEFAULT_DIGITS = 30
#: Digits the CLI and the API accept (Arb works at any precision; beyond this the cost is rarely wanted).
MAX_DIGITS = 1000
#: Integrand evaluations Arb may spend on one integral before it returns the (wider) enclosure it has.
EVAL_LIMIT = 200_000


def require_flint():
    """The python-flint module, or a MissingExtraError saying how to install it (it is an optional extra)."""
    from ....extras import require

    return require("flint", "certified", where="method certified")


#: Decimal digits printed beyond those asked for: the outward rounding of the bounds then widens the interval by
#: at most 10^−(digits+GUARD_DIGITS−1) relative, a tenth of what ``digits`` allows.
GUARD_DIGITS = 2
#: Working-precision attempts: when an enclosure is wider than asked, the precision is doubled and it is recomputed.
PRECISION_ATTEMPTS = 4


def starting_bits(digits: int) -> int:
    """The first working precision for ``digits`` significant digits (the ball's radius is asked to be a 20th of
    10^−digits; Arb's integrator loses a few bits to its error bounds)."""
    return int(math.ceil((digits + GUARD_DIGITS) * math.log2(10))) + 40


@dataclass(frozen=True)
class Enclosure:
    """A rigorous enclosure of one albedo value: Arb's ball and what is reported of it.

    ``lower``/``upper`` are decimals with ``digits`` + :data:`GUARD_DIGITS` significant digits rounded outward;
    ``reached`` says whether that reported interval itself has a relative radius ≤ 10^−digits:
    (upper − lower)/2 ≤ 10^−digits · min(|lower|, |upper|), checked exactly on the decimals (an interval that
    contains 0 never reaches it). ``value`` is the midpoint rounded to float64 and ``error`` an upper bound of
    |true albedo − value| (the radius plus that rounding, rounded up). ``lower_float``/``upper_float`` are float64
    bounds rounded outward (a float64 lower bound ≤ the true value ≤ the float64 upper bound).
    """

    ball: object  # flint.arb
    digits: int
    evaluations: int
    reached: bool
    lower: str
    upper: str
    value: float
    error: float
    lower_float: float = -math.inf
    upper_float: float = math.inf
    bits: int = 0

    @classmethod
    def of(cls, ball, digits: int, evaluations: int, bits: int = 0) -> Enclosure:
        """Report ``ball``; call at the working precision (the endpoints are exact there)."""
        arb = type(ball)
        value = float(ball.mid())
        bound = (arb(ball.rad()) + abs(ball.mid() - arb(value))).upper()
        error = float(bound)
        if arb(error) < bound:  # round the bound up, never down
            error = float(np.nextafter(error, np.inf))
        shown = digits + GUARD_DIGITS
        lower = _decimal(ball.lower(), shown, ROUND_FLOOR)
        upper = _decimal(ball.upper(), shown, ROUND_CEILING)
        return cls(ball, digits, evaluations, relative_radius_within(lower, upper, digits), lower, upper, value,
                   error, outward_float(ball.lower(), -1), outward_float(ball.upper(), +1), bits)


def relative_radius_within(lower: str, upper: str, digits: int) -> bool:
    """Whether the decimal interval [lower, upper] has (upper − lower)/2 ≤ 10^−digits · min(|lower|, |upper|)
    (exact decimal arithmetic; false for an interval that contains 0)."""
    lo, hi = Decimal(lower), Decimal(upper)
    if lo <= 0 <= hi:
        return False
    context = Context(prec=max(60, 4 * digits))
    half = context.divide(context.subtract(hi, lo), 2)
    return half <= context.multiply(Decimal(10) ** -digits, min(abs(lo), abs(hi)))


def outward_float(endpoint, direction: int) -> float:
    """An exact dyadic endpoint as a float64 rounded away from the interval: down for ``direction`` −1 (a lower
    bound), up for +1 (an upper bound); exact when the endpoint is a float64."""
    arb = type(endpoint)
    value = float(endpoint)
    if not math.isfinite(value):
        return -math.inf if direction < 0 else math.inf
    exact = arb(value)
    if direction < 0 and exact > endpoint:
        value = float(np.nextafter(value, -np.inf))
    elif direction > 0 and exact < endpoint:
        value = float(np.nextafter(value, np.inf))
    return value


def _decimal(endpoint, digits: int, rounding: str) -> str:
    """An exact dyadic endpoint (an exact arb) as a decimal string rounded in the given direction."""
    mantissa, exponent = (int(part) for part in endpoint.mid().man_exp())
    # m·2^e written exactly in decimal: m·2^e for e ≥ 0, m·5^(−e)·10^e for e < 0 (string construction is exact).
    exact = Decimal(mantissa << exponent) if exponent >= 0 else Decimal(f"{mantissa * 5 ** -exponent}E{exponent}")
    return str(Context(prec=digits, rounding=rounding).plus(exact))


class Integrator:
    """Arb integrals at a working precision (``bits``, by default :func:`starting_bits`), counting integrand
    evaluations."""

    def __init__(self, digits: int, bits: int | None = None) -> None:
        flint = require_flint()
        self.arb, self.acb = flint.arb, flint.acb
        self.digits = digits
        self.bits = starting_bits(digits) if bits is None else int(bits)
        self.evaluations = 0

    def integral(self, f: Callable, a, b, abs_tol=None):
        """∫_a^b f along the segment; ``a``, ``b`` exact (see :meth:`segment` for inexact ones)."""
        def counted(x, analytic):
            self.evaluations += 1
            return f(x, analytic)

        tol = self.arb(2) ** (-(self.bits - 20))
        options = {} if abs_tol is None else {"abs_tol": abs_tol}
        return self.acb.integral(counted, a, b, rel_tol=tol, eval_limit=EVAL_LIMIT, **options).real

    def segment(self, f: Callable, a, b, abs_tol=None):
        """∫_a^b f for endpoints that are balls (computed from the parameters): Arb integrates between their exact
        midpoints, and each end piece ∫ from the true endpoint to its midpoint — a segment inside the endpoint's
        ball — is enclosed by its length times f on that ball (f analytic-checked there, so the bound holds for
        the function Arb integrates, not for another branch)."""
        arb, acb = self.arb, self.acb
        ends = []
        for end in (a, b):
            mid = arb(end.mid())
            piece = arb(0)
            if end.rad() != 0:
                size = arb(end.rad())
                value = f(acb(end), True)
                piece = arb(0, (size * abs(value)).upper()) if value.is_finite() else arb("nan")
                self.evaluations += 1
            ends.append((mid, piece))
        (lo, lo_piece), (hi, hi_piece) = ends
        return self.integral(f, lo, hi, abs_tol) + lo_piece + hi_piece

    def integral_of_power(self, base: Callable, n, rest: Callable, a, b, slope):
        """∫_a^b base(x)^n · rest(x) dx, base ≥ 0 on [a, b]; if base(a) = 0, base(x) ≤ slope·(x − a) is required.

        Arb converges slowly into an endpoint branch point of the power, so [a, a + ε] is enclosed directly:
        |∫| ≤ slope^n ε^(n+1)/(n+1) · sup|rest|, with ε chosen to make that 2^−(bits+30) of the scale, and the
        rest, where the power is analytic, is integrated.
        """
        arb, acb = self.arb, self.acb

        def integrand(x, analytic):
            return power_ball(base(x), n, analytic, acb, arb) * rest(x, analytic)

        exponent = float(n.mid())
        if exponent.is_integer() or not base(acb(a)).is_zero():  # no branch point at a: Arb alone suffices
            return self.integral(integrand, a, b)
        eps = arb(2) ** -math.ceil((self.bits + 30) / (exponent + 1))
        if eps > (b - a) / 2:
            eps = (b - a) / 2
        cover = acb(a + eps / 2 + arb(0, float((eps / 2).upper())))
        bound = slope ** n * eps ** (n + 1) / (n + 1) * arb(abs(rest(cover, False)).upper())
        return arb(0, float(bound.upper())) + self.integral(integrand, a + eps, b)


def nan_ball(acb):
    return acb("nan")


def atan_ball(z, analytic: bool, acb):
    """atan z, analytic off its cuts i·[1, ∞) and −i·[1, ∞): under the analytic check a ball whose imaginary part
    may reach ±1 is refused (a non-finite ball), so Arb bisects instead of integrating across a cut."""
    if analytic and not abs(z.imag).upper() < 1:
        return nan_ball(acb)
    return z.atan()


def power_ball(x, n, analytic: bool, acb, arb):
    """x^n (n ≥ 0 real) on a ball around a piece of the path, where x ≥ 0.

    Off the cut (−∞, 0] of the power this is Arb's power. A ball that reaches the cut is non-analytic there: under
    the analytic check that is said with a non-finite ball (Arb then bisects), and for a plain enclosure on the
    path the disk |x^n| ≤ max|x|^n is returned, which holds for every x ≥ 0 of the ball.
    """
    if x.real.lower() > 0:
        return x.pow(n, analytic=analytic)
    if analytic:
        return nan_ball(acb)
    bound = arb(x.abs_upper()) ** n
    return acb(arb(0, bound), arb(0, bound))


# -- reductions ------------------------------------------------------------------------------------------------

def validate_digits(digits: object) -> int:
    """The number of significant digits asked of an enclosure (an integer in [1, MAX_DIGITS])."""
    if isinstance(digits, bool) or not isinstance(digits, (int, np.integer)):
        raise ArgumentError(f"digits must be an integer, got {digits!r}", where="digits")
    if not 1 <= digits <= MAX_DIGITS:
        raise ArgumentError(f"digits must lie in [1, {MAX_DIGITS}], got {digits}", where="digits")
    return int(digits)

