"""Materials: lobes composed by the standards' rules (mixing, albedo-scaling layering), with exact albedos.

:mod:`.components` (the lobes and their exact E(μ)), :mod:`.albedo` (E inside the integrand: exact, curves,
engine tables), :mod:`.compose` (the rules), :mod:`.openpbr` (OpenPBR Surface's structure and parameters),
:mod:`.model` (the ``openpbr`` model), :mod:`.route` (albedo method ``"material"``, term by term), :mod:`.files`
(material files, TOML or JSON).
Importing the package registers the model in :data:`brdfnorm.models.REGISTRY` and the method in the engine's.
"""

from __future__ import annotations

from ..engine.methods import Method, register_method
from ..models import REGISTRY
from . import files, route
from .model import OpenPBR

if "openpbr" not in REGISTRY:
    REGISTRY.register("openpbr", OpenPBR)
    register_method(Method("material", route.applies, route.albedo_method,
                           "a material term by term: its lobes' exact albedos through the layering factors"),
                    auto_priority=0)

__all__ = ["OpenPBR", "files"]
