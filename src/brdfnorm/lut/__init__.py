"""``brdfnorm.lut``: energy-compensation lookup tables — computed (:mod:`.table`), written and read back in the
formats engines load (:mod:`.formats`).

>>> import brdfnorm as bn
>>> from brdfnorm import lut
>>> table = lut.compute(bn.load("blinn-phong"), {"mu": [0.25, 0.5, 1.0], "n": [4.0, 64.0]}, rtol=1e-8)
>>> sorted(table), list(table.axes)
(['1-E', 'E', 'E_avg', 'E_avg_error', 'E_error'], ['mu', 'n'])
"""

from .formats import FORMATS, dumps, load, save
from .table import Lut, compute, compute_cells, grid_values

__all__ = ["FORMATS", "Lut", "compute", "compute_cells", "dumps", "grid_values", "load", "save"]
