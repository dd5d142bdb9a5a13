"""Mitsuba 3's BSDFs as models: ``mitsuba:PLUGIN`` and Mitsuba XML files, evaluated by the renderer's own code.

A model here is one Mitsuba BSDF plugin instance (``mi.load_dict`` for ``mitsuba:roughconductor``, ``mi.load_string``
for an XML file read through :func:`brdfnorm.inputs.read_bounded`). It is evaluated by ``BSDF.eval`` in the local
frame (N = +z, the shading frame the identity): Mitsuba's ``si.wi`` is the direction towards the sensor — brdfnorm's
view V — and ``wo`` the direction towards the emitter, the light L (Mitsuba 3 documentation, "BSDF" class: ``eval``
returns f(wi, wo) times the foreshortening |cos θ_o| of ``wo``). So ``eval(wi = V, wo = L)`` is exactly the
light-integral integrand f(L, V)|N·L| of :meth:`brdfnorm.models.Model.projected`, and f itself is that divided by
|L_z|. The context is ``TransportMode.Importance``: in radiance mode Mitsuba scales refraction by 1/η² (the radiance
compression), in importance mode it does not, which is the energy form of :mod:`brdfnorm.models.dielectric` (R + T
of a smooth interface is 1).

Vectorized through a Dr.Jit LLVM variant (``llvm_ad_rgb``: whole numpy batches become Dr.Jit arrays, one kernel per
call) where Dr.Jit finds a libLLVM it can use, else ``scalar_rgb`` (a Python loop: correct, slow). Dr.Jit looks for
the library itself (``/usr/lib/x86_64-linux-gnu/libLLVM*.so.*``, or ``DRJIT_LIBLLVM_PATH``); LLVM 15 and 16 abort the
process when Mitsuba 3.9's kernels are compiled ("Cannot select: fmaximum"), so below :data:`MIN_LLVM` the scalar
variant is used. ``BRDFNORM_MITSUBA_VARIANT`` overrides the choice.

Mitsuba's variants evaluate in float32: :attr:`MitsubaModel.epsilon` declares it (unit roundoff 2⁻²⁴) and the
hemisphere quadrature charges that noise in its error estimates (:mod:`brdfnorm.engine.machinery.rounding`).
"""

from __future__ import annotations

import os
import re
import xml.etree.ElementTree as ElementTree
from collections import OrderedDict
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from ..errors import ArgumentError, BrdfFileError, ModelNotFoundError, ParameterError
from ..parameters import Parameter
from .base import Lobe, Model, Origin, mirror
from .dielectric import refract

PREFIX = "mitsuba:"
INSTALL_HINT = "Mitsuba 3 is not installed: pip install 'brdfnorm[mitsuba]'"
#: The oldest libLLVM this module lets Dr.Jit use (15 and 16 abort on Mitsuba 3.9's kernels; 19 was tested).
MIN_LLVM = (19,)
#: Largest Mitsuba XML file read (a BSDF description is a few kilobytes).
MAX_XML_BYTES = 1024**2
#: Plugin instances kept per model, one per distinct set of parameter values (a sweep evaluates several).
CACHE_SIZE = 64
#: Mitsuba texture plugins: a BSDF property given as one of these varies over the surface and is refused.
TEXTURES = ("bitmap", "checkerboard", "mesh_attribute", "volume", "grid", "constvolume", "gridvolume")

_DISTRIBUTION = Parameter("distribution", "choice", "beckmann", choices=("beckmann", "ggx"),
                          description="microfacet distribution")


def _alpha(default: float) -> Parameter:
    return Parameter("alpha", "float", default, 1e-3, 1.0, "roughness α (slope width), isotropic")


def _ior(name: str, default: float, what: str) -> Parameter:
    return Parameter(name, "float", default, 1.0, 4.0, f"{what} index of refraction")


def _colour(name: str, default: float, maximum: float | None, what: str) -> Parameter:
    return Parameter(name, "color", (default,) * 3, 0.0, maximum, what)


def _unit(name: str, default: float, what: str) -> Parameter:
    return Parameter(name, "float", default, 0.0, 1.0, what)


