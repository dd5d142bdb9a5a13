"""Machinery the engine's routes share.

- :mod:`.tensor_rule` — lobe-aligned coordinates of the hemisphere and a global tensor rule with degree doubling
  on them (the hemisphere and half-vector routes try it before adaptive panels);
- :mod:`.kronrod` — the G7/K15 Gauss–Kronrod rule of every adaptive panel (the engine's and the tables' μ-average);
- :mod:`.grazing_panels` — the adaptive panels' starting grid at grazing views, and the ladder of panel edges;
- :mod:`.slope_coordinates` — the radial coordinates (pole, tail, cap) the half-vector routes run in over each
  microfacet slope distribution;
- :mod:`.rounding` — float64 rounding noise of an integrand near its peak, and the floor it sets on an estimate.
"""
