"""The batch judged on every reading of disputed evidence, as the single case is.

Samples, sweeps and margins evaluate the case's batch; where readings of disputed evidence
bear on a requirement (:mod:`tuflexperf.analysis.readings`) the same rows are evaluated on
each reading's case too, for the requirement blocks it affects only (a reading's
evaluator holds those blocks alone), and per row the worse reading's value is kept: a row
is met only where it is met on every reading, and disputed where it is met on some but
not all (UNPROVEN, as :func:`tuflexperf.analysis.verdict.on_readings` judges one case).
A reading that flies the nominal's thrust (it moves only the fans' power, or a dead engine's
drag) takes the nominal's thrust-only results of the same rows instead of making them again
(:class:`tuflexperf.analysis.batch_model.SharedRows`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tuflexperf.analysis.batch import BatchResult
from tuflexperf.analysis.readings import Reading, thrust_identity
from tuflexperf.analysis.verdict import requirement_met
from tuflexperf.io.case import Case

Array = NDArray[np.float64]
#: the readings the samples draw themselves (the extrapolation band, the lack of fit's
#: surface): where they draw them they do not fly the bound
DRAWN_BY_SAMPLES = "extrapolation_bound"
MODEL_FORM_BOUND = "model_form_bound"


def _badness(values: Array, limits: Array, kind: str) -> Array:
    """How far each row is from meeting its limit [the requirement's unit]; NaN worst."""
    margin = limits - values if kind == "max" else values - limits
    return np.where(np.isfinite(margin), -margin, np.inf)


def combine_rows(values: Mapping[str, Array], limits: Mapping[str, Array],
                 kinds: Mapping[str, str], theirs: list[tuple[Reading, Mapping[str, Array]]]
                 ) -> tuple[dict[str, Array], dict[str, NDArray[np.bool_]],
                            dict[str, dict[str, Array]]]:
    """Per requirement the worse reading's value per row, the rows met on some reading but
    not on another, and each reading's values (``"nominal"`` first) where a reading bears
    on it; a requirement no reading evaluates keeps its values."""
    worse: dict[str, Array] = dict(values)
    disputed: dict[str, NDArray[np.bool_]] = {}
    by_reading: dict[str, dict[str, Array]] = {}
    for name, nominal in values.items():
        # a reading that changes no row's value never entered it (as the single case)
        mine = [(r, v[name]) for r, v in theirs if name in v
                and not np.allclose(v[name], nominal, rtol=1e-9, atol=1e-9, equal_nan=True)]
        if not mine:
            continue
        limit, kind = limits[name], kinds[name]
        worst = np.asarray(nominal, dtype=float)
        met = requirement_met(worst, limit, kind)
        some, every = met.copy(), met.copy()
        by_reading.setdefault("nominal", {})[name] = worst
        for reading, other in mine:
            other = np.asarray(other, dtype=float)
            by_reading.setdefault(reading.key, {})[name] = other
            worst = np.where(_badness(other, limit, kind) > _badness(worst, limit, kind),
                             other, worst)
            met = requirement_met(other, limit, kind)
            some |= met
            every &= met
        worse[name] = worst
        disputed[name] = some & ~every
    return worse, disputed, by_reading


class ReadingsEvaluator:
    """A case's :class:`BatchEvaluator` whose results are judged on every reading too.

    ``evaluate`` returns the nominal batch's :class:`BatchResult` with each disputed
    requirement's values the worse reading's (``reading_values`` and ``disputed`` as
    :func:`combine_rows`); every other attribute is the nominal evaluator's.

    Parameters
    ----------
    case : Case
        The nominal case.
    drawn : bool
        Leave out the reading the samples draw themselves (:data:`DRAWN_BY_SAMPLES`).
    drawn_model_form : bool
        Leave out the lack of fit's bound (:data:`MODEL_FORM_BOUND`): the samples draw it.
    """

    def __init__(self, case: Case, drawn: bool = False, drawn_model_form: bool = False
                 ) -> None:
        from tuflexperf.analysis.evaluators import evaluator_for
        from tuflexperf.analysis.evidence import case_readings

        self.nominal = evaluator_for(case)
        self.requirements = self.nominal.requirements
        blocks = frozenset(r.block for r in self.requirements)
        # every reading (a mission's too: the samples fly it beside the batch)
        self.all_readings = tuple(r for r in case_readings(case)
                                  if not (drawn and r.key == DRAWN_BY_SAMPLES)
                                  and not (drawn_model_form and r.key == MODEL_FORM_BOUND))
        self.readings: list[tuple[Reading, frozenset[str]]] = [
            (r, r.affects & blocks) for r in self.all_readings if r.affects & blocks]
        # the readings that fly the nominal's thrust (a power correction, a dead engine's
        # drag) take its thrust-only results (batch_model.SharedRows)
        live = self.nominal.thrust_identity[0]
        self.sharing = frozenset(r.key for r, _ in self.readings
                                 if thrust_identity(r.case)[0] == live)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.nominal, name)

    def evaluate(self, values: Mapping[str, Array] | None = None, size: int | None = None,
                 coefficients: Array | None = None,
                 extrapolation_n: Array | None = None,
                 power_scale: Array | None = None,
                 shared: dict[Any, Any] | None = None) -> BatchResult:
        """As :meth:`BatchEvaluator.evaluate`, on every reading too (``shared`` as
        :meth:`readings_rows`)."""
        return self.combined(*self.readings_rows(values, size, coefficients, extrapolation_n,
                                                 power_scale, shared))

    def readings_rows(self, values: Mapping[str, Array] | None = None, size: int | None = None,
                      coefficients: Array | None = None,
                      extrapolation_n: Array | None = None,
                      power_scale: Array | None = None,
                      shared: dict[Any, Any] | None = None
                      ) -> tuple[BatchResult, dict[str, dict[str, Array]]]:
        """The nominal batch's result and, by reading key, each reading's values where it
        is flown, before :meth:`combined` judges the rows on them (arguments as
        :meth:`evaluate`; ``shared`` the caller's dict of these rows' thrust-only results,
        :class:`~tuflexperf.analysis.batch_model.SharedRows`, for what else flies them)."""
        # the results that read only the thrust: made once for every reading that flies it
        if shared is None and self.sharing:
            shared = {}
        result = self.nominal.evaluate(values, size, coefficients, extrapolation_n, power_scale,
                                       shared)
        theirs: dict[str, dict[str, Array]] = {}
        if not self.readings:
            return result, theirs
        from tuflexperf.analysis.evaluators import evaluator_for

        rows = next(iter(result.values.values())).shape[0] if result.values else size
        for reading, blocks in self.readings:
            if reading.beyond_tested_only:
                # the bound moves thrust beyond the tested airspeeds only: a block no row of
                # which flies there is the nominal's (its evaluation saved)
                blocks = frozenset(r.block for r in self.requirements
                                   if r.block in blocks and r.name in result.extrapolated
                                   and result.extrapolated[r.name].any())
            if blocks:
                evaluator = evaluator_for(reading.case, blocks)
                theirs[reading.key] = evaluator.evaluate(
                    values, rows, coefficients, extrapolation_n, power_scale,
                    shared if reading.key in self.sharing else None).values
        return result, theirs

    def combined(self, result: BatchResult, theirs: Mapping[str, Mapping[str, Array]]
                 ) -> BatchResult:
        """The nominal ``result`` with each requirement's rows judged on every reading in
        ``theirs`` (:meth:`readings_rows`): the worse reading's values, ``disputed`` and
        ``reading_values`` as :func:`combine_rows`."""
        if not self.readings:
            return result
        flown = [(r, theirs[r.key]) for r, _ in self.readings if r.key in theirs]
        worse, disputed, by_reading = combine_rows(result.values, result.limits,
                                                   result.kinds, flown)
        return dataclasses.replace(result, values=worse, disputed=disputed,
                                   reading_values=by_reading)


