"""One batch evaluator per case (and requirement blocks) and process.

Building a :class:`~tuflexperf.analysis.batch.BatchEvaluator` reads the battery and finds
its candidates once; samples, sweeps and margins ask here, so each process builds it once
per case, and once per reading of the case's disputed evidence
(:mod:`tuflexperf.analysis.batch_readings`).
"""

from __future__ import annotations

from tuflexperf.analysis.batch import BatchEvaluator
from tuflexperf.analysis.cache import file_key, fingerprint
from tuflexperf.io.case import Case

_evaluators: dict[str, BatchEvaluator] = {}
#: evaluators kept per process: a case and the readings of its disputed evidence
EVALUATORS_KEPT = 8


def evaluator_for(case: Case, blocks: frozenset[str] | None = None) -> BatchEvaluator:
    """One :class:`BatchEvaluator` per case (and requirement ``blocks``) and process
    (workers build theirs once)."""
    # content, not repr: a case's free-form provenance may be large (analysis.cache)
    battery = case.battery_path
    key = fingerprint(case.aircraft, case.propulsion, case.atmosphere, case.requirements,
                      case.overrides, str(battery),
                      file_key(battery) if battery is not None and battery.exists() else None,
                      None if blocks is None else sorted(blocks))
    if key not in _evaluators:
        if len(_evaluators) >= EVALUATORS_KEPT:  # one case and its readings at a time
            _evaluators.clear()
        _evaluators[key] = BatchEvaluator(case, blocks)
    return _evaluators[key]
