"""Constants several analyses share: the battery ratings' rules, the RK4 and climb-scan resolution.

They live below every analysis so that the single-case problems (mission, pack limits) and
the batch evaluators read the same numbers without importing one another.
"""

from __future__ import annotations

from tuflexperf.models.battery import SECONDS_PER_HOUR as SECONDS_PER_HOUR  # one definition

RATING_SEGMENT_S = 30.0  # any stretch of the flight this long keeps its mean current within it
BURST_OVER_CONTINUOUS = 2.0  # a LiPo's burst rating, the usual twice the continuous one
STEPS = 64  # RK4 steps per segment: the states are smooth, 64 steps give ~1e-9 relative
# the climb's airspeed scan, single case and batch alike: up to 8 x the stall speed, 4001 points
MAX_SPEED_OVER_STALL = 8.0
SPEED_GRID_POINTS = 4001
