"""The cloth channel of a three-channel DFG texture: DFG_cloth(μ, α) = ∫ D_charlie(H) V_neubelt(L, V) (N·L) dL, the
albedo of Estevez & Kulla 2017's sheen distribution with the visibility V = 1/(4(N·L + N·V − N·L N·V)) that
Filament and glTF use (the ``charlie`` lobe with ``shadowing=neubelt``, white). Engines store it beside the split-sum
pair (Filament's DFG LUT: DFG_f0, DFG_f90 and the cloth DG in one RGB texture indexed by N·V and roughness), so
``lut --channels dfg`` adds it when the table's other axes are ``alpha`` or ``roughness``: the cloth lobe is evaluated
at the same value of the same name (the sheen α, or the roughness with α = roughness²), clamped to the sheen lobe's
smallest α (recorded in the table's ``meta["dfg"]``).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..models.base import Model
from ..models.charlie import ALPHA_MIN, Charlie

#: The axis names the cloth channel follows.
CLOTH_AXES = ("alpha", "roughness")
DESCRIPTION = ("DFG_cloth = ∫ D_charlie V_neubelt cos dL (Estevez & Kulla 2017 sheen, white, at the same alpha or "
               "roughness, alpha ≥ 1e-3)")


def cloth_model(param_grids: Mapping[str, np.ndarray]) -> tuple[Model, dict[str, np.ndarray]] | None:
    """The white ``charlie`` lobe with ``shadowing=neubelt`` and its parameter grids, or None where the table's
    parameter axes are not exactly one of ``alpha`` / ``roughness``."""
    if len(param_grids) != 1 or next(iter(param_grids)) not in CLOTH_AXES:
        return None
    (name, grid), = param_grids.items()
    floor = ALPHA_MIN if name == "alpha" else float(np.sqrt(ALPHA_MIN))
    return Charlie(shadowing="neubelt"), {name: np.clip(np.asarray(grid, dtype=float), floor, 1.0)}