#: Declared parameters of the plugins brdfnorm knows, with Mitsuba 3's defaults (a property left at its default is
#: not passed, so Mitsuba's own default applies). Other plugins take the properties given to :func:`load`.
PLUGINS: dict[str, tuple[Parameter, ...]] = {
    "diffuse": (_colour("reflectance", 0.5, 1.0, "diffuse reflectance"),),
    "roughconductor": (_DISTRIBUTION, _alpha(0.1),
                       _colour("eta", 0.0, None, "real part of the conductor's index (0 and k = 1: F = 1)"),
                       _colour("k", 1.0, None, "imaginary part of the conductor's index"),
                       _colour("specular_reflectance", 1.0, None, "scale of the reflection (1 is physical)")),
    "roughdielectric": (_DISTRIBUTION, _alpha(0.1), _ior("int_ior", 1.5046, "interior"),
                        _ior("ext_ior", 1.000277, "exterior"),
                        _colour("specular_reflectance", 1.0, None, "scale of the reflection (1 is physical)"),
                        _colour("specular_transmittance", 1.0, None, "scale of the refraction (1 is physical)")),
    "roughplastic": (_DISTRIBUTION, _alpha(0.1), _ior("int_ior", 1.49, "interior"),
                     _ior("ext_ior", 1.000277, "exterior"),
                     _colour("diffuse_reflectance", 0.5, 1.0, "reflectance of the diffuse base"),
                     _colour("specular_reflectance", 1.0, None, "scale of the coating reflection (1 is physical)"),
                     Parameter("nonlinear", "bool", False, description="account for internal scattering's tint")),
    "principled": (_colour("base_color", 0.5, 1.0, "base colour"), _unit("roughness", 0.5, "roughness"),
                   _unit("metallic", 0.0, "metallic"), _unit("specular", 0.5, "specular (sets the index)"),
                   _unit("spec_tint", 0.0, "specular tint"), _unit("anisotropic", 0.0, "anisotropy"),
                   _unit("sheen", 0.0, "sheen"), _unit("sheen_tint", 0.0, "sheen tint"),
                   _unit("clearcoat", 0.0, "clearcoat"), _unit("clearcoat_gloss", 0.0, "clearcoat gloss"),
                   _unit("spec_trans", 0.0, "specular transmission")),
}


def mitsuba_module():
    """``mitsuba`` with a variant set (the LLVM one where usable), or a one-line install hint (exit 2)."""
    try:
        import mitsuba as mi
    except ImportError:
        raise ModelNotFoundError(INSTALL_HINT, where="mitsuba") from None
    wanted = variant(mi)
    if mi.variant() != wanted:
        mi.set_variant(wanted)
    return mi


def variant(mi) -> str:
    """The variant to evaluate in: ``BRDFNORM_MITSUBA_VARIANT``, else ``llvm_ad_rgb`` where Dr.Jit's LLVM backend
    loaded a libLLVM ≥ :data:`MIN_LLVM`, else ``scalar_rgb``."""
    chosen = os.environ.get("BRDFNORM_MITSUBA_VARIANT")
    if chosen:
        rgb = [v for v in mi.variants() if v.endswith("_rgb") and not v.startswith("cuda")]
        if chosen not in rgb:
            raise ArgumentError(f"expected one of this Mitsuba's RGB CPU variants ({', '.join(rgb)}), got "
                                f"{chosen!r}", where="BRDFNORM_MITSUBA_VARIANT")
        return chosen
    import drjit as dr

    if "llvm_ad_rgb" in mi.variants() and dr.has_backend(dr.JitBackend.LLVM):
        if tuple(dr.detail.llvm_version()) >= MIN_LLVM:
            return "llvm_ad_rgb"
    return "scalar_rgb"


def _one_line(failure: Exception) -> str:
    """Mitsuba's message without its source-file tags, on one line."""
    text = " ".join(str(failure).split())
    return re.sub(r"\[[\w.]+:\d+\]\s*", "", text)[:300] or type(failure).__name__


