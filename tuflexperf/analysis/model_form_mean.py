"""The sampled rows' mean model-form error: the residual surface's posterior, per engine.

Where the propulsion file holds ``lack_of_fit.residuals`` and the case draws the model form,
each sampled row's thrust adds the posterior mean of a Gaussian process over them
(:mod:`tuflexperf.models.residual_surface`); the deterministic check adds none.
"""

from __future__ import annotations

from typing import Any

from tuflexperf.analysis.cache import ByObject
from tuflexperf.io.case import Case
from tuflexperf.models.residual_surface import ResidualSurface, residual_surface

_SURFACES: ByObject[tuple[ResidualSurface | None, ...]] = ByObject()


def residual_surfaces(propulsion: Any) -> tuple[ResidualSurface | None, ...]:
    """Per engine, the posterior of its residual surface, None without one in the file
    (:func:`~tuflexperf.models.residual_surface.residual_surface`; built once per propulsion).
    """
    def build() -> tuple[ResidualSurface | None, ...]:
        return tuple(
            None if e.model_form_residuals is None or not e.model_form_sd_n
            else residual_surface(e.model_form_residuals, e.throttle_scale,
                                  propulsion.tested_airspeed_m_s, e.model_form_sd_n,
                                  e.model_form_noise_n or 0.0)
            for e in propulsion.engines)
    return _SURFACES.get(propulsion, build)


def centres_model_form(case: Case) -> bool:
    """Whether the case's samples draw the model form (its switches) about a residual
    surface of the file's: their rows then add its mean (:func:`residual_surfaces`)."""
    block = case.uncertainty
    switches = None if block is None else block.propulsion
    if switches is not None and not (switches.model_form and switches.residual):
        return False
    return any(s is not None for s in residual_surfaces(case.propulsion))
