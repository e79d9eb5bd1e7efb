"""The thrust model's confidence band over airspeed, from the fit's covariance.

At throttle ``x`` and airspeed ``V`` the poly22 thrust is ``g(x, V)^T p`` with
``g = (1, x, V, x^2, x V, V^2)``; its variance from the coefficients' covariance ``C`` is
``g^T C g`` (delta method, exact for a model linear in its coefficients). Beyond the
tested airspeed range the leave-one-airspeed-out error ``extrapolation_sd_n`` is added in
quadrature (the same error model the probabilistic ``check`` samples). The band is
``T +- z sd`` with ``z = 1.96`` for 95 %.

References
----------
Montgomery & Runger, *Applied Statistics and Probability for Engineers*, 12-4 (confidence
interval on the mean response); paper section 4 (the poly22 model).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tuflexperf.models.thrust import Engine, Propulsion, engine_thrust_n, outside_tested_range

Z_95 = 1.959963984540054


@dataclass(frozen=True)
class ThrustBand:
    """Thrust of one engine over airspeed with its standard deviation and 95 % band [N]."""

    engine: str
    throttle: float
    airspeed_m_s: NDArray[np.float64] = field(repr=False)
    thrust_n: NDArray[np.float64] = field(repr=False)
    sd_n: NDArray[np.float64] = field(repr=False)
    low_n: NDArray[np.float64] = field(repr=False)
    high_n: NDArray[np.float64] = field(repr=False)
    extrapolated: NDArray[np.bool_] = field(repr=False)
    has_covariance: bool = True

    def to_dict(self) -> dict[str, Any]:
        return {
            "engine": self.engine,
            "throttle": self.throttle,
            "airspeed_m_s": self.airspeed_m_s.tolist(),
            "thrust_n": self.thrust_n.tolist(),
            "sd_n": self.sd_n.tolist(),
            "low_n": self.low_n.tolist(),
            "high_n": self.high_n.tolist(),
            "extrapolated": self.extrapolated.tolist(),
            "has_covariance": self.has_covariance,
        }


def extrapolation_weight(propulsion: Propulsion, airspeed_m_s: Any) -> Any:
    """1 beyond the tested airspeed range (above or below), 0 inside it."""
    return outside_tested_range(propulsion, np.asarray(airspeed_m_s, dtype=float)).astype(float)


def thrust_sd_n(
    engine: Engine,
    throttle: ArrayLike,
    airspeed_m_s: ArrayLike,
    extrapolation_weight: ArrayLike = 0.0,
) -> NDArray[np.float64]:
    """Standard deviation [N] of one engine's thrust at ``throttle`` [fraction], ``V`` [m/s].

    ``sqrt(g^T C g + (w extrapolation_sd_n)^2)``; 0 where the engine has no covariance.

    References
    ----------
    Montgomery & Runger, *Applied Statistics and Probability for Engineers*, 12-4.
    """
    x = np.asarray(throttle, dtype=float) * engine.throttle_scale
    v = np.asarray(airspeed_m_s, dtype=float)
    x, v = np.broadcast_arrays(x, v)
    variance = np.zeros(x.shape)
    if engine.covariance is not None:
        g = np.stack([np.ones_like(x), x, v, x * x, x * v, v * v], axis=-1)
        c = np.asarray(engine.covariance, dtype=float)
        variance = variance + np.einsum("...i,ij,...j->...", g, c, g)
    if engine.extrapolation_sd_n is not None:
        w = np.asarray(extrapolation_weight, dtype=float)
        variance = variance + (w * engine.extrapolation_sd_n) ** 2
    return np.sqrt(np.maximum(variance, 0.0))


def thrust_band(
    propulsion: Propulsion,
    engine_index: int = 0,
    throttle: float = 1.0,
    airspeed_m_s: ArrayLike | None = None,
    z: float = Z_95,
) -> ThrustBand:
    """Thrust [N] of engine ``engine_index`` at ``throttle`` over airspeed with its band.

    Parameters
    ----------
    propulsion : Propulsion
        The model, with per-engine ``covariance`` / ``extrapolation_sd_n`` where known.
    engine_index : int
        Which engine.
    throttle : float
        Throttle [fraction].
    airspeed_m_s : array, optional
        Airspeeds [m/s]; default 0 to 1.5 x the highest tested airspeed, 0.5 m/s apart.
    z : float
        Half-width in standard deviations (1.96: 95 %).

    Returns
    -------
    ThrustBand
        As measured (no density scaling): the band of the model itself.

    References
    ----------
    Montgomery & Runger, 12-4; paper section 4.
    """
    engine = propulsion.engines[engine_index]
    if airspeed_m_s is None:
        top = 1.5 * propulsion.tested_airspeed_m_s[1]
        airspeed_m_s = np.linspace(0.0, top, int(round(top / 0.5)) + 1)
    v = np.asarray(airspeed_m_s, dtype=float)
    thrust = np.asarray(engine_thrust_n(engine, throttle, v), dtype=float) * np.ones_like(v)
    weight = extrapolation_weight(propulsion, v)
    sd = thrust_sd_n(engine, throttle, v, weight)
    return ThrustBand(
        engine=engine.name,
        throttle=float(throttle),
        airspeed_m_s=v,
        thrust_n=thrust,
        sd_n=sd,
        low_n=thrust - z * sd,
        high_n=thrust + z * sd,
        extrapolated=weight > 0.5,
        has_covariance=engine.covariance is not None,
    )
