"""The one integration machinery the engine's routes share (no route re-implements it).

- :mod:`.result` — :class:`~.result.RouteResult`, what every route and rule returns;
- :mod:`.panels` — the one panel pool of the adaptive 2-D routes, the K15/G7 rule pair on a panel, and the
  rectangle driver of the half-vector and dielectric routes;
- :mod:`.confirmation` — the confirmation of a case's panels on new nodes before it stops (within tolerance, out of
  budget, stalled), shared by the hemisphere route and the rectangle driver: the check on halves with its corner
  check, the budget stop that keeps the confirmation's cost, the stall check;
- :mod:`.kronrod` — the G7/K15 Gauss–Kronrod rule of every adaptive panel (the engine's and the tables' μ-average);
- :mod:`.kinks` — the Gauss–Lobatto edge nodes of the panels' checks and the floor under a panel that converges
  algebraically;
- :mod:`.rounding` — float64 rounding noise of an integrand near its peak, and the floor it sets on an estimate;
- :mod:`.grazing_panels` — the adaptive panels' starting grid at grazing views, and the ladder of panel edges;
- :mod:`.interval` — the 1-D adaptive integration (the 1-D routes, the claims, the tables' μ-average);
- :mod:`.tensor_rule` — a global tensor rule with degree doubling, the interface of the grids it runs on, and the
  hemisphere's lobe-aligned coordinates as one (the hemisphere and half-vector routes try it before adaptive
  panels); :mod:`.global_driver` — its one levels loop; :mod:`.hemisphere_global` — the hemisphere route's entry
  point to it;
- :mod:`.grid_estimate` — the lobe-aligned global rule's estimate of its reported grid, extrapolated where its
  convergence is shown to be geometric, and (every grid) the coarser difference kept after a sudden agreement;
- :mod:`.slope_coordinates` — the radial coordinates (pole, tail, cap) the half-vector routes run in over each
  microfacet slope distribution;
- :mod:`.directions` — random hemisphere directions and rotations about the normal;
- :mod:`.lobe_search` — the generic route's search for a lobe's main peak and every separated peak besides it;
  :mod:`.partition` — a case with several peaks integrated as one sub-case per peak.
"""