class MitsubaModel(Model):
    """One Mitsuba BSDF plugin, its properties the model's parameters (see the module docstring)."""

    name = "mitsuba"
    formula = "f(L, V) = Mitsuba BSDF.eval(wi = V, wo = L) / |N·L|  (the renderer's own float32 code)"
    #: Unit roundoff of the evaluation: Mitsuba's variants compute in float32.
    epsilon = 2.0**-24

    def __init__(self, plugin: str, parameters: tuple[Parameter, ...], fixed: Mapping[str, object] | None = None,
                 *, xml: str | None = None, source_path: str | None = None, **values: object) -> None:
        self.mi = mitsuba_module()
        self.variant = self.mi.variant()  # its plugin instances belong to this variant
        self.plugin = plugin
        self.name = f"{PREFIX}{plugin}"
        self.parameters = parameters
        self.fixed = dict(fixed or {})  # properties passed as given (plugins brdfnorm does not declare)
        self.xml = xml
        self.source_path = source_path
        self.channels = 3
        self._cache: OrderedDict = OrderedDict()
        super().__init__(**values)

    def origin(self) -> Origin:
        """``mitsuba:PLUGIN`` with the undeclared properties it was given, or an XML file's path and its
        ``<bsdf>`` text (:func:`brdfnorm.load_text` loads the same element)."""
        if self.xml is not None:
            return Origin(self.source_path if self.source_path and is_mitsuba(self.source_path) else "<bsdf>.xml",
                          self.xml)
        return Origin(self.name, fixed=self.fixed)

    def _check(self) -> None:
        self.isotropic = not np.any(np.asarray(self._params.get("anisotropic", 0.0), dtype=float) != 0)
        mi = self.mi
        self.transmits = False
        for values in self._value_sets(self._params):  # Mitsuba refuses bad properties here, each set of a sweep
            bsdf = self._bsdf(values)
            if any(mi.has_flag(bsdf.flags(i), mi.BSDFFlags.Delta) for i in range(bsdf.component_count())):
                raise ParameterError(f"{self.plugin} has a delta (smooth) component, which has no BRDF values to "
                                     "integrate; use its rough variant (e.g. roughconductor for conductor)",
                                     where=self.source_path or self.name)
            self.transmits |= bool(mi.has_flag(bsdf.flags(), mi.BSDFFlags.Transmission))

    def search_space(self) -> dict[str, tuple[float, float] | None]:
        """``check`` holds the exterior index (the medium the surface is seen from, air by default) and searches the
        interior one above it: Mitsuba refuses equal indices (no interface), which a search of both reaches."""
        names = {p.name for p in self.parameters}
        if not {"int_ior", "ext_ior"} <= names:
            return {}
        outside = float(np.max(self._params["ext_ior"]))
        top = self.parameter("int_ior").maximum
        return {"ext_ior": None, "int_ior": (min(outside * (1.0 + 1e-3), top), top)}

    def _value_sets(self, params: Mapping[str, object]) -> list[tuple]:
        """The distinct parameter-value tuples of (possibly array-valued) ``params``."""
        shape = np.broadcast_shapes(*self._batch_shapes(params))
        if not shape:
            return [self._case_values(params, None)]
        broadcast = {p.name: params[p.name] if p.kind == "choice" else
                     np.broadcast_to(np.asarray(params[p.name], dtype=float),
                                     shape + ((3,) if p.kind == "color" else ())) for p in self.parameters}
        return list(dict.fromkeys(self._case_values(broadcast, index) for index in np.ndindex(shape)))

    # -- plugin instances ---------------------------------------------------------------------------------
    def _case_values(self, params: Mapping[str, object], index) -> tuple:
        """The parameter values of one case as a hashable tuple (``index`` picks an element of array values)."""
        out = []
        for p in self.parameters:
            value = params[p.name]
            if p.kind == "choice":
                out.append(value)
                continue
            array = np.asarray(value, dtype=float)
            if index is not None and array.ndim > (1 if p.kind == "color" else 0):
                array = array[index]
            out.append(tuple(float(v) for v in np.broadcast_to(array, (3,))) if p.kind == "color"
                       else float(array))
        return tuple(out)

    def _properties(self, values: tuple) -> dict:
        """Mitsuba's scene dictionary for these parameter values (those at their default left out)."""
        mi = self.mi
        props: dict = {"type": self.plugin, **self.fixed}
        for p, value in zip(self.parameters, values, strict=True):
            default = tuple(np.broadcast_to(np.asarray(p.default, dtype=float), (3,))) if p.kind == "color" \
                else p.default
            if value == default and p.name not in self.fixed:
                continue
            if p.kind == "color":
                props[p.name] = value[0] if value[0] == value[1] == value[2] else \
                    {"type": "rgb", "value": mi.ScalarColor3f(*value)}
            elif p.kind == "bool":
                props[p.name] = bool(value)
            else:
                props[p.name] = value
        return props

    def _bsdf(self, values: tuple):
        if self.mi.variant() != self.variant:  # another model (or the user) set another variant since
            self.mi.set_variant(self.variant)
        cached = self._cache.get(values)
        if cached is not None:
            self._cache.move_to_end(values)
            return cached
        where = self.source_path or self.name
        try:
            if self.xml is not None:
                bsdf = self.mi.load_string(self.xml)
            else:
                bsdf = self.mi.load_dict(self._properties(values))
        except Exception as failure:  # noqa: BLE001 - Mitsuba raises RuntimeError for every kind of bad input
            error = BrdfFileError(f"Mitsuba refused it: {_one_line(failure)}", where) if self.xml is not None \
                else ParameterError(f"Mitsuba refused it: {_one_line(failure)}", where=where)
            raise error from None
        if not isinstance(bsdf, self.mi.BSDF):
            raise BrdfFileError(f"not a BSDF but a {type(bsdf).__name__}", where)
        self._cache[values] = bsdf
        if len(self._cache) > CACHE_SIZE:
            self._cache.popitem(last=False)
        return bsdf

    # -- evaluation ---------------------------------------------------------------------------------------
    def projected(self, L: np.ndarray, V: np.ndarray, params: Mapping[str, object]) -> np.ndarray:
        """Mitsuba's eval(wi = V, wo = L): f(L, V)|N·L| (..., 3), one call per distinct set of parameter values."""
        shape = np.broadcast_shapes(L.shape[:-1], V.shape[:-1], *self._batch_shapes(params))
        L = np.broadcast_to(L, shape + (3,)).reshape(-1, 3)
        V = np.broadcast_to(V, shape + (3,)).reshape(-1, 3)
        out = np.zeros((L.shape[0], 3))
        swept = [p for p in self.parameters if p.kind != "choice"
                 and np.ndim(params[p.name]) > (1 if p.kind == "color" else 0)]
        if not swept:
            out[:] = self._eval(self._bsdf(self._case_values(params, None)), L, V)
            return out.reshape(shape + (3,))
        columns = []
        for p in swept:
            tail = (3,) if p.kind == "color" else ()
            array = np.broadcast_to(np.asarray(params[p.name], dtype=float), shape + tail)
            columns.append(array.reshape(L.shape[0], -1))
        table = np.concatenate(columns, axis=1)
        rows, first, label = np.unique(table, axis=0, return_index=True, return_inverse=True)
        label = label.reshape(-1)
        flat = {p.name: np.broadcast_to(np.asarray(params[p.name], dtype=float),
                                        shape + ((3,) if p.kind == "color" else ())).reshape(L.shape[0], -1)
                for p in swept}
        for group in range(rows.shape[0]):
            members = np.flatnonzero(label == group)
            one = dict(params)
            for p in swept:
                row = flat[p.name][first[group]]
                one[p.name] = tuple(row) if p.kind == "color" else float(row[0])
            out[members] = self._eval(self._bsdf(self._case_values(one, None)), L[members], V[members])
        return out.reshape(shape + (3,))

    def evaluate(self, L: np.ndarray, V: np.ndarray, params: Mapping[str, object]) -> np.ndarray:
        """f(L, V) = eval / |N·L| (0 where L lies in the tangent plane, as Mitsuba's eval is there)."""
        value = self.projected(L, V, params)
        cos = np.abs(np.broadcast_to(L[..., 2:3], value.shape))
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(cos > 0, value / np.where(cos > 0, cos, 1.0), 0.0)

    def _batch_shapes(self, params: Mapping[str, object]) -> list[tuple[int, ...]]:
        shapes = []
        for p in self.parameters:
            if p.kind == "choice":
                continue
            value = np.asarray(params[p.name])
            shapes.append(value.shape[:-1] if p.kind == "color" else value.shape)
        return shapes

    def _eval(self, bsdf, L: np.ndarray, V: np.ndarray) -> np.ndarray:
        """eval(wi = V, wo = L) in importance mode for (M, 3) float64 directions, rounded to float32: (M, 3)."""
        mi = self.mi
        if L.shape[0] == 0:
            return np.zeros((0, 3))
        if mi.variant() != self.variant:
            mi.set_variant(self.variant)
        ctx = mi.BSDFContext(mi.TransportMode.Importance)
        if not self.variant.startswith("scalar"):
            L32, V32 = L.astype(np.float32), V.astype(np.float32)
            import drjit as dr

            si = dr.zeros(mi.SurfaceInteraction3f, L.shape[0])
            si.wi = mi.Vector3f(V32[:, 0], V32[:, 1], V32[:, 2])
            si.sh_frame = mi.Frame3f(mi.Vector3f(0.0, 0.0, 1.0))
            si.n = mi.Normal3f(0.0, 0.0, 1.0)
            value = bsdf.eval(ctx, si, mi.Vector3f(L32[:, 0], L32[:, 1], L32[:, 2]))
            return np.array(value, dtype=np.float64).reshape(3, -1).T
        out = np.empty((L.shape[0], 3))
        si = mi.SurfaceInteraction3f()
        si.sh_frame = mi.Frame3f(mi.Vector3f(0.0, 0.0, 1.0))
        for i in range(L.shape[0]):
            si.wi = mi.Vector3f(*(float(c) for c in V[i]))
            out[i] = np.array(bsdf.eval(ctx, si, mi.Vector3f(*(float(c) for c in L[i]))), dtype=np.float64)
        return out

    # -- hints for the integrator -------------------------------------------------------------------------
    def lobe(self, fixed, params, over):
        """About the mirror direction, 2α wide, for the plugins with a microfacet α; a search otherwise."""
        if "alpha" not in params:
            return None
        alpha = np.asarray(params["alpha"], dtype=float)
        shape = np.broadcast_shapes(np.shape(fixed)[:-1], np.shape(alpha))
        width = np.broadcast_to(np.clip(2.0 * alpha, 1e-6, 1.0), shape)
        return Lobe(np.broadcast_to(mirror(fixed), shape + (3,)), width, np.full(shape, np.pi))

    def transmission_lobe(self, fixed, params) -> Lobe:
        """About the direction refracted through N (roughdielectric's indices; 1.5 otherwise), α-wide or broad."""
        eta = np.asarray(params.get("int_ior", 1.5), dtype=float) / np.asarray(params.get("ext_ior", 1.0), dtype=float)
        alpha = np.asarray(params.get("alpha", 0.5), dtype=float)
        shape = np.broadcast_shapes(np.shape(fixed)[:-1], np.shape(alpha), np.shape(eta))
        V = np.broadcast_to(fixed, shape + (3,))
        eta = np.broadcast_to(eta, shape)
        L, exists = refract(V, np.broadcast_to(np.array([0.0, 0.0, 1.0]), shape + (3,)), eta)
        grazing = np.stack([-V[..., 0], -V[..., 1], np.full(shape, -1e-3)], axis=-1)
        direction = np.where(exists[..., None], L, grazing)
        direction = direction / np.linalg.norm(direction, axis=-1, keepdims=True)
        width = np.broadcast_to(np.clip(2.0 * np.maximum(alpha, alpha / eta), 1e-6, 1.0), shape)
        return Lobe(direction, width, np.full(shape, np.pi))


