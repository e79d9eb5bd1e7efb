"""Drag of the bare test structure, from its velocity sweep (paper section 3 and 4).

The balance measures thrust minus the drag of the structure that holds the fan
(SPEC 4: ``force_n = thrust - D(V)``), so every thrust-table point is corrected
by ``+ D(V)``. ``D`` is fitted by least squares to the bare-structure sweep as
``D(V) = c1 V + c2 V^2``: no drag at rest, quadratic in the dynamic pressure plus
a linear term for what is not (a Reynolds-number effect on the rods). Each sweep
gets its own zero offset (the balance's tare), estimated with the fit and then
dropped, so a balance that does not read exactly zero at rest does not leak
into the thrust.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class DragModel:
    """``D(V) = c1 V + c2 V^2`` in N (V in m/s), with the fit's quality and range."""

    c1_n_per_m_s: float
    c2_n_per_m2_s2: float
    r2: float
    rmse_n: float
    n_samples: int
    airspeed_range_m_s: tuple[float, float]
    tares_n: tuple[float, ...]

    def drag_n(self, airspeed_m_s: NDArray[np.float64] | float) -> NDArray[np.float64] | float:
        """Structure drag in N at airspeed ``airspeed_m_s`` (m/s)."""
        v = np.asarray(airspeed_m_s, dtype=float)
        return self.c1_n_per_m_s * v + self.c2_n_per_m2_s2 * v * v

    def as_dict(self) -> dict[str, object]:
        return {
            "model": "D = c1 V + c2 V^2",
            "c1_n_per_m_s": self.c1_n_per_m_s,
            "c2_n_per_m2_s2": self.c2_n_per_m2_s2,
            "r2": self.r2,
            "rmse_n": self.rmse_n,
            "n_samples": self.n_samples,
            "airspeed_range_m_s": list(self.airspeed_range_m_s),
            "tares_n": list(self.tares_n),
            "drag_at_max_airspeed_n": float(self.drag_n(self.airspeed_range_m_s[1])),
        }


def fit_structure_drag(
    sweeps: Sequence[tuple[NDArray[np.float64], NDArray[np.float64]]],
) -> DragModel:
    """Least-squares structure drag from one or more ``(airspeed_m_s, force_n)`` sweeps.

    Parameters
    ----------
    sweeps : sequence of (ndarray, ndarray)
        Per sweep, airspeed in m/s and the balance force in N (cleaned), same length.

    Returns
    -------
    DragModel
        ``force = tare_j - (c1 V + c2 V^2)`` fitted jointly over all samples.
    """
    m = len(sweeps)
    blocks, targets = [], []
    for j, (v, f) in enumerate(sweeps):
        v = np.asarray(v, dtype=float)
        tare = np.zeros((v.size, m))
        tare[:, j] = 1.0
        blocks.append(np.column_stack([tare, v, v * v]))
        targets.append(-np.asarray(f, dtype=float))  # -force = D(V) - tare
    design = np.vstack(blocks)
    target = np.concatenate(targets)
    coef, *_ = np.linalg.lstsq(design, target, rcond=None)
    residual = target - design @ coef
    sse = float(residual @ residual)
    sst = float(np.sum((target - target.mean()) ** 2))
    dof = max(target.size - design.shape[1], 1)
    speeds = np.concatenate([np.asarray(v, dtype=float) for v, _ in sweeps])
    return DragModel(
        c1_n_per_m_s=float(coef[m]),
        c2_n_per_m2_s2=float(coef[m + 1]),
        r2=1.0 - sse / sst if sst > 0 else float("nan"),
        rmse_n=float(np.sqrt(sse / dof)),
        n_samples=int(target.size),
        airspeed_range_m_s=(float(speeds.min()), float(speeds.max())),
        tares_n=tuple(float(-c) for c in coef[:m]),
    )
