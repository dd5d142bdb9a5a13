"""Every limit the readers apply, in one place (issues 35, 40, 41): the same for every command that reads a table
(``lut``, ``fit --lut``, ``audit``, ``check``, the explorer) and for the Python API.

Each limit is checked from what a file *declares* (its size from ``stat``, a header's shape, a zip directory's
sizes, a PNG's IHDR, an EXR's data window and channel list, a C declaration's sizes, a count of the numbers in a
text made by a vectorized scan) before anything of that size is allocated or looped over; what passes is then
decoded by vectorized code (numpy), so that time and memory stay proportional to a legal table's size. A file
beyond a limit is refused with one error naming it and the limit.

The numbers were chosen so that the largest legal input decodes in well under 10 s and 1 GB on one core:

========================  ==============================================================================
limit                     what it bounds
========================  ==============================================================================
``MAX_ELEMENTS``          values in one table (every channel counted): 16 Mi, e.g. 2048² × 4 channels
``MAX_AXIS``              nodes along one dimension of an image (PNG width/height, EXR window): 65 536
``MAX_CHANNELS``          channels of one image (EXR parts' channels together; a PNG has at most 4): 16
``MAX_TEXT_NUMBERS``      numbers in one CSV or JSON file (parsed by C code): 4 Mi
``MAX_LITERAL_NUMBERS``   numbers in one source file (C/GLSL/HLSL/JS literals, scanned token by token): 1 Mi
``MAX_FILE_BYTES``        bytes of one file, by format (text formats less: a parsed number costs more)
``MAX_ARRAY_BYTES``       bytes an ``.npz``'s members declare, decompressed, together
``MAX_ZIP_DIRECTORY``     bytes of an ``.npz``'s central directory
``NPY_HEADER_BYTES``      bytes of one ``.npy`` header (numpy's own default)
``MAX_JSON_DEPTH``        nesting of a JSON document's arrays and objects
``MAX_XML_DEPTH``         nesting of a Mitsuba XML file's elements
``MAX_ERROR_TEXT``        characters of any text quoted in an error line (the middle elided)
``MAX_ERROR_LINE``        characters of a whole ``error:`` line of the command line: 1000
``MAX_AUDIT_VALUES``      values ``brdfnorm audit`` (and :func:`brdfnorm.audit.audit`) takes: 1 Mi
``MAX_AUDIT_GRID_AXES``   grid axes of an audited table (μ or θ, roughness, F0): 3
========================  ==============================================================================
"""

from __future__ import annotations

_MIB = 1024**2

#: Values in one table, every channel counted (2048² RGBA; a 128³ table with 8 channels).
MAX_ELEMENTS = 16 * _MIB
#: Nodes along one dimension of an image (a 1 × 16 M-pixel strip is no table).
MAX_AXIS = 65_536
#: Channels of one image, all parts together.
MAX_CHANNELS = 16
#: Numbers in one text file (1024² × 4 channels); counted by a vectorized scan before any list is built.
MAX_TEXT_NUMBERS = 4 * _MIB
#: Numbers in one source file of array literals (1024² or 512² × 4): the scanner's Python loop costs ~1 µs a token.
MAX_LITERAL_NUMBERS = 1024 * 1024
#: Bytes of one input file, by format.
MAX_FILE_BYTES = {"npz": 512 * _MIB, "exr": 512 * _MIB, "png": 256 * _MIB, "raw": 256 * _MIB,
                  "json": 64 * _MIB, "csv": 128 * _MIB, "text": 64 * _MIB}
#: Default for a file of no table format (a ``.brdf``, a checkpoint).
DEFAULT_FILE_BYTES = 256 * _MIB
#: Bytes of all the arrays an ``.npz`` declares, decompressed (a 1.5 MB archive can declare gigabytes).
MAX_ARRAY_BYTES = 512 * _MIB
#: Bytes of an ``.npz``'s central directory (brdfnorm writes a few hundred; zipfile makes one object per entry).
MAX_ZIP_DIRECTORY = _MIB
#: Bytes of one ``.npy`` header (numpy's own default limit).
NPY_HEADER_BYTES = 10_000
#: Nesting of a JSON document.
MAX_JSON_DEPTH = 64
#: Nesting of an XML file's elements (a Mitsuba BSDF nests a few levels).
MAX_XML_DEPTH = 64
#: Characters of a name or a cell quoted in an error line; longer ones keep their start and end.
MAX_ERROR_TEXT = 80
#: Characters of a whole error line (a path of thousands of characters is elided in the middle).
MAX_ERROR_LINE = 1000
#: Values an audit takes (checked from the shape, before any inference): each cell is compared against exact
#: values under every hypothesis of its convention, so the work grows with the table (1024², or 512² × 4).
MAX_AUDIT_VALUES = 1024 * 1024
#: Grid axes of an audited table (μ or θ, the roughness, F0); a fourth axis has no meaning there.
MAX_AUDIT_GRID_AXES = 3