def joined_rows(parts: Sequence[tuple[BatchResult, Mapping[str, Mapping[str, Array]]]]
                ) -> tuple[BatchResult, dict[str, dict[str, Array]]]:
    """Consecutive rows' :meth:`ReadingsEvaluator.readings_rows` as those of one batch (each
    row's results are its own, whatever rows share its batch). A reading not flown on some
    part's rows (a bound beyond the tested airspeeds, where none of them flies) has the
    nominal's values there, as one batch gives them."""
    results = [result for result, _ in parts]

    def rows(arrays: list[Any]) -> Any:
        return None if arrays[0] is None else np.concatenate(arrays)

    def by_name(field: str) -> dict[str, Array]:
        first = getattr(results[0], field)
        return {n: np.concatenate([getattr(r, field)[n] for r in results]) for n in first}

    joined = dataclasses.replace(
        results[0], values=by_name("values"), limits=by_name("limits"),
        refused=rows([r.refused for r in results]),
        without_envelope=rows([r.without_envelope for r in results]),
        extrapolated=by_name("extrapolated"), airspeeds=by_name("airspeeds"))
    keys = list(dict.fromkeys(key for _, theirs in parts for key in theirs))
    theirs: dict[str, dict[str, Array]] = {}
    for key in keys:
        names = dict.fromkeys(n for _, t in parts for n in t.get(key, {}))
        theirs[key] = {n: np.concatenate([t.get(key, {}).get(n, result.values[n])
                                          for result, t in parts]) for n in names}
    return joined, theirs


def readings_evaluator(case: Case, drawn: bool = False, drawn_model_form: bool = False
                       ) -> ReadingsEvaluator:
    """The :class:`ReadingsEvaluator` of ``case`` (its evaluators kept per process)."""
    return ReadingsEvaluator(case, drawn, drawn_model_form)


def reading_labels(case: Case) -> dict[str, tuple[str, str]]:
    """Each reading's key -> (what it flies, what the nominal case flies in its place)."""
    from tuflexperf.analysis.evidence import case_readings

    return {r.key: (r.label, r.nominal_label) for r in case_readings(case)}
