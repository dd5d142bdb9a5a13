"""The material as a :class:`brdfnorm.models.Model`: any command that takes a model takes it.

:class:`OpenPBR` evaluates the terms of :func:`brdfnorm.materials.openpbr.build` (cached per parameter set); swept
parameters (arrays, as ``check``, ``lut`` and sweeps bind them) are evaluated one distinct parameter set at a time.

Its albedo has a route of its own, method ``"material"`` (:func:`albedo_method`, registered by
:mod:`brdfnorm.materials`): term by term, E(μ_o) = Σ_k w_k Π_view (1 − E_t(μ_o)) · I_k(μ_o) with
I_k = ∫ Π_light (1 − E_t(μ_i)) f_k (N·L) dL — the lobe's exact albedo where the term has no light-side factor, for a
Lambertian lobe ρ·2∫Π(1 − E_t(μ))μ dμ (1-D, adaptive), and otherwise the generic cubature of that one product. It
is independent of the generic ``"quadrature"`` of the whole BRDF, which the tests compare it with.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Mapping

import numpy as np

from ..errors import ParameterError
from ..models.base import Lobe, Model, mirror, normal_lobe
from ..models.zeltner import ROUGHNESS_MIN as ZELTNER_MIN
from ..parameters import Parameter
from . import openpbr
from .compose import Term, evaluate_terms

_TERMS: OrderedDict = OrderedDict()
_TERMS_CACHE = 128


def _key(p: Mapping[str, object]) -> tuple:
    return tuple((k, v if isinstance(v, str) else tuple(np.ravel(np.asarray(v, dtype=float)))) for k, v in
                 sorted(p.items()))


def terms_of(p: Mapping[str, object]) -> list[Term]:
    """The (cached) terms of one material's scalar parameter values."""
    key = _key(p)
    if key in _TERMS:
        _TERMS.move_to_end(key)
        return _TERMS[key]
    terms = _TERMS[key] = openpbr.build(dict(p))
    if len(_TERMS) > _TERMS_CACHE:
        _TERMS.popitem(last=False)
    return terms


