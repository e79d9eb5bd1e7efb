"""Every reading of a case's disputed evidence, from the providers that make them.

The providers sit beside the analyses they bear on; this module only gathers them, so
that the registry asks one place (:func:`case_readings`).
"""

from __future__ import annotations

from tuflexperf.analysis.cache import ByObject
from tuflexperf.analysis.extrapolation_reading import extrapolation_readings
from tuflexperf.analysis.flown_reading import flown_power_readings
from tuflexperf.analysis.model_form_reading import model_form_readings
from tuflexperf.analysis.power_reading import measured_power_readings
from tuflexperf.analysis.readings import Provider, Reading
from tuflexperf.analysis.windmilling_reading import windmilling_readings
from tuflexperf.io.case import Case

PROVIDERS: tuple[Provider, ...] = (measured_power_readings, flown_power_readings,
                                   windmilling_readings, extrapolation_readings,
                                   model_form_readings)


_READINGS: ByObject[tuple[Reading, ...]] = ByObject(2)


def case_readings(case: Case, blocks: frozenset[str] | None = None) -> tuple[Reading, ...]:
    """Every reading of ``case`` (those bearing on ``blocks`` only, when given).

    A case's are kept (a case is frozen): ``check --samples`` asks for the same case's three
    times (its verdicts, the samples' evaluator, their labels), each flying the power
    reading's point, and its readings' cases are then the same objects.
    """
    out = _READINGS.get(case, lambda: tuple(r for provider in PROVIDERS
                                            for r in provider(case)))
    return tuple(r for r in out if blocks is None or r.affects & blocks)