def _inferred(name: str, value: object) -> tuple[Parameter, object | None]:
    """A parameter declared from a value given to an undeclared plugin (a float, R,G,B or a string property);
    nested dictionaries (textures) are refused."""
    if isinstance(value, Mapping):
        kind = value.get("type")
        if kind in ("rgb", "spectrum"):
            return Parameter(name, "color", (0.0,) * 3), None
        raise ParameterError(f"a {kind or 'nested'} texture or plugin is not supported: brdfnorm evaluates a BSDF "
                             "that is the same everywhere on the surface (give a float or R,G,B)",
                             where=f"parameter {name}")
    if isinstance(value, str):
        return Parameter(name, "choice", value, choices=(value,)), None
    if isinstance(value, bool):
        return Parameter(name, "bool", bool(value)), None
    array = np.asarray(value, dtype=float)
    if array.shape[-1:] == (3,):
        return Parameter(name, "color", (np.nan,) * 3), None
    return Parameter(name, "float", np.nan), None


def load_plugin(plugin: str, **values: object) -> MitsubaModel:
    """``mitsuba:PLUGIN`` with properties as keyword values: a declared plugin (:data:`PLUGINS`) or any other,
    whose properties are then exactly those given."""
    if not re.fullmatch(r"[a-z][a-z0-9_]*", plugin):
        raise ModelNotFoundError(f"expected a Mitsuba plugin name after {PREFIX!r}, got {plugin!r}", where="model")
    for name, value in values.items():
        if isinstance(value, Mapping) and value.get("type") not in ("rgb", "spectrum"):
            _inferred(name, value)  # raises: textures are refused
    declared = PLUGINS.get(plugin)
    if declared is None:
        declared = tuple(_inferred(name, value)[0] for name, value in values.items())
    return MitsubaModel(plugin, declared, **values)


