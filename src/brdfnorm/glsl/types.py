"""GLSL types of the supported subset and the implicit conversions between them.

Follows the OpenGL Shading Language 4.10 specification, §4.1 (basic types), §4.1.10 (implicit
conversions: int → uint → float, componentwise for vectors) and §5.4 (constructors).

Every value is held at run time as a flat tuple of components, column-major for matrices and
element after element for arrays, each component a Python scalar or a float64 / bool numpy array over
the batch of direction pairs. Integers are held as float64 holding integral values (exact up to 2^53),
so an int → float conversion costs nothing at run time; integer results wrap to 32 bits as GLSL's do
(``-1u`` is 4294967295; see :func:`.compiler.components.wrap`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

SCALARS = ("bool", "int", "uint", "float")
_PREFIX = {"bool": "b", "int": "i", "uint": "u", "float": ""}
_BY_PREFIX = {"b": "bool", "i": "int", "u": "uint", "": "float"}


@dataclass(frozen=True)
class Type:
    """A GLSL type: a scalar, vector or matrix of ``base``, optionally an array of ``length`` of them.

    ``rows`` is the vector size (components per column), ``cols`` the number of matrix columns.
    """

    base: str
    rows: int = 1
    cols: int = 1
    length: int | None = None

    @property
    def is_array(self) -> bool:
        """An array type."""
        return self.length is not None

    @property
    def element(self) -> Type:
        """The element type of an array."""
        return Type(self.base, self.rows, self.cols)

    @property
    def is_scalar(self) -> bool:
        """A single bool, int, uint or float."""
        return self.rows == 1 and self.cols == 1 and self.length is None and self.base != "void"

    @property
    def is_vector(self) -> bool:
        """A vector of 2 to 4 components."""
        return self.rows > 1 and self.cols == 1 and self.length is None

    @property
    def is_matrix(self) -> bool:
        """A float matrix."""
        return self.cols > 1 and self.length is None

    @property
    def is_numeric(self) -> bool:
        """An int, uint or float scalar, vector or matrix (not an array)."""
        return self.base in ("int", "uint", "float") and self.length is None

    @property
    def is_integer(self) -> bool:
        """Of base type int or uint."""
        return self.base in ("int", "uint")

    @property
    def size(self) -> int:
        """Number of flat components of a value of this type."""
        return self.rows * self.cols * (self.length or 1)

    def with_base(self, base: str) -> Type:
        """The same shape with another base type."""
        return Type(base, self.rows, self.cols, self.length)

    def column(self) -> Type:
        """The type of one column of a matrix (or of one component of a vector)."""
        return Type(self.base, self.rows) if self.cols > 1 else Type(self.base)

    def __str__(self) -> str:
        if self.base == "void":
            name = "void"
        elif self.cols > 1:
            name = f"mat{self.cols}" if self.cols == self.rows else f"mat{self.cols}x{self.rows}"
        elif self.rows > 1:
            name = f"{_PREFIX[self.base]}vec{self.rows}"
        else:
            name = self.base
        return name if self.length is None else f"{name}[{self.length}]"


VOID = Type("void", 0, 0)
BOOL = Type("bool")
INT = Type("int")
UINT = Type("uint")
FLOAT = Type("float")
VEC3 = Type("float", 3)

_VEC = re.compile(r"^([biu]?)vec([234])$")
_MAT = re.compile(r"^mat([234])(?:x([234]))?$")

# Opaque and otherwise unsupported type names, mapped to the feature they belong to (for the error).
_UNSUPPORTED = re.compile(
    r"^(?:[iu]?(?:sampler|image|texture)\w*|atomic_uint|subpassInput\w*|double|dvec[234]|dmat[234](?:x[234])?"
    r"|u?int64_t|i64vec[234]|u64vec[234]|float16_t|f16vec[234])$"
)


def parse_type_name(name: str) -> Type | None:
    """The type named ``name`` (``vec3``, ``mat2x3``, ``bool``, ...), or None if it is not a type name."""
    if name in SCALARS or name == "void":
        return VOID if name == "void" else Type(name)
    match = _VEC.match(name)
    if match:
        return Type(_BY_PREFIX[match.group(1)], int(match.group(2)))
    match = _MAT.match(name)
    if match:
        cols = int(match.group(1))
        return Type("float", int(match.group(2) or cols), cols)
    return None


def unsupported_type_feature(name: str) -> str | None:
    """A description of the unsupported feature a type name belongs to, or None."""
    if not _UNSUPPORTED.match(name):
        return None
    if "sampler" in name or name.startswith(("texture", "itexture", "utexture")):
        return f"samplers and textures ({name})"
    if "image" in name:
        return f"images ({name})"
    if name == "atomic_uint":
        return "atomic counters (atomic_uint)"
    return f"the type {name} (only bool, int, uint, float and their vectors and float matrices)"


_RANK = {"int": 0, "uint": 1, "float": 2}


def converts(src: Type, dst: Type) -> bool:
    """True when ``src`` converts implicitly to ``dst`` (GLSL 4.10 §4.1.10), identity included."""
    if src == dst:
        return True
    if src.rows != dst.rows or src.cols != dst.cols or src.length != dst.length:
        return False
    if src.base not in _RANK or dst.base not in _RANK:
        return False
    return _RANK[src.base] < _RANK[dst.base]