def parameter_sets(parameters: tuple[Parameter, ...], params: Mapping[str, object], shape: tuple[int, ...]):
    """Yield (mask over ``shape`` or None, scalar parameter values) for each distinct parameter set in a batch."""
    batched = {}
    for p in parameters:
        value = params[p.name]
        if p.kind == "choice":
            continue
        array = np.asarray(value, dtype=float)
        batch = array.shape[:-1] if p.per_channel else array.shape
        if batch:
            tail = (3,) if p.per_channel else ()
            batched[p.name] = np.broadcast_to(array, shape + tail).reshape((-1,) + tail)
    if not batched:
        yield None, dict(params)
        return
    rows = np.column_stack([v.reshape(v.shape[0], -1) for v in batched.values()])
    unique, inverse = np.unique(rows, axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    for index in range(unique.shape[0]):
        mask = inverse == index
        first = int(np.argmax(mask))
        scalar = dict(params)
        for name, value in batched.items():
            scalar[name] = tuple(value[first]) if value.ndim == 2 else float(value[first])
        yield mask.reshape(shape), scalar


class OpenPBR(Model):
    name = "openpbr"
    #: A material model: material files may name it (:mod:`brdfnorm.materials.files`).
    material = True
    formula = ("f = F f_fuzz + lerp(1, 1−E_fuzz, F)[C f_coat + lerp(1, T(1−E_coat), C) mix(f_spec + (1−E_spec) "
               "f_diffuse, f_metal, M)]  (OpenPBR Surface, albedo-scaling layering; rules selectable)")
    energy = ("layered by albedo scaling: E ≤ 1 where every lobe's is (view-side rule); the charlie fuzz "
              "(fuzz_lobe=charlie) gains energy at grazing views at low roughness")
    closed_form_domain = "none"
    parameters = openpbr.PARAMETERS
    channels = 3

    def _check(self) -> None:
        p = self._params
        weight = np.asarray(p["transmission_weight"], dtype=float)
        #: Scatters into the lower hemisphere where a translucent base is present (the engine then integrates both).
        self.transmits = bool(np.any(weight > 0))
        if self.transmits and all(np.ndim(p[q.name]) == (1 if q.per_channel else 0) for q in self.parameters
                                  if q.kind not in ("choice", "bool")):
            openpbr.check_transmission(dict(p))
        fuzz = np.asarray(p["fuzz_roughness"], dtype=float)
        on = np.asarray(p["fuzz_weight"]) > 0
        if p["fuzz_lobe"] == "zeltner" and np.any(on & (fuzz < ZELTNER_MIN)):
            raise ParameterError(f"the fuzz (zeltner LTC sheen) needs fuzz_roughness ≥ {ZELTNER_MIN:g} (the fit's "
                                 "range)", where="parameter fuzz_roughness")
        if p["fuzz_lobe"] == "charlie" and np.any(on & (fuzz * fuzz < 1e-3 * (1 - 1e-12))):
            raise ParameterError("the fuzz (charlie sheen) needs fuzz_roughness ≥ 0.0317 (α ≥ 1e-3)",
                                 where="parameter fuzz_roughness")

    def search_space(self) -> dict[str, tuple[float, float] | None]:
        """``check`` holds the table size, the conductor's index unless it is used, the parameters of layers that
        are off (they then do nothing; the translucent base unless transmission_weight > 0) and thin-walled mode."""
        p = self._params
        space: dict[str, tuple[float, float] | None] = {"albedo_table": None}
        if p["metal_fresnel"] != "conductor":
            space.update(metal_eta=None, metal_k=None)
        if p["fuzz_weight"] == 0:
            space.update(fuzz_roughness=None)
        else:  # the lobe's own range of roughness
            low = ZELTNER_MIN if p["fuzz_lobe"] == "zeltner" else float(np.sqrt(1e-3))
            space.update(fuzz_roughness=(low, 1.0))
        space.update(specular_weight=(0.0, 1.0), geometry_thin_walled=None)
        if np.all(np.asarray(p["transmission_weight"]) == 0):  # opaque as given: the translucent base stays off
            space.update(transmission_weight=None, transmission_color=None, transmission_depth=None)
        else:  # an index-matched interface (specular_weight 0) refracts into a delta, refused
            space.update(specular_weight=(1e-3, 1.0))
        return space

    def projected(self, L, V, params):
        shape = np.broadcast_shapes(L.shape[:-1], V.shape[:-1])
        out = np.zeros(shape + (3,))
        for mask, scalar in parameter_sets(self.parameters, params, shape):
            terms = terms_of(scalar)
            source, size = scalar["albedo_source"], int(scalar["albedo_table"])
            if mask is None:
                return evaluate_terms(terms, L, V, source, size)
            Lm = np.broadcast_to(L, shape + (3,))[mask]
            Vm = np.broadcast_to(V, shape + (3,))[mask]
            out[mask] = evaluate_terms(terms, Lm, Vm, source, size)
        return out

    def evaluate(self, L, V, params):
        with np.errstate(divide="ignore", invalid="ignore"):
            value = self.projected(L, V, params) / np.abs(L[..., 2:3])
        return np.where(L[..., 2:3] != 0, value, 0.0)

    def transmission_lobe(self, fixed, params) -> Lobe:
        """The refraction lobe of the translucent base (its ``ggx-dielectric`` lobe's hint, for the first parameter
        set: a hint only)."""
        first = next(parameter_sets(self.parameters, params, np.shape(fixed)[:-1]))[1]
        component = next((t.component for t in terms_of(first) if t.component.transmits), None)
        if component is None:
            return normal_lobe(fixed)
        model = component.model()
        return model.transmission_lobe(fixed, model.params)

    def lobe(self, fixed, params, over):
        """The mirror direction, as wide as the sharper of the specular and (present) coat lobes (the diffuse part is
        broad and needs no hint)."""
        r = np.asarray(params["specular_roughness"], dtype=float)
        coat = np.asarray(params["coat_roughness"], dtype=float)
        r = np.where(np.asarray(params["coat_weight"], dtype=float) > 0, np.minimum(r, coat), r)
        shape = np.broadcast_shapes(np.shape(fixed)[:-1], r.shape)
        width = np.broadcast_to(np.clip(2.0 * r * r, 1e-3, 1.0), shape)
        return Lobe(np.broadcast_to(mirror(fixed), shape + (3,)), width, np.full(shape, np.pi))
