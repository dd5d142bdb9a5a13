"""The engine's routes: each module computes the albedo integral one way and says where it applies.

Generic (any model):

- :mod:`.quadrature` — method ``"quadrature"``: the lobe's hint or search, overflow scaling, a BSDF's two
  hemispheres, over the two routes below;
- :mod:`.hemisphere` — adaptive hemisphere quadrature in lobe-aligned coordinates;
- :mod:`.halfvector_generic` — the same method's half-vector route for isotropic lobes centred on the mirror
  direction, tried first.

Exact routes of particular lobes (each registered with :mod:`brdfnorm.engine.methods`):

- :mod:`.series` — Blinn-Phong by seed 002's hypergeometric form (``"series"``);
- :mod:`.azimuthal` — isotropic GGX/Beckmann with F = 1, the azimuth in closed form (``"azimuthal"``);
- :mod:`.halfvector`, :mod:`.halfvector_global` and :mod:`.microfacet` — microfacet lobes over the half vector
  (``"microfacet"``), and Kulla & Conty's compensation;
- :mod:`.dielectric` and :mod:`.dielectric_average` — rough dielectrics, reflection plus refraction
  (``"dielectric"``), and their hemispherical average E_avg as one 3-D integral;
- :mod:`.certified` — guaranteed enclosures by ball arithmetic (``"certified"``).

The closed forms of the seed articles (``"closed-form"``) live in :mod:`brdfnorm.models.closed_forms`, below the models
that declare them.
"""
