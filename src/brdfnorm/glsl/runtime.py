"""Run-time state of a compiled shader: frames, lane masks and masked (per-lane) assignment.

A GPU runs each invocation's control flow on its own; here all direction pairs (lanes) run together
as numpy arrays, so control flow whose condition differs between lanes is executed under a *mask*:
the set of lanes still active. A mask is ``None`` (every lane active), ``False`` (no lane active:
the rest of the block is skipped) or a boolean array. Assignments under a mask blend the new value
into the old one with ``np.where``; ``return``, ``break`` and ``continue`` remove their lanes from the
mask until the enclosing function / loop iteration ends. This is the classic SIMT execution model
(e.g. Fung et al., "Dynamic warp formation", MICRO 2007, §2) with a mask stack kept in Python.
"""

from __future__ import annotations

import numpy as np


def normalize_mask(mask):
    """``None`` when every lane is set, ``False`` when none is, the array otherwise."""
    if isinstance(mask, np.ndarray) and mask.ndim:
        if not mask.any():
            return False
        if mask.all():
            return None
        return mask
    return None if bool(mask) else False


def mask_and(mask, cond):
    """Lanes active under ``mask`` for which ``cond`` (a bool scalar or array) holds."""
    if mask is False:
        return False
    if mask is None:
        return normalize_mask(cond)
    if not isinstance(cond, np.ndarray) or not cond.ndim:
        return mask if bool(cond) else False
    return normalize_mask(mask & cond)


def mask_and_not(mask, cond):
    """Lanes active under ``mask`` for which ``cond`` does not hold."""
    if isinstance(cond, np.ndarray) and cond.ndim:
        return mask_and(mask, ~cond)
    return mask_and(mask, not bool(cond))


def mask_or(a, b):
    """Union of two masks."""
    if a is None or b is None:
        return None
    if a is False:
        return b
    if b is False:
        return a
    return normalize_mask(a | b)


def is_uniform(value) -> bool:
    """True when a bool component is the same in every lane (a scalar)."""
    return not isinstance(value, np.ndarray) or not value.ndim


def blend(mask, new: tuple, old: tuple) -> tuple:
    """``new`` in the lanes of ``mask``, ``old`` elsewhere (componentwise)."""
    if mask is None:
        return new
    if mask is False:
        return old
    return tuple(n if n is o else np.where(mask, n, o) for n, o in zip(new, old, strict=False))


def select(index, options: list[tuple], default: tuple) -> tuple:
    """Per-lane choice ``options[index]`` (``default`` where the index is out of range)."""
    if is_uniform(index):
        # an int from an overflowing conversion or a NaN uniform is no index: the default, as out of range
        return options[int(index)] if np.isfinite(index) and 0 <= index < len(options) else default
    out = default
    for i, option in enumerate(options):
        out = tuple(np.where(index == i, o, d) for o, d in zip(option, out, strict=False))
    return out


class LoopState:
    """Lanes that left the current loop (or switch) by ``break`` or skipped to its next iteration by
    ``continue`` (a switch passes ``continue`` on to the enclosing loop)."""

    __slots__ = ("broken", "continued", "switch")

    def __init__(self, switch: bool = False) -> None:
        self.broken = False
        self.continued = False
        self.switch = switch


class Frame:
    """The state of one function invocation over all lanes.

    ``slots`` holds the local variables (indices assigned at compile time), ``globals`` the shared
    global variables and uniforms, ``mask`` the active lanes, ``ret`` the return value gathered so far
    and ``loops`` the enclosing loops' states. ``budget`` (loop iterations, nodes run in loops) is shared by
    all frames of one evaluation.
    """

    __slots__ = ("slots", "globals", "mask", "ret", "loops", "budget")

    def __init__(self, nslots: int, globals_: list, mask, budget: list) -> None:
        self.slots: list = [None] * nslots
        self.globals = globals_
        self.mask = mask
        self.ret = None
        self.loops: list[LoopState] = []
        self.budget = budget
