"""The model interface every lobe implements, built-in (numpy) or read from a ``.brdf`` file (GLSL).

Following pbrt-v4's BxDFs, a model is one small class that evaluates one lobe and knows a few facts about
it. Directions live in the local frame N = +z, X = +x, Y = +y; ``L`` is the light (incoming) direction
ω_i and ``V`` the view (outgoing) direction ω_o, both pointing away from the surface, as arrays of shape
``(..., 3)``. Parameter values may be arrays broadcasting against the direction batch ``(...)`` — that is
how a sweep over a parameter is integrated in one vectorized pass.
"""

from __future__ import annotations

import difflib
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from ..errors import ArgumentError, ParameterError
from ..parameters import Parameter, resolve
from ..validate import directions, short_repr

Over = Literal["light", "view"]


@dataclass(frozen=True)
class Lobe:
    """Where the integrand f(L, V)(N·ω) peaks as a function of the integration direction ω.

    A hint for the integrator (:mod:`brdfnorm.engine.routes.hemisphere`), never a correctness requirement:
    ``direction`` (..., 3) unit vector of the peak, ``width`` (...) its angular scale in radians,
    ``support`` (...) the angle around ``direction`` beyond which the integrand is exactly zero (π if none).
    """

    direction: np.ndarray
    width: np.ndarray
    support: np.ndarray


@dataclass(frozen=True)
class NativeKernel:
    """A model's BRDF as one compiled scalar function, for the compiled engine to call inside its own loops.

    ``function`` is a Numba ``njit`` dispatcher ``f(lx, ly, lz, vx, vy, vz, u) -> tuple of channels float64``
    (L and V as components in the local frame N = +z, X = +x, Y = +y; ``u`` a 1-D float64 array of the
    parameter values packed by ``pack``). It returns f(L, V) itself, not f·(N·L), and must give the same
    values as :meth:`Model.evaluate` to rounding. ``pack(params)`` turns one case's parameter values (scalars,
    colours as 3-vectors) into ``u``; ``key`` identifies the compiled code (for caches).
    """

    function: Callable
    channels: int
    pack: Callable[[Mapping[str, object]], np.ndarray]
    key: str


def mirror(direction: np.ndarray) -> np.ndarray:
    """Mirror direction about N = +z: (x, y, z) -> (-x, -y, z)."""
    out = np.array(direction, dtype=float, copy=True)
    out[..., :2] *= -1.0
    return out


def normal_lobe(fixed: np.ndarray) -> Lobe:
    """The uninformed hint: a broad lobe around N with no support limit."""
    shape = np.shape(fixed)[:-1]
    direction = np.zeros(shape + (3,))
    direction[..., 2] = 1.0
    return Lobe(direction, np.ones(shape), np.full(shape, np.pi))


@dataclass(frozen=True)
class Origin:
    """What :func:`brdfnorm.load` rebuilds a model from (:meth:`Model.origin`): the name or path it was given,
    the file's text where the model was read from a file (another process or machine may not see the file, or
    see it changed), and properties fixed when it was loaded that are not declared parameters."""

    key: str
    text: str | None = field(default=None, repr=False)
    fixed: Mapping[str, object] = field(default_factory=dict)


