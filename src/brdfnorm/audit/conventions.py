"""The declared space of table conventions an audit searches, and the sample positions each one implies.

A convention (:class:`Convention`) says, for a table of a microfacet lobe's energy over the view direction and
the roughness (and, for three axes, Schlick's f0):

* which array axis is the view direction and which the roughness (and f0), and whether each runs reversed;
* where the direction samples sit: μ = cos θ_o at nodes i/(N−1) (``mu-node``) or texel centres (i + ½)/N
  (``mu-texel``), θ_o = t·π/2 at nodes or texel centres (``theta-node``, ``theta-texel``), or the LTC tables'
  μ = 1 − t², t = i/(N−1) (``ltc``; Heitz et al. 2016's fitting code, which also clamps θ ≤ 1.57);
* where the roughness samples sit and what they mean: α = t (``alpha-node``, ``alpha-texel``) or α = t²
  (``r2-node``, ``r2-texel``: the axis is the perceptual roughness r, α = r²);
* endpoint clamps: μ ≥ ``mu_floor`` and α ≥ ``alpha_floor`` (searched among :data:`MU_FLOORS`, :data:`ALPHA_FLOORS`
  where the grid reaches below them);
* Smith shadowing: ``height-correlated`` or ``separable`` (for rough dielectrics also the refraction's form,
  :data:`DIELECTRIC_SHADOWING`);
* per channel, its meaning (:data:`MEANINGS`), which also says the Fresnel factor: none (E, 1 − E), Schlick's
  (the split-sum channels; E_f0 over an f0 axis) or the exact dielectric one, at one index of refraction η
  (``E_dielectric``, η = :attr:`Convention.eta`, 1.5 unless pinned) or at η = (1 + √f0)/(1 − √f0) over an f0
  axis (``E_f0_dielectric``); Schlick's factor at one f0 over a 2-D table is ``E_schlick`` (f0 found, or pinned
  with ``schlick_f0=``); or the cloth channel of a three-channel DFG texture (``DFG_cloth``, the sheen lobe at
  the same α).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import ArgumentError
from ..lut.splitsum import DFG_F0, DFG_F90
from ..models.microfacet import SHADOWING  # the lobe's own choices: the audit searches what the model offers

DIRECTIONS = ("mu-node", "mu-texel", "theta-node", "theta-texel", "ltc")
ROUGHNESS = ("alpha-node", "alpha-texel", "r2-node", "r2-texel")
F0_POSITIONS = ("f0-node", "f0-texel")
#: The third axis of a rough-glass table is η (``ETA_AXES``): Cycles' precompute (``eta-cycles``: nodes z/(n − 1),
#: F0 = clamp(t, 1e-4, 0.99)⁴, η = (1 + √F0)/(1 − √F0), light entering the denser medium), the same seen from inside
#: (``eta-cycles-exiting``: 1/η), or values given with ``--axis eta=…`` (``eta-explicit``).
ETA_AXES = ("eta-cycles", "eta-cycles-exiting")
#: η layouts taken when pinned (``--as f0=eta-moonray``), not searched: MoonRay's ``TransmissionAlbedo`` accessor
#: (``netaRange``: η = 1.05 + 2t at nodes t = z/(n − 1), entering; ``-exiting``: 1/η, its ``mEExit`` table), and
#: appleseed's glass tables (``AlbedoTable3D``, ``glassbsdf.cpp``: η = lerp(1.01, 3, t), light entering,
#: ``g_glass_ggx_albedo_table``; ``eta-appleseed-exiting``: η = lerp(1/3, 1/1.01, t) — linear in η, not 1/η of the
#: entering nodes — ``g_glass_ggx_rcp_eta_albedo_table``).
PINNED_ETA_AXES = ("eta-moonray", "eta-moonray-exiting", "eta-appleseed", "eta-appleseed-exiting")
#: appleseed's η range (``MinEta``, ``MaxEta`` of glassbsdf.cpp).
APPLESEED_ETA = (1.01, 3.0)
#: For rough dielectrics (a model with ``refraction_shadowing``) the refraction's G2 is searched too: Heitz's Beta
#: form (``height-correlated``, brdfnorm's default), G1·G1 for both (``separable``: OpenPBR, Mitsuba), and
#: height-correlated reflection with the refraction's G2 as the reflection's 1/(1 + Λ_V + Λ_L) (Blender Cycles'
#: glass) or as G1·G1.
DIELECTRIC_SHADOWING = SHADOWING + ("height-correlated/refraction=reflection-form",
                                    "height-correlated/refraction=separable")
#: Channel meanings. DFG_f0 = ∫ f cos (1 − (1 − V·H)⁵) (Karis's split-sum scale), DFG_f90 = ∫ f cos (1 − V·H)⁵
#: (the bias, the Fresnel moment), E_f0 = ∫ f cos F_Schlick(f0, f90 = 1) over an f0 axis, E_avg = 2∫ E μ dμ and
#: 1-E_avg (the form Kulla–Conty's compensation divides by);
#: E_dielectric = ∫ f cos F(η, V·H) with the exact dielectric Fresnel factor (Walter et al. 2007, eq. 22) at the
#: convention's η, and E_f0_dielectric the same over an f0 axis at η = (1 + √f0)/(1 − √f0); DFG_cloth =
#: ∫ D_charlie V_neubelt cos, the cloth channel engines store beside the split-sum pair (:mod:`brdfnorm.lut.cloth`);
#: F_avg = 2∫ F μ dμ of a Fresnel factor over its own axes, no lobe (:mod:`.fresnel_average`).
MEANINGS = ("E", "1-E", DFG_F0, DFG_F90, "E_f0", "E_avg", "1-E_avg", "E_dielectric", "E_f0_dielectric",
            "DFG_cloth", "E_schlick", "E_conductor", "E_glass", "R_glass", "T_glass", "F_avg")
#: Meanings of a rough-glass table over an η axis: R + T, R and T of the lobe at each cell's η.
GLASS_MEANINGS = ("E_glass", "R_glass", "T_glass")
#: Meanings with the exact dielectric Fresnel factor (searched only where nothing else fits, or pinned).
DIELECTRIC_MEANINGS = ("E_dielectric", "E_f0_dielectric")
#: The index of refraction of an E_dielectric table unless ``eta=`` pins another (f0 = 0.04, the usual default).
ETA = 1.5
#: Schlick's f0 of an E_schlick table (∫ f cos F_Schlick(f0, f90 = 1) over (μ, α)) unless found or pinned.
SCHLICK_F0 = 0.04
#: μ clamps searched where a grid reaches μ = 0: 1e-4 (brdfnorm lut's usual), cos(1.57) (LTC's θ ≤ 1.57), ...
MU_FLOORS = (1e-4, float(np.cos(1.57)), 1e-3, 1e-2, 1e-5, 1e-6)
#: α clamps searched where a grid reaches α = 0 (1e-8 stands for the α → 0 limit).
ALPHA_FLOORS = (1e-8, 1e-5, 1e-4, 1e-3, 2e-3, 1e-2)


@dataclass(frozen=True)
class Convention:
    """One hypothesis: axis roles and flips, sample positions, clamps, shadowing, channel meanings."""

    direction_axis: int | None = 0  # None: a table without a direction axis (E_avg over roughness)
    roughness_axis: int = 1
    f0_axis: int | None = None
    direction: str = "mu-node"
    roughness: str = "alpha-node"
    f0: str = "f0-node"
    flips: tuple[bool, ...] = (False, False)
    shadowing: str = "height-correlated"
    mu_floor: float = 1e-4
    alpha_floor: float = 1e-8
    meanings: tuple[str | None, ...] = field(default=())
    eta: float = ETA  # the index of refraction of an E_dielectric channel (of an E_conductor channel: η of η + ik)
    k: float = 0.0  # the extinction coefficient of an E_conductor channel (η + ik)
    schlick_f0: float = SCHLICK_F0  # Schlick's f0 of an E_schlick channel
    free_f0: bool = True  # schlick_f0 is fitted to the table (least squares), not pinned
    #: Axis values given by the user (``--axis``), role -> values in array order: ('mu' | 'theta' | 'alpha' |
    #: 'f0', values); such an axis is ``explicit`` and never flipped.
    explicit: tuple[tuple[str, tuple[float, ...]], ...] = ()

    def geometry(self) -> tuple:
        """What the direction and roughness values depend on (for sharing reference values)."""
        return (self.direction_axis, self.roughness_axis, self.f0_axis, self.direction, self.roughness, self.f0,
                self.flips, self.shadowing)

    def describe(self) -> dict:
        axes = {}
        if self.direction_axis is not None:
            theta = self.direction.startswith("theta") or any(n == "theta" for n, _ in self.explicit)
            axes[self.direction_axis] = "theta" if theta else "mu"
        axes[self.roughness_axis] = ("roughness (alpha = r^2)" if self.roughness.startswith("r2") else "alpha")
        if self.f0_axis is not None:
            axes[self.f0_axis] = "eta" if self.f0.startswith("eta") else "f0"
        return {"axes": [axes[i] for i in sorted(axes)], "flipped": [bool(f) for f in self.flips],
                "direction": self.direction, "roughness": self.roughness,
                **({"f0": self.f0} if self.f0_axis is not None else {}),
                "mu_floor": self.mu_floor, "alpha_floor": self.alpha_floor, "shadowing": self.shadowing,
                "channels": list(self.meanings), **({"eta": self.eta} if "E_dielectric" in self.meanings else {}),
                **({"eta": self.eta, "k": self.k} if "E_conductor" in self.meanings else {}),
                **({"schlick_f0": self.schlick_f0} if "E_schlick" in self.meanings else {})}

    def text(self) -> str:
        d = self.describe()
        parts = [f"axes ({', '.join(d['axes'])})"]
        flipped = [a for a, f in zip(d["axes"], d["flipped"], strict=True) if f]
        if flipped:
            parts.append("reversed: " + ", ".join(flipped))
        parts += [self.direction if self.direction_axis is not None else "", self.roughness,
                  f"mu>={self.mu_floor:g}", f"alpha>={self.alpha_floor:g}", self.shadowing,
                  "channels " + "/".join(m or "?" for m in self.meanings)]
        if "E_dielectric" in self.meanings:
            parts.append(f"eta={self.eta:g}")
        if "E_conductor" in self.meanings:
            parts.append(f"conductor eta={self.eta:g} k={self.k:g}")
        if "E_schlick" in self.meanings:
            parts.append(f"f0={self.schlick_f0:.6g}")
        return "; ".join(p for p in parts if p)


def positions(kind: str, n: int, index: np.ndarray, flip: bool) -> np.ndarray:
    """The unit coordinate t of samples ``index`` of an ``n``-sample axis (node or texel), reversed if ``flip``."""
    index = np.asarray(index, dtype=float)
    if flip:
        index = n - 1 - index
    if kind.endswith("texel"):
        return (index + 0.5) / n
    return index / (n - 1) if n > 1 else np.zeros_like(index)


def mu_of(kind: str, t: np.ndarray) -> np.ndarray:
    """μ at unit coordinate t for a direction convention (before the floor)."""
    if kind.startswith("mu"):
        return t
    if kind.startswith("theta"):
        return np.cos(np.clip(t, 0.0, 1.0) * (np.pi / 2))
    if kind == "ltc":
        return 1.0 - t * t
    raise ArgumentError(f"unknown direction convention {kind!r} (known: {', '.join(DIRECTIONS)})", where="pins")


def alpha_of(kind: str, t: np.ndarray) -> np.ndarray:
    if kind.startswith("alpha"):
        return t
    if kind.startswith("r2"):
        return t * t
    raise ArgumentError(f"unknown roughness convention {kind!r} (known: {', '.join(ROUGHNESS)})", where="pins")


def _explicit(c: Convention, role: str) -> tuple[str, np.ndarray] | None:
    for name, values in c.explicit:
        if name == role or (role == "mu" and name == "theta"):
            return name, np.asarray(values, dtype=float)
    return None


def _kind(c: Convention, role: str) -> str:
    return {"mu": c.direction, "alpha": c.roughness, "f0": c.f0, "eta": c.f0}[role]


def unit_positions(c: Convention, role: str, n: int, index: np.ndarray, flip: bool) -> np.ndarray:
    """The unit coordinate t of samples ``index`` of the axis of ``role`` (mu, alpha, f0): where a GPU fetch
    puts them. Explicit values are placed linearly between their first and last value."""
    given = _explicit(c, role)
    if given is not None:
        values = given[1]
        span = values[-1] - values[0]
        return (values[np.asarray(index, dtype=int)] - values[0]) / (span if span else 1.0)
    kind = _kind(c, role)
    return positions("node" if kind == "ltc" else kind, n, index, flip)


def role_value(c: Convention, role: str, t: np.ndarray) -> np.ndarray:
    """μ, α or f0 at unit coordinate t (before the floors)."""
    given = _explicit(c, role)
    if given is not None:
        name, values = given
        value = values[0] + t * (values[-1] - values[0])
        return np.cos(value) if name == "theta" else value
    if role == "mu":
        return mu_of(c.direction, t)
    if role == "alpha":
        return alpha_of(c.roughness, t)
    if role == "eta" and c.f0.startswith("eta-appleseed"):
        lo, hi = APPLESEED_ETA
        if c.f0.endswith("exiting"):
            lo, hi = 1.0 / hi, 1.0 / lo
        return lo + t * (hi - lo)
    if role == "eta" and c.f0.startswith("eta-moonray"):
        eta = 1.05 + 2.0 * t
        return 1.0 / eta if c.f0.endswith("exiting") else eta
    if role == "eta":
        f0 = np.clip(t, 1e-4, 0.99) ** 4
        # an index-matched interface does not scatter: η is kept 2e-6 from 1 (R there is ~1e-13, T ~1)
        eta = np.maximum((1.0 + np.sqrt(f0)) / (1.0 - np.sqrt(f0)), 1.0 + 2e-6)
        return 1.0 / eta if c.f0.endswith("exiting") else eta
    return t


def axis_roles(c: Convention) -> dict[int, str]:
    roles = {c.roughness_axis: "alpha"}
    if c.direction_axis is not None:
        roles[c.direction_axis] = "mu"
    if c.f0_axis is not None:
        roles[c.f0_axis] = "eta" if c.f0.startswith("eta") else "f0"
    return roles


def coordinates(c: Convention, shape: tuple[int, ...], index: list[np.ndarray]) -> dict[str, np.ndarray]:
    """μ, α (and f0) at the samples ``index`` (one index vector per array axis), floors applied."""
    out = {}
    for axis, role in axis_roles(c).items():
        value = role_value(c, role, unit_positions(c, role, shape[axis], index[axis], c.flips[axis]))
        floor = {"mu": c.mu_floor, "alpha": c.alpha_floor}.get(role, -np.inf)
        out[role] = np.maximum(value, floor)
    return out


def geometries(grid_ndim: int, pinned: dict[str, str], explicit: dict[str, np.ndarray] | None = None,
               shape: tuple[int, ...] | None = None, shadowings: tuple[str, ...] = SHADOWING,
               third: tuple[str, ...] = F0_POSITIONS) -> list[Convention]:
    """Every geometry (axis roles, flips, positions, shadowing) of a grid of ``grid_ndim`` axes, with pinned
    parts fixed (``pinned``: direction=..., roughness=..., shadowing=..., axes=mu,alpha, flip=0/1 per axis)."""
    out = []
    if grid_ndim == 1:
        roles = [(None, 0, None)]
    elif grid_ndim == 2:
        roles = [(0, 1, None), (1, 0, None)]
    elif grid_ndim == 3:
        roles = [perm for perm in itertools.permutations(range(3))]
    else:
        raise ArgumentError(f"tables of 1, 2 or 3 axes are audited; this one has {grid_ndim}", where="shape")
    names = {"mu": 0, "theta": 0, "alpha": 1, "roughness": 1, "r": 1, "f0": 2, "eta": 2}
    if "axes" in pinned:
        wanted = [names.get(a.strip()) for a in pinned["axes"].split(",")]
        if None in wanted or len(wanted) != grid_ndim:
            raise ArgumentError(f"axes={pinned['axes']}: name each of the {grid_ndim} array axes mu, theta, alpha, "
                                "roughness, f0 or eta", where="pins")
        if grid_ndim == 1:
            wanted = [1]
    for role in roles:
        d, r, f = role
        if "axes" in pinned and grid_ndim > 1:
            actual = [0] * grid_ndim
            actual[d] = 0
            actual[r] = 1
            if f is not None:
                actual[f] = 2
            if actual != wanted:
                continue
        directions = [None] if d is None else _pinned(pinned, "direction", DIRECTIONS)
        if "axes" in pinned and d is not None and "direction" not in pinned:
            first = pinned["axes"].split(",")[d].strip()
            directions = [x for x in directions if x.startswith("theta") == (first == "theta")]
        roughness = _pinned(pinned, "roughness", ROUGHNESS)
        f0s = [None] if f is None else _pinned(pinned, "f0", third,
                                                 PINNED_ETA_AXES if third == ETA_AXES else ())
        flip_sets = list(itertools.product((False, True), repeat=grid_ndim))
        if "flip" in pinned:
            flip_sets = [tuple(bool(int(x)) for x in pinned["flip"].split(","))]
            if len(flip_sets[0]) != grid_ndim:
                raise ArgumentError(f"flip=: one 0/1 per array axis ({grid_ndim})", where="pins")
        given = explicit or {}
        fixed_axes = []
        if d is not None and ("mu" in given or "theta" in given):
            directions, fixed_axes = ["explicit"], fixed_axes + [d]
        if "alpha" in given:
            roughness, fixed_axes = ["explicit"], fixed_axes + [r]
        if f is not None and "f0" in given:
            f0s, fixed_axes = ["explicit"], fixed_axes + [f]
        if f is not None and "eta" in given:
            f0s, fixed_axes = ["eta-explicit"], fixed_axes + [f]
        roles = {d: ("theta" if "theta" in given else "mu"), r: "alpha", f: "eta" if "eta" in given else "f0"}
        if shape is not None and any(len(given[roles[a]]) != shape[a] for a in fixed_axes):
            continue  # the given values do not fit this axis
        chosen = tuple(sorted((roles[a], tuple(float(v) for v in given[roles[a]])) for a in fixed_axes))
        for direction, rough, f0, flips, shadowing in itertools.product(
                directions, roughness, f0s, flip_sets, _pinned(pinned, "shadowing", shadowings)):
            if any(flips[a] for a in fixed_axes):
                continue
            out.append(Convention(direction_axis=d, roughness_axis=r, f0_axis=f,
                                  direction=direction or "mu-node", roughness=rough, f0=f0 or "f0-node",
                                  flips=flips, shadowing=shadowing,
                                  mu_floor=float(pinned.get("mu_floor", 1e-4)),
                                  alpha_floor=float(pinned.get("alpha_floor", 1e-8)), explicit=chosen,
                                  eta=float(pinned.get("eta", ETA)), k=float(pinned.get("k", 0.0)),
                                  schlick_f0=float(pinned.get("schlick_f0", SCHLICK_F0)),
                                  free_f0="schlick_f0" not in pinned))
    if not out:
        raise ArgumentError("the pinned parts leave no convention to test", where="pins")
    return out


def _pinned(pinned: dict[str, str], key: str, known: tuple[str, ...], also: tuple[str, ...] = ()) -> list[str]:
    """The values of ``key`` searched (``known``), or the one pinned (among ``known`` and ``also``)."""
    if key not in pinned:
        return list(known)
    if pinned[key] not in known + also:
        raise ArgumentError(f"{key}={pinned[key]}: known values are {', '.join(known + also)}", where="pins")
    return [pinned[key]]


PIN_KEYS = ("axes", "direction", "roughness", "f0", "flip", "shadowing", "mu_floor", "alpha_floor", "channels", "eta",
            "schlick_f0", "k")


def parse_pins(items: list[str] | dict | None) -> dict[str, str]:
    """``--as KEY=VALUE`` items (or a mapping) -> the pinned parts."""
    if items is None:
        return {}
    pairs = items.items() if isinstance(items, dict) else [i.partition("=")[::2] for i in items]
    out = {}
    for key, value in pairs:
        key = str(key).strip()
        if key not in PIN_KEYS or value in ("", None):
            raise ArgumentError(f"expected KEY=VALUE with KEY one of {', '.join(PIN_KEYS)}; got {key!r}",
                                where="pins")
        out[key] = str(value).strip()
    for key in ("mu_floor", "alpha_floor"):
        if key in out:
            try:
                value = float(out[key])
            except ValueError:
                raise ArgumentError(f"{key} must be a number", where="pins") from None
            if not 0 <= value < 1:
                raise ArgumentError(f"{key} must lie in [0, 1)", where="pins")
    if "eta" in out:
        try:
            eta = float(out["eta"])
        except ValueError:
            raise ArgumentError("eta must be a number", where="pins") from None
        if "k" in out:  # a conductor's η + ik
            if not (np.isfinite(eta) and 0.0 < eta <= 1000.0):
                raise ArgumentError("eta must lie in (0, 1000] (the real part of a conductor's η + ik)", where="pins")
        elif not (np.isfinite(eta) and 1.0 < eta <= 1000.0):
            raise ArgumentError("eta must lie in (1, 1000] (an E_dielectric table of an index of refraction)",
                                where="pins")
    if "k" in out:
        try:
            k = float(out["k"])
        except ValueError:
            raise ArgumentError("k must be a number", where="pins") from None
        if not (np.isfinite(k) and 0.0 <= k <= 1000.0) or "eta" not in out:
            raise ArgumentError("k (a conductor's extinction, in [0, 1000]) goes with eta: --as eta=0.2 --as k=3.9",
                                where="pins")
    if "schlick_f0" in out:
        try:
            value = float(out["schlick_f0"])
        except ValueError:
            raise ArgumentError("schlick_f0 must be a number", where="pins") from None
        if not 0.0 <= value <= 1.0:
            raise ArgumentError("schlick_f0 must lie in [0, 1]", where="pins")
    if "channels" in out:
        for meaning in out["channels"].split(","):
            if meaning.strip() not in MEANINGS and meaning.strip() != "-":
                raise ArgumentError(f"channels: unknown meaning {meaning!r} (known: {', '.join(MEANINGS)}, - to "
                                    "skip a channel)", where="pins")
    return out


def fresnel_of(c: Convention) -> dict[str, float]:
    """The Fresnel constants a convention's meanings are evaluated with (``Reference.meaning``'s keywords)."""
    return {"eta": c.eta, "schlick_f0": c.schlick_f0, "k": c.k}


def with_floors(c: Convention, mu_floor: float, alpha_floor: float) -> Convention:
    return replace(c, mu_floor=mu_floor, alpha_floor=alpha_floor)


def stored_axis_values(c: Convention, shape: tuple[int, ...], index: list[np.ndarray]) -> dict[str, np.ndarray]:
    """Each axis's value at the samples ``index`` in the variable the table itself is indexed by, before any
    clamp: μ (or θ in degrees for the θ conventions), r for the r² roughness conventions (α = r²) or α, f0, or the
    values given outright with ``--axis``. This is what a bad cell's position is reported in."""
    if not isinstance(c, Convention):  # an F_avg table's convention (:mod:`.fresnel_average`) knows its axes
        return c.stored_values(shape, index)
    out = {}
    for axis, role in sorted(axis_roles(c).items()):  # in array-axis order
        i = np.asarray(index[axis])
        given = _explicit(c, role)
        if given is not None:
            name, values = given
            out["theta_deg" if name == "theta" else name] = (np.degrees(values[i.astype(int)]) if name == "theta"
                                                             else values[i.astype(int)])
            continue
        t = unit_positions(c, role, shape[axis], i, c.flips[axis])
        if role == "mu" and c.direction.startswith("theta"):
            out["theta_deg"] = 90.0 * t
        elif role == "alpha" and c.roughness.startswith("r2"):
            out["r"] = t
        else:
            out[role] = role_value(c, role, t)
    return out
