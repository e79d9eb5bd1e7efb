"""The measured power correction: the discharge runs' measured over the modelled power.

A discharge run holds one throttle and airspeed until the cut-off and logs the pack's
``V I``; the power model (the propulsion's power surface of the run's fan, else the battery
file's fan-power law) gives a power there too. Their ratio over the runs is fitted by
``fit`` (:func:`tuflexperf.reduction.battery.fit_power_correction`) as

``r(x, V) = c0 + c_x x + c_V V``

(the throttle term only with runs at two throttles or more, the airspeed term only with
runs at two airspeeds or more), and flown as ``P_measured(x, V) = r(x, V) P_model(x, V)``.
Outside the runs' throttle and airspeed span the law is held at the nearest tested edge
(a line through two runs, continued, could reach any value; the edge is what was measured).

Plain arithmetic and :mod:`tuflexperf.models._math` only: floats, numpy arrays and CasADi
symbols alike.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from tuflexperf.models._math import Vectorizable, fmax, fmin


@dataclass(frozen=True)
class PowerCorrection:
    """Measured over modelled electrical power, ``r = c0 + c_x x + c_V V`` [-], held at the
    edges of the tested span.

    Attributes
    ----------
    constant : float
        ``c0`` [-].
    per_throttle : float
        ``c_x`` [1/throttle fraction]; 0 when the runs held one throttle.
    per_airspeed_s_m : float
        ``c_V`` [s/m]; 0 when the runs held one airspeed.
    throttle_span : tuple[float, float]
        Least and greatest throttle of the runs [-].
    airspeed_span_m_s : tuple[float, float]
        Least and greatest airspeed of the runs [m/s].
    """

    constant: float
    per_throttle: float
    per_airspeed_s_m: float
    throttle_span: tuple[float, float]
    airspeed_span_m_s: tuple[float, float]

    def ratio(self, throttle: Vectorizable, airspeed_m_s: Vectorizable) -> Vectorizable:
        """``r(x, V)`` [-] at ``throttle`` [-] and true airspeed [m/s], held at the span's edges.

        References
        ----------
        Issue 43 item 2 (the measured discharge power as a correction law over throttle and
        airspeed).
        """
        x = fmin(fmax(throttle, self.throttle_span[0]), self.throttle_span[1])
        v = fmin(fmax(airspeed_m_s, self.airspeed_span_m_s[0]), self.airspeed_span_m_s[1])
        return self.constant + self.per_throttle * x + self.per_airspeed_s_m * v

    def extrapolates(self, throttle: float, airspeed_m_s: float,
                     source: str = "the runs'") -> list[str]:
        """What of ``(throttle, airspeed_m_s)`` lies outside the tested span, in words
        (``source`` names whose span it is)."""
        said: list[str] = []
        (x0, x1), (v0, v1) = self.throttle_span, self.airspeed_span_m_s
        if not x0 - 1e-9 <= throttle <= x1 + 1e-9:
            said.append(f"throttle {throttle:.2f} outside {source} {_span(x0, x1, '.2f')}")
        if not v0 - 0.05 <= airspeed_m_s <= v1 + 0.05:
            said.append(f"{airspeed_m_s:.1f} m/s outside {source} "
                        f"{_span(v0, v1, '.1f')} m/s")
        return said

    def to_dict(self) -> dict[str, Any]:
        return {"constant": self.constant, "per_throttle": self.per_throttle,
                "per_airspeed_s_m": self.per_airspeed_s_m,
                "throttle_span": list(self.throttle_span),
                "airspeed_span_m_s": list(self.airspeed_span_m_s)}


def _span(low: float, high: float, fmt: str) -> str:
    low_text, high_text = format(low, fmt), format(high, fmt)
    return low_text if low_text == high_text else f"{low_text}-{high_text}"


def corrected(power_w: Vectorizable, correction: PowerCorrection | None, throttle: Vectorizable,
              airspeed_m_s: Vectorizable) -> Vectorizable:
    """``power_w`` [W] times the correction's ratio at ``(throttle, airspeed_m_s)``, or as
    it is without one: the one place the measured power enters every power model."""
    if correction is None or power_w is None:
        return power_w
    return power_w * correction.ratio(throttle, airspeed_m_s)
