"""Exact reference values for an audit, each computed once and shared by every hypothesis that needs it.

Two base quantities per (μ, α, shadowing), both by brdfnorm's albedo engine
(:func:`brdfnorm.lut.table.compute_cells`, the same cells ``brdfnorm lut`` computes):

* E(μ, α) — the directional albedo of the lobe with its Fresnel off;
* F90(μ, α) = ∫ f cos (1 − V·H)⁵ dL — the split-sum bias (``lut --channels dfg``'s DFG_f90, by
  :func:`brdfnorm.lut.table.split_sum_models`).

Every Schlick channel meaning is a linear combination of them: 1 − E; DFG_f0 = E − F90 (since
(1 − (1 − c)⁵) + (1 − c)⁵ = 1); E_f0 = f0·E + (1 − f0)·F90 (Schlick's F = f0 + (1 − f0)(1 − c)⁵ with f90 = 1); and
E_avg(α) = 2∫₀¹ E μ dμ by :func:`brdfnorm.lut.table.average_over_mu`. The exact dielectric Fresnel factor is not
linear in anything tabulated, so E_dielectric(μ, α, η) = ∫ f cos F(η, V·H) dL is a third base quantity, computed
per (μ, α, η) by the lobe with ``fresnel=dielectric`` (E_f0_dielectric sets η = (1 + √f0)/(1 − √f0) per cell).
DFG_cloth is the albedo of another lobe, the white sheen distribution with Neubelt's visibility, at the same α
clamped to that lobe's range (:func:`brdfnorm.lut.cloth.cloth_model`, what ``lut --channels dfg`` tabulates).

Many hypotheses share their μ and α values (a flip of a symmetric sample set, a transposed square table, the same
grid with another clamp), so values are cached per (quantity, shadowing, μ, α, η) and only new ones are computed.
Each value keeps the engine's error estimate, which an audit adds to its tolerance. Under the compiled backend the
cells of each batch run on a thread per core (:mod:`brdfnorm.parallel.threads`; the values do not depend on it).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np

from ..lut.cloth import cloth_model
from ..lut.splitsum import DFG_F0, DFG_F90
from ..lut.table import average_over_mu, compute_cells, split_sum_models
from ..models.base import Model
from ..models.charlie import ALPHA_MIN as CLOTH_ALPHA_MIN
from ..models.microfacet import SHADOWING
from ..parallel.threads import local_threads
from ..parallel.threads import scope as threads_scope
from .conventions import (
    DIELECTRIC_MEANINGS,
    DIELECTRIC_SHADOWING,
    ETA,
    ETA_AXES,
    F0_POSITIONS,
    GLASS_MEANINGS,
    SCHLICK_F0,
)

#: Tolerances of the reference cells: E is cheap (closed-form-like routes) and F90 goes through a generic
#: quadrature (~3 ms a cell), so it is computed looser; both error estimates are carried.
RTOL = {"E": 1e-9, "F90": 1e-6, "E_avg": 1e-8, "E_dielectric": 1e-6, "DFG_cloth": 1e-7, "E_conductor": 1e-6,
        "E_glass": 1e-7, "R_glass": 1e-7, "T_glass": 1e-7}
#: The tolerance of values that only rank hypotheses (:meth:`Reference.ranking`): E of a lobe without a fast route
#: (the sheen: 36 ms a cell at 1e-9, 9 ms at 1e-6) is computed finely only for the few hypotheses kept.
RANK_RTOL = 1e-6


class Reference:
    """A cache of exact E, F90 (and E_avg) values of one model."""

    def __init__(self, model: Model) -> None:
        names = {p.name for p in model.parameters}
        if "alpha" not in names:
            raise_unsupported(model)
        if "fresnel" in names and str(model.params.get("fresnel")) != "none":
            from ..errors import ArgumentError

            raise ArgumentError("audits tabulate the lobe with its Fresnel off (Fresnel enters as the split-sum "
                                "channels and E_f0's Schlick axis); drop -p fresnel=...", where="model")
        self.model = model.with_params(fresnel="none") if "fresnel" in names else model
        # a rough dielectric whose refraction's shadowing is not given: that form is searched too
        self.refraction = ("refraction_shadowing" in names
                           and str(model.params.get("refraction_shadowing")) == "auto")
        # the shadowing forms searched: the lobe's own choices (Smith's two for ggx/beckmann, Kulla's and
        # Neubelt's for the sheen lobe), with the refraction's forms for a rough dielectric
        own = tuple(model.parameter("shadowing").choices) if "shadowing" in names else ()
        self.shadowings = DIELECTRIC_SHADOWING if self.refraction else (own or SHADOWING)
        self.store: dict[tuple, dict[tuple[float, float, float], tuple[float, float, float]]] = {}
        self.rank_rtol = 0.0
        self.computed = {"E": 0, "F90": 0, "E_avg": 0, "E_dielectric": 0, "DFG_cloth": 0, "E_conductor": 0,
                         "E_glass": 0}
        self.dielectric = "fresnel" in names and "dielectric" in model.parameter("fresnel").choices
        self.eta_max = float(model.parameter("eta").maximum) if self.dielectric else np.inf
        self.conductor = "fresnel" in names and "conductor" in model.parameter("fresnel").choices
        # a rough dielectric (reflection and transmission): a third table axis is its η, the channels R + T, R, T
        self.glass = "refraction_shadowing" in names
        self.third_kinds = ETA_AXES if self.glass else F0_POSITIONS
        # A model whose α is declared on a narrower range (a Mitsuba plugin: α ≥ 1e-3) is evaluated at the range's
        # end where a convention's grid or clamp reaches beyond it; for such a model the clamps below its minimum
        # give the same reference values, and the audit cannot tell them apart.
        declared = model.parameter("alpha")
        lowest = getattr(model, "alpha_min", None)  # a lobe whose alpha = 0 means something else (the sheen)
        self.alpha_range = (lowest if lowest is not None else declared.minimum if declared.minimum is not None
                            else -np.inf,
                            declared.maximum if declared.maximum is not None else np.inf)

    def _model(self, quantity: str, shadowing: str) -> Model:
        if quantity == "DFG_cloth":
            return cloth_model({"alpha": np.zeros(1)})[0]
        names = {p.name for p in self.model.parameters}
        shadowing, _, refraction = shadowing.partition("/refraction=")
        base = self.model.with_params(shadowing=shadowing) if "shadowing" in names else self.model
        if refraction and self.refraction:
            base = base.with_params(refraction_shadowing=refraction)
        if quantity == "F90":
            return split_sum_models(base)[0][DFG_F90]
        if quantity == "E_dielectric":
            return base.with_params(fresnel="dielectric")
        if quantity == "E_conductor":
            return base.with_params(fresnel="conductor")
        return base

    def values(self, quantity: str, shadowing: str, mu: np.ndarray, alpha: np.ndarray,
               eta: np.ndarray | float = 0.0, k: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """(value, error estimate) of ``quantity`` at the pairs (mu, alpha) — triples with ``eta`` for
        E_dielectric and E_conductor (with the extinction ``k``) — broadcast together."""
        with threads_scope(local_threads()):  # every batch of cells below on a thread per core
            return self._values(quantity, shadowing, mu, alpha, eta, k)

    def _values(self, quantity: str, shadowing: str, mu: np.ndarray, alpha: np.ndarray, eta: np.ndarray | float,
                k: float) -> tuple[np.ndarray, np.ndarray]:
        mu, alpha, eta = np.broadcast_arrays(np.asarray(mu, dtype=float),
                                             np.clip(np.asarray(alpha, dtype=float), *self.alpha_range),
                                             np.asarray(eta, dtype=float))
        if quantity in GLASS_MEANINGS:
            return self._glass(quantity, shadowing, mu, alpha, eta)
        table = self.store.setdefault((quantity, shadowing, float(k)), {})
        keys = list(zip(mu.ravel().tolist(), alpha.ravel().tolist(), eta.ravel().tolist(), strict=True))
        rtol = max(RTOL[quantity], self.rank_rtol)
        missing = sorted({key for key in keys if key not in table or table[key][2] > rtol})
        if missing:
            m = np.array([key[0] for key in missing])
            a = np.array([key[1] for key in missing])
            if quantity == "E_avg":
                value, error, _, _ = average_over_mu(self._model("E", shadowing), {"alpha": a}, rtol=rtol)
            else:
                cell_params = {"alpha": a}
                if quantity in ("E_dielectric", "E_conductor"):
                    cell_params["eta"] = np.array([key[2] for key in missing])
                if quantity == "E_conductor":
                    cell_params["k"] = np.full(len(missing), float(k))
                cells = compute_cells(self._model(quantity, shadowing), np.arccos(np.clip(m, -1.0, 1.0)),
                                      cell_params, rtol=rtol)
                value, error = cells.value[:, 0], cells.error[:, 0]
            self.computed[quantity] += len(missing)
            for key, v, e in zip(missing, value.tolist(), error.tolist(), strict=True):
                table[key] = (v, e, rtol)
        pairs = [table[key] for key in keys]
        value = np.array([p[0] for p in pairs]).reshape(mu.shape)
        error = np.array([p[1] for p in pairs]).reshape(mu.shape)
        return value, error

    def _glass(self, quantity: str, shadowing: str, mu: np.ndarray, alpha: np.ndarray,
               eta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """R + T, R or T of a rough dielectric at each cell's (μ, α, η): one quadrature gives the three (the
        error estimate is the total's, carried by each part)."""
        tables = {q: self.store.setdefault((q, shadowing, 0.0), {}) for q in GLASS_MEANINGS}
        keys = list(zip(mu.ravel().tolist(), alpha.ravel().tolist(), eta.ravel().tolist(), strict=True))
        rtol = max(RTOL["E_glass"], self.rank_rtol)
        table = tables[quantity]
        missing = sorted({key for key in keys if key not in table or table[key][2] > rtol})
        if missing:
            m, a, e = (np.array([key[i] for key in missing]) for i in range(3))
            cells = compute_cells(self._model("E", shadowing), np.arccos(np.clip(m, -1.0, 1.0)),
                                  {"alpha": a, "eta": e}, rtol=rtol)
            error = cells.error.reshape(len(missing), -1)[:, 0].tolist()
            parts = {"E_glass": cells.value.reshape(len(missing), -1)[:, 0],
                     "R_glass": cells.reflected.reshape(len(missing), -1)[:, 0],
                     "T_glass": cells.transmitted.reshape(len(missing), -1)[:, 0]}
            self.computed["E_glass"] += len(missing)
            for q, values in parts.items():
                for key, v, err in zip(missing, values.tolist(), error, strict=True):
                    tables[q][key] = (v, err, rtol)
        pairs = [table[key] for key in keys]
        return (np.array([p[0] for p in pairs]).reshape(mu.shape), np.array([p[1] for p in pairs]).reshape(mu.shape))

    @contextmanager
    def ranking(self) -> Iterator[None]:
        """Within: values computed to RANK_RTOL at most (stage 1 only ranks hypotheses, within a loose bound of
        1e-2; a value computed finer before is used as it is)."""
        self.rank_rtol = RANK_RTOL
        try:
            yield
        finally:
            self.rank_rtol = 0.0

    def meaning(self, meaning: str, shadowing: str, mu: np.ndarray | None, alpha: np.ndarray,
                f0: np.ndarray | None = None, eta: float = ETA,
                schlick_f0: float = SCHLICK_F0, k: float = 0.0,
                axis_eta: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(value, error estimate) of a channel meaning (conventions.MEANINGS) at the given coordinates; ``eta``
        is the index of refraction of an E_dielectric channel, ``schlick_f0`` the f0 of an E_schlick one."""
        if meaning in ("E_avg", "1-E_avg"):
            value, error = self.values("E_avg", shadowing, np.zeros_like(alpha), alpha)
            return (value if meaning == "E_avg" else 1.0 - value), error
        if meaning == "E_dielectric":
            return self.values("E_dielectric", shadowing, mu, alpha, eta)
        if meaning in GLASS_MEANINGS:  # a rough dielectric over an η axis
            return self.values(meaning, shadowing, mu, alpha, axis_eta)
        if meaning == "E_conductor":  # the exact conductor Fresnel factor at η + ik
            return self.values("E_conductor", shadowing, mu, alpha, eta, k)
        if meaning == "E_f0_dielectric":
            return self._f0_dielectric(shadowing, mu, alpha, f0)
        if meaning == "DFG_cloth":  # another lobe, whatever this one's shadowing: one cache for all
            return self.values("DFG_cloth", "", mu, np.clip(alpha, CLOTH_ALPHA_MIN, 1.0))
        E, e_err = self.values("E", shadowing, mu, alpha)
        if meaning == "E":
            return E, e_err
        if meaning == "1-E":
            return 1.0 - E, e_err
        F, f_err = self.values("F90", shadowing, mu, alpha)
        if meaning == DFG_F90:
            return F, f_err
        if meaning == DFG_F0:
            return E - F, e_err + f_err
        if meaning in ("E_f0", "E_schlick"):  # Schlick's F = f0 + (1 − f0)(1 − V·H)⁵, per cell or one f0
            f0 = np.broadcast_to(schlick_f0 if meaning == "E_schlick" else f0, E.shape)
            return f0 * E + (1.0 - f0) * F, f0 * e_err + (1.0 - f0) * f_err
        raise ValueError(meaning)

    def _f0_dielectric(self, shadowing: str, mu, alpha, f0) -> tuple[np.ndarray, np.ndarray]:
        """E_dielectric at η = (1 + √f0)/(1 − √f0) per cell (0 at f0 = 0: η = 1 reflects nothing). Beyond the
        lobe's largest η (f0 → 1 sends η to infinity) the value is bracketed: the dielectric reflectance grows
        with η at every angle and tends to 1, so E_dielectric lies between its value at the largest η and E; the
        midpoint is returned with half the bracket added to the error estimate."""
        mu, alpha, f0 = np.broadcast_arrays(mu, alpha, np.clip(np.asarray(f0, dtype=float), 0.0, 1.0))
        root = np.sqrt(f0)
        with np.errstate(divide="ignore"):
            eta = (1.0 + root) / (1.0 - root)
        beyond = (eta > self.eta_max) & (f0 < 1.0)  # f0 = 1 is the limit F = 1 itself: E
        value, error = self.values("E_dielectric", shadowing, mu, alpha, np.minimum(eta, self.eta_max))
        mirror = f0 >= 1.0
        if mirror.any():
            value, error = value.copy(), error.copy()
            value[mirror], error[mirror] = self.values("E", shadowing, mu[mirror], alpha[mirror])
        if beyond.any():
            E, e_err = self.values("E", shadowing, mu[beyond], alpha[beyond])
            value, error = value.copy(), error.copy()
            low = value[beyond]
            value[beyond] = 0.5 * (low + E)
            error[beyond] += e_err + 0.5 * np.abs(E - low)
        return value, error

    def supports(self, meaning: str) -> bool:
        """Whether this lobe can be audited for ``meaning`` (the dielectric Fresnel needs its ``fresnel``)."""
        if meaning == "E_conductor":
            return self.conductor
        if meaning in GLASS_MEANINGS:
            return self.glass
        return meaning not in DIELECTRIC_MEANINGS or self.dielectric

    @staticmethod
    def expensive(meaning: str) -> bool:
        """Meanings computed by a generic quadrature per cell (~1–3 ms a cell): the split-sum bias F90, the
        exact dielectric Fresnel and the cloth channel."""
        return meaning in (DFG_F0, DFG_F90, "E_f0", "E_schlick", "DFG_cloth", "E_conductor") + DIELECTRIC_MEANINGS \
            + GLASS_MEANINGS


def raise_unsupported(model: Model) -> None:
    from ..errors import ArgumentError

    raise ArgumentError(f"{model.name} has no 'alpha' parameter; audits cover microfacet lobes over (μ, α) "
                        "(ggx, beckmann, ...)", where="model")
