"""Reconstruct the shipped TU-Flex propulsion model (data/tuflex/propulsion.yaml).

The paper publishes, per fan, the full-throttle thrust at 0, 30 and 40 m/s
(section 4). At full throttle the poly22 reduces to ``a + b v + c v^2`` with
``a = p00 + p10 + p20``, ``b = p01 + p11`` and ``c = p02``: three published
points fix ``a, b, c`` exactly (derived). The split of ``a`` and ``b`` between
the throttle terms is not published; it is estimated so the surface is
physical elsewhere:

* ``p00 = 0``: no thrust at idle and rest;
* ``p10 = 0.3 a``, ``p20 = 0.7 a``: static thrust rising roughly with throttle
  squared (thrust ~ rpm^2, rpm ~ throttle), as fan data show;
* ``p01 = -0.15 N/(m/s)``: a windmilling fan at zero throttle is a drag of a few
  newtons at cruise speeds (about 0.6 of the 93 mm disk's dynamic pressure area
  at 45 m/s), and ``T(0, v)`` keeps falling over the whole 0-45 m/s envelope.

Run: ``python scripts/reconstruct_propulsion.py`` (rewrites the file).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

# Paper section 4 / SPEC 6: full-throttle thrust in N at 0, 30 and 40 m/s.
PUBLISHED_FULL_THROTTLE_N = {
    "EDF1": (55.12, 40.02, 35.26),
    "EDF2": (55.41, 41.76, 37.76),
}
AIRSPEEDS_M_S = (0.0, 30.0, 40.0)
P10_SHARE = 0.3
P01_N_PER_M_S = -0.15

OUT = Path(__file__).resolve().parent.parent / "data" / "tuflex" / "propulsion.yaml"


def coefficients(full_throttle_n: tuple[float, float, float]) -> dict[str, float]:
    vandermonde = np.array([[1.0, v, v * v] for v in AIRSPEEDS_M_S])
    a, b, c = np.linalg.solve(vandermonde, np.array(full_throttle_n))
    return {
        "p00": 0.0,
        "p10": P10_SHARE * a,
        "p01": P01_N_PER_M_S,
        "p20": (1.0 - P10_SHARE) * a,
        "p11": b - P01_N_PER_M_S,
        "p02": c,
    }


def render() -> str:
    lines = [
        "# Reconstructed TU-Flex propulsion model; written by scripts/reconstruct_propulsion.py.",
        "# Provenance of every number: data/README.md (published / derived / estimated).",
        "name: Schuebeler DS-51-DIA HST",
        "model: poly22      # T = p00 + p10 x + p01 v + p20 x^2 + p11 x v + p02 v^2 (x fraction, v m/s)",
        "tested_airspeed_m_s: [0, 30]   # published: tunnel limit 30 m/s",
        "delay_s: 0.05                  # published: sine sweep, section 4",
        "# no reference_density_kg_m3: the paper used thrust 'with uncorrected atmosphere'",
        "engines:",
    ]
    for name, points in PUBLISHED_FULL_THROTTLE_N.items():
        c = coefficients(points)
        lines.append(f"  - name: {name}")
        lines.append("    coefficients:")
        for term in ("p00", "p10", "p01", "p20", "p11", "p02"):
            lines.append(f"      {term}: {c[term]:.10g}")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(render(), encoding="utf-8")
    print(f"wrote {OUT}")
