"""Glauert blockage correction of the tunnel airspeed (paper eq. 5, SPEC 3).

``V'/V = 1 - (T / (rho C V^2)) / (2 sqrt(1 + 2 tau))`` with
``tau = T / (rho A V^2)``, ``A`` the fan's and ``C`` the tunnel's cross-section
(Glauert, as recommended for propeller tests by Fitzgerald 2007, the paper's
ref. [13]). The paper found it under 4 % and 1 m/s at 30 m/s and neglected it;
``tuflexperf fit`` reports it per point and applies it only with ``--glauert``.

The correction describes a fan in a moving stream: at rest (``V`` below
:data:`MIN_AIRSPEED_M_S`) there is no stream to correct, and where
``1 + 2 tau <= 0`` (a windmilling fan's drag larger than the stream can give) the
formula has no real value; both give ``nan`` (no correction).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

MIN_AIRSPEED_M_S = 1.0


def glauert_ratio(
    thrust_n: ArrayLike,
    airspeed_m_s: ArrayLike,
    density_kg_m3: float,
    fan_area_m2: float,
    tunnel_area_m2: float,
) -> NDArray[np.float64]:
    """Corrected over measured airspeed ``V'/V`` (paper eq. 5); ``nan`` where not defined."""
    thrust = np.asarray(thrust_n, dtype=float)
    v = np.asarray(airspeed_m_s, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        q = density_kg_m3 * v * v
        tau = thrust / (q * fan_area_m2)
        root = np.sqrt(1.0 + 2.0 * tau)
        ratio = 1.0 - (thrust / (q * tunnel_area_m2)) / (2.0 * root)
    valid = (v >= MIN_AIRSPEED_M_S) & (1.0 + 2.0 * tau > 0) & np.isfinite(ratio)
    return np.where(valid, ratio, np.nan)
