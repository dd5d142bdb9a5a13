"""``brdfnorm explore``: BRDF Explorer's loop in the browser — sliders, lobe plots, the albedo curve — with
brdfnorm's exact numbers and their error bars, and the ``.brdf`` file reloaded whenever it is saved.

Disney's BRDF Explorer (Burley et al., 2012) plots an albedo estimated by float32 Monte Carlo; here every curve
and readout is :func:`brdfnorm.albedo` / :func:`brdfnorm.normalize` with its error estimate, and the energy
verdict is :func:`brdfnorm.check.check`'s, coarse first and refined in the background (:mod:`.compute`), served by
Starlette + uvicorn (:mod:`.server`) to a page drawn with plotly.js's basic bundle (vendored beside the page, no
network), for the models in a fixed table (:mod:`.catalog`).
"""

from __future__ import annotations

from .catalog import Catalog
from .compute import evaluate_view, fit_factor, format_with_error
from .server import background, bind, serve, url_of

__all__ = ["Catalog", "background", "bind", "evaluate_view", "fit_factor", "format_with_error", "serve", "url_of"]
