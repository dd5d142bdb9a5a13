"""Built-in lobes and the registry that names them (the names are the CLI's model names)."""

from __future__ import annotations

from ..registry import Reference, Registry
from .base import Lobe, Model, Over, mirror
from .beckmann import Beckmann
from .beckmann_dielectric import BeckmannDielectric
from .blinn_phong import BlinnPhong
from .blinn_phong_gaussian import BlinnPhongGaussian
from .burley import Burley
from .charlie import Charlie
from .eon import EnergyPreservingOrenNayar
from .fon import FujiiOrenNayar
from .ggx import GGX
from .ggx_dielectric import GGXDielectric
from .lambert import Lambert
from .oren_nayar import OrenNayar
from .phong import PhongModified, PhongOriginal
from .zeltner import Zeltner

#: The built-in models by name; ``openpbr`` (a material of these lobes, :mod:`brdfnorm.materials`, which sits
#: above the engine) is declared by where it lives and imported when first looked up.
REGISTRY: Registry[type[Model]] = Registry("model", "model", {
    **{cls.name: cls for cls in (Lambert, PhongOriginal, PhongModified, BlinnPhong, BlinnPhongGaussian, GGX, Beckmann,
                                 GGXDielectric, BeckmannDielectric, Charlie, OrenNayar,
                                 FujiiOrenNayar, EnergyPreservingOrenNayar, Burley, Zeltner)},
    "openpbr": Reference("brdfnorm.materials.model:OpenPBR"),
})

__all__ = ["REGISTRY", "Lobe", "Model", "Over", "mirror", "Beckmann", "BeckmannDielectric", "BlinnPhong",
           "BlinnPhongGaussian", "Burley", "Charlie", "EnergyPreservingOrenNayar",
           "FujiiOrenNayar", "GGX", "GGXDielectric", "Lambert", "OrenNayar", "PhongModified", "PhongOriginal",
           "Zeltner"]
