"""Materials: lobes composed by the standards' rules (mixing, albedo-scaling layering), with exact albedos.

:mod:`.components` (the lobes and their exact E(μ)), :mod:`.albedo` (E inside the integrand: exact, curves,
engine tables), :mod:`.compose` (the rules), :mod:`.openpbr` (OpenPBR Surface's structure and parameters),
:mod:`.model` (the ``openpbr`` model), :mod:`.route` (albedo method ``"material"``, term by term), :mod:`.files`
(material files, TOML or JSON).
The model is declared in :data:`brdfnorm.models.REGISTRY` and the method in the engine's
:data:`brdfnorm.engine.methods.METHODS`, by where they live (:class:`brdfnorm.registry.Reference`): importing this
package registers nothing.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..registry import lazy_exports

if TYPE_CHECKING:
    from . import files
    from .model import OpenPBR

__all__ = ["OpenPBR", "files"]


#: ``OpenPBR`` and ``files`` imported on first use (PEP 562): a ``.brdf`` file's load reads
#: :func:`.files.is_material_file` without importing the material model, its lobes and the engine.
__getattr__, __dir__ = lazy_exports(__name__, {"OpenPBR": "model", "files": "files"})
