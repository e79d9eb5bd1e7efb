"""flightlog's figure: flown electrical power against airspeed, samples and bins.

Draws a :class:`tuflexperf.analysis.flown.FlownResult` (and the model's power per bin where a
comparison is given); computes nothing of its own.
"""

from __future__ import annotations

import io
from typing import Any

import numpy as np


def flight_png(flown: Any, comparison: Any, title: str) -> bytes:
    """PNG bytes (150 dpi): airborne samples as a scatter, bin means with their spread."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.0, 4.6))
    s = flown.series
    if s:
        air = (s["airborne"] > 0) & np.isfinite(s["power_w"])
        ax.scatter(s["airspeed_m_s"][air], s["power_w"][air], s=3, alpha=0.25, color="0.5",
                   label="airborne samples")
    if flown.bins:
        v = np.array([b.airspeed_m_s for b in flown.bins])
        p = np.array([b.power_w for b in flown.bins])
        sd = np.array([b.power_std_w for b in flown.bins])
        ax.errorbar(v, p, yerr=sd, fmt="o", color="C0", capsize=3,
                    label="flown, 1 m/s bins (mean +- sd)")
    if flown.level_bins:
        ax.plot([b.airspeed_m_s for b in flown.level_bins],
                [b.power_w for b in flown.level_bins], "s", mfc="none", color="C2",
                label="flown, level flight")
    if comparison is not None and comparison.bins:
        ax.plot([b["airspeed_m_s"] for b in comparison.bins],
                [b["predicted_power_w"] for b in comparison.bins], "D-", color="C3",
                label="model")
    ax.set_xlabel(f"{flown.airspeed_kind} airspeed (m/s)")
    ax.set_ylabel("electrical power (W)")
    ax.set_title(f"{title}: airborne {flown.window.duration_s:.0f} s", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    buffer = io.BytesIO()
    from tuflexperf.io.files import FLIGHT_PNG_SOFTWARE

    # marks the PNG as flightlog's: a later flightlog may replace it (SPEC 5), nothing else
    fig.savefig(buffer, format="png", dpi=150, metadata={"Software": FLIGHT_PNG_SOFTWARE})
    plt.close(fig)
    return buffer.getvalue()