def _refuse_textures(root: ElementTree.Element, where: str) -> None:
    """Textures vary over the surface; includes and ``filename`` properties would have Mitsuba read other files
    (the XML is data: only what it holds is evaluated)."""
    for element in root.iter():
        if element.tag == "texture" or (element.tag in ("bsdf", "texture") and element.get("type") in TEXTURES):
            raise BrdfFileError(f"a {element.get('type', '')} texture is not supported: brdfnorm evaluates a BSDF "
                                "that is the same everywhere on the surface (give a float, rgb or spectrum)", where)
        if element.tag == "include" or element.get("name") == "filename":
            raise BrdfFileError("refers to another file (an <include> or a filename property); brdfnorm reads only "
                                "the XML it is given", where)


def _depth_bounded(root: ElementTree.Element, where: str) -> None:
    """Refuse elements nested deeper than :data:`~brdfnorm.inputs.limits.MAX_XML_DEPTH` (walked without recursion:
    ``ElementTree.tostring`` and Mitsuba's loader recurse, and 100 000 nested ``<bsdf>`` raised RecursionError)."""
    from ..inputs.limits import MAX_XML_DEPTH

    stack = [(root, 1)]
    while stack:
        element, depth = stack.pop()
        if depth > MAX_XML_DEPTH:
            raise BrdfFileError(f"elements nested more than {MAX_XML_DEPTH} deep", where)
        stack.extend((child, depth + 1) for child in element)


