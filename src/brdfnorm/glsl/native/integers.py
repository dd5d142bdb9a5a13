"""GLSL's integer bit operators for generated native modules, on 32-bit values held as float64.

The same results as the numpy backend's :mod:`..compiler.components` (``int_mod``, ``bitwise``, ``shift``), which
work on int64 arrays: ``%`` as Mesa llvmpipe evaluates it (an unsigned 32-bit remainder, ``x % 0`` all bits
set), ``&``, ``|``, ``^`` on the two's complement patterns, ``<<`` and ``>>`` (arithmetic for negative values)
by the low 5 bits of the count. The callers wrap the result to int or uint as GLSL's arithmetic does.

:data:`SOURCE` is written into every generated module (fixed text of brdfnorm's, nothing of a shader's), so that
Numba caches the helpers a shader uses next to it, in the per-user cache; unused ones are never compiled.
"""

from __future__ import annotations

SOURCE = '''
_MASK = 0xFFFFFFFF
_SIGN = 2**31
_WORD = 2**32


@njit(cache=True, nogil=True)
def _signed(r: int) -> float:
    return float(r - _WORD if r >= _SIGN else r)


@njit(cache=True, nogil=True)
def int_mod(a: float, b: float) -> float:
    """Integer ``%``: an unsigned 32-bit remainder; ``x % 0`` has all bits set."""
    ua, ub = int(a) % _WORD, int(b) % _WORD
    return _signed(_MASK if ub == 0 else ua % ub)


@njit(cache=True, nogil=True)
def int_and(a: float, b: float) -> float:
    """``&`` of the 32-bit patterns."""
    return _signed((int(a) & int(b)) & _MASK)


@njit(cache=True, nogil=True)
def int_or(a: float, b: float) -> float:
    """``|`` of the 32-bit patterns."""
    return _signed((int(a) | int(b)) & _MASK)


@njit(cache=True, nogil=True)
def int_xor(a: float, b: float) -> float:
    """``^`` of the 32-bit patterns."""
    return _signed((int(a) ^ int(b)) & _MASK)


@njit(cache=True, nogil=True)
def int_shl(a: float, b: float) -> float:
    """``<<`` by the low 5 bits of the count."""
    return _signed(((int(a) & _MASK) << (int(b) & 31)) & _MASK)


@njit(cache=True, nogil=True)
def int_shr(a: float, b: float) -> float:
    """``>>`` by the low 5 bits of the count, arithmetic (the sign bit copied) for a negative value."""
    x = int(a) & _MASK
    if x >= _SIGN:
        x -= _WORD
    return _signed((x >> (int(b) & 31)) & _MASK)
'''
