"""The discharge runs' measured power as a reading of the case (see :mod:`readings`).

Work in progress on branch ``power``: until it lands this provider makes no reading.
"""

from __future__ import annotations

from tuflexperf.analysis.readings import Reading
from tuflexperf.io.case import Case


def measured_power_readings(case: Case) -> tuple[Reading, ...]:
    """The case flown on the measured power correction law, when the battery file has one."""
    return ()