def load_xml(path: str | os.PathLike) -> MitsubaModel:
    """A Mitsuba XML file holding one ``<bsdf>`` (at its root, or the first in a ``<scene>``)."""
    from ..inputs import parsing, read_bounded

    where = os.fspath(path)
    data = read_bounded(path, MAX_XML_BYTES, error=BrdfFileError)
    with parsing(path, error=BrdfFileError):
        root = ElementTree.fromstring(data)  # the file is data: parsed here, loaded by Mitsuba as a string
    _depth_bounded(root, where)
    bsdf = root if root.tag == "bsdf" else root.find(".//bsdf")
    if bsdf is None:
        raise BrdfFileError("no <bsdf> element", where)
    _refuse_textures(bsdf, where)
    bsdf.set("version", root.get("version", bsdf.get("version", "3.0.0")))
    bsdf.attrib.pop("id", None)
    text = ElementTree.tostring(bsdf, encoding="unicode")
    return MitsubaModel(bsdf.get("type", "bsdf"), (), xml=text, source_path=where)


def plugin_type(xml: str) -> str:
    """The plugin type of a ``<bsdf>`` element's text (as :func:`load_xml` made it)."""
    return ElementTree.fromstring(xml).get("type", "bsdf")


def is_mitsuba(key: str) -> bool:
    """True for the names and paths this module loads: ``mitsuba:PLUGIN`` or a ``.xml`` file."""
    return key.startswith(PREFIX) or Path(key).suffix.lower() == ".xml"


def load_string(xml: str, where: str) -> MitsubaModel:
    """The model of a ``<bsdf>`` element's text as :func:`load_xml` made it (sent to another process)."""
    return MitsubaModel(plugin_type(xml), (), xml=xml, source_path=where)


def load(key: str, **values: object) -> MitsubaModel:
    """``mitsuba:PLUGIN`` (with properties as keyword values) or an XML file (no keyword values)."""
    if key.startswith(PREFIX):
        return load_plugin(key[len(PREFIX):], **values)
    if values:
        raise ParameterError("a Mitsuba XML file's properties are set in the file", where=key)
    return load_xml(key)