class Model(ABC):
    """A BRDF with declared parameters, bound to parameter values.

    Subclasses define :attr:`name`, :attr:`parameters`, :meth:`evaluate`, and optionally
    :meth:`lobe`, :meth:`closed_form_albedo` and :meth:`projected`.
    """

    name: str = "model"
    #: One-line formula shown by ``brdfnorm models``.
    formula: str = ""
    #: Whether the lobe conserves energy, in words (``brdfnorm models``; "" where not stated); ``check`` measures it.
    #: A lobe that does begins the words with "conserved" (:attr:`conserves_energy` reads it).
    energy: str = ""
    #: Where :meth:`closed_form_albedo` holds, in words (``brdfnorm models``).
    closed_form_domain: str = "normal incidence"
    #: Declared parameters (name, kind, range, default).
    parameters: tuple[Parameter, ...] = ()
    #: Number of output channels (1 for a scalar lobe, 3 for RGB).
    channels: int = 1
    #: True when the albedo depends only on θ (not φ) of the fixed direction.
    isotropic: bool = True
    #: The file the model was read from, as the user gave it (None for built-in lobes); errors name it.
    source_path: str | None = None
    #: Other names a parameter answers to: alias -> (parameter, the parameter's value from the alias's, the
    #: mapping in words). ``roughness`` on the microfacet lobes sets α = roughness².
    aliases: dict = {}

    def __init__(self, **values: object) -> None:
        self._params = resolve(self.parameters, self.translate(values), where=self.name, aliases=tuple(self.aliases))
        self._check()

    @property
    def params(self) -> dict:
        """The bound parameter values (defaults overridden by what was given)."""
        return dict(self._params)

    def origin(self) -> Origin:
        """What :func:`brdfnorm.load` (or, with a text, :func:`brdfnorm.load_text`) rebuilds this model from,
        with :attr:`params` as keywords: for a built-in lobe its registry name; models read from a file say so."""
        return Origin(self.name)

    def with_params(self, **values: object) -> Model:
        """A copy bound to other parameter values."""
        clone = object.__new__(type(self))
        clone.__dict__.update(self.__dict__)
        merged = {**self._params, **self.translate(values)}
        clone._params = resolve(self.parameters, merged, where=self.name)
        clone._check()
        return clone

    def translate(self, values: Mapping[str, object]) -> dict:
        """``values`` with each alias (:attr:`aliases`) replaced by the parameter it sets."""
        out = dict(values)
        for alias, (target, mapping, text) in self.aliases.items():
            if alias in out:
                if target in values:
                    raise ParameterError(f"give {target} or {alias}, not both ({text})", where=self.name)
                value = self.parameter(target).validate(out.pop(alias))
                out[target] = mapping(np.asarray(value, dtype=float))
        return out

    def _check(self) -> None:  # noqa: B027 - a hook: most lobes have nothing to check across their parameters
        """Checks across parameters, after each binding (a ParameterError for values that do not go together)."""

    @property
    def conserves_energy(self) -> bool | None:
        """Whether E ≤ 1 at every view as declared in :attr:`energy`; None where the lobe does not say."""
        return self.energy.startswith("conserved") if self.energy else None

    def parameter(self, name: str) -> Parameter:
        """The declared parameter called ``name``."""
        for p in self.parameters:
            if p.name == name:
                return p
        names = [p.name for p in self.parameters] + list(self.aliases)
        close = difflib.get_close_matches(str(name), names, n=1, cutoff=0.6)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        # -p and table axes take an alias; a sweep or a search runs over the parameter itself
        if isinstance(name, str) and name in self.aliases:
            target, _, text = self.aliases[name]
            raise ParameterError(f"{name} is not a parameter of its own here ({text}): use {target}", where=self.name)
        raise ParameterError(f"unknown parameter {short_repr(name)}{hint}", where=self.name)

    # -- evaluation -------------------------------------------------------------------------------
    @abstractmethod
    def evaluate(self, L: np.ndarray, V: np.ndarray, params: Mapping[str, object]) -> np.ndarray:
        """f(L, V) for directions (..., 3) and parameter values broadcasting against (...): (..., C)."""

    def projected(self, L: np.ndarray, V: np.ndarray, params: Mapping[str, object]) -> np.ndarray:
        """f(L, V)·(N·L), the light-integral integrand (overridden where the product is better behaved)."""
        return self.evaluate(L, V, params) * L[..., 2:3]

    def eval(self, L: np.ndarray, V: np.ndarray) -> np.ndarray:
        """f(L, V) at the bound parameters; L and V broadcast against each other: (..., C)."""
        L, V = directions(L, "L"), directions(V, "V")
        try:
            L, V = np.broadcast_arrays(L, V)
        except ValueError:
            raise ArgumentError(f"L {L.shape} and V {V.shape} do not broadcast", where="V") from None
        return self.evaluate(L, V, self._params)

    def native_kernel(self) -> NativeKernel | None:
        """The lobe as a compiled scalar function (:class:`NativeKernel`), or None where there is none (the
        engine then evaluates :meth:`evaluate` through numpy)."""
        return None

    # -- facts for the integrator -------------------------------------------------------------------
    def lobe(self, fixed: np.ndarray, params: Mapping[str, object], over: Over) -> Lobe | None:
        """Peak of the integrand over the free direction, given the fixed one (a hint only).

        None (the default) lets the integrator find it by sampling
        (:func:`brdfnorm.engine.machinery.lobe_search.search_lobes`).
        """
        return None

    def search_space(self) -> dict[str, tuple[float, float] | None]:
        """How ``brdfnorm check`` should search float parameters at the bound values, where the declared ranges do
        not say it: name -> (low, high), a narrower range that goes with the other parameters, or None to hold the
        bound value (a setting such as a table size, not a property of the surface). Empty by default."""
        return {}

    def closed_form_albedo(self, fixed: np.ndarray, params: Mapping[str, object], over: Over) -> np.ndarray:
        """Exact albedo where a closed form applies, NaN elsewhere; (..., C)."""
        return np.full(np.shape(fixed)[:-1] + (self.channels,), np.nan)

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self._params.items())
        return f"{type(self).__name__}({args})"


def scalar_param(params: Mapping[str, object], name: str) -> np.ndarray:
    """A float parameter as an array with a trailing channel-less shape, ready to broadcast."""
    return np.asarray(params[name], dtype=float)


def at_normal(fixed: np.ndarray) -> np.ndarray:
    """Mask of fixed directions equal to N (where normal-incidence closed forms apply)."""
    fixed = np.asarray(fixed, dtype=float)
    return (fixed[..., 2] >= 1.0 - 1e-15) & (np.abs(fixed[..., 0]) + np.abs(fixed[..., 1]) <= 1e-15)
