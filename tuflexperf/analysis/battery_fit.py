"""The case's battery characterised: the equivalent circuit fitted to the discharge runs,
cross-validated run against run, and the fans' electrical power fitted beside it.

Step 1 and 2 of :mod:`tuflexperf.analysis.endurance`: every analysis that flies on the packs
(the mission, the endurance, the pack limits of take-off, trim and OEI) reads the one
characterisation cached here per file contents.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

from tuflexperf.analysis.cache import BoundedCache, file_key, fingerprint
from tuflexperf.errors import InputError
from tuflexperf.io.battery import (
    Battery,
    case_battery,
    load_battery,
    refuse_contradicted_capacity,
)
from tuflexperf.io.case import Case
from tuflexperf.io.discharge import (
    DischargeRun,
    read_discharge_run,
)
from tuflexperf.models.battery import DischargeParameters
from tuflexperf.reduction.battery import (
    DischargeFit,
    PowerFit,
    fan_power_of,
    refuse_unreproduced_runs,
    run_engine,
)

# A discharge run's measured power further than this from the power model is a warning.
RUN_POWER_TOLERANCE = 0.10

_characterisation_cache: BoundedCache[BatteryCharacterisation] = BoundedCache()

_battery_cache: BoundedCache[Battery] = BoundedCache()


# --- battery characterisation (fit + cross-validation + power), cached per file contents ---
@dataclass(frozen=True)
class CrossValidation:
    """A model fitted on one run predicting another run's time to cut-off."""

    fitted_on: str
    predicted_run: str
    observed_min: float
    predicted_min: float

    @property
    def error_percent(self) -> float:
        return 100.0 * (self.predicted_min - self.observed_min) / self.observed_min

    def to_dict(self) -> dict[str, Any]:
        return {
            "fitted_on": self.fitted_on,
            "predicted_run": self.predicted_run,
            "observed_min": self.observed_min,
            "predicted_min": self.predicted_min,
            "error_percent": self.error_percent,
        }


@dataclass(frozen=True)
class BatteryCharacterisation:
    """Everything the discharge runs give: pack model, its validation, fan power model."""

    battery: Battery
    runs: tuple[Any, ...]  # DischargeRun, or the RunSummary a fitted battery file stores
    fit: DischargeFit
    power: PowerFit
    # each run's model predicting every other run's time to cut-off (stored by ``fit``)
    cross_validation: tuple[CrossValidation, ...] = ()

    def discharge_runs(self) -> tuple[DischargeRun, ...]:
        """The runs themselves (read on demand: the report draws them, check does not).

        A run changed since the fit is bad input here, where it is read: the figures would
        draw other data against the pack model (check flies the fitted parameters only).
        """
        from tuflexperf.io.files import sha256_of

        for r in self.runs:
            if not isinstance(r, DischargeRun) and sha256_of(r.path) != r.sha256:
                raise InputError(
                    f"{self.battery.path}: fit.runs: {r.path.name} changed since the pack model "
                    f"was fitted (sha256 differs); fit it again (tuflexperf fit "
                    f"{self.battery.path.name} --out ...)"
                )
        return tuple(r if isinstance(r, DischargeRun) else read_discharge_run(r.path)
                     for r in self.runs)


def characterise_battery(battery: Battery, case: Case) -> BatteryCharacterisation:
    """Fit the pack model to all runs and fit the fan power (cross-validation on demand).

    The full-throttle static power is the published range interpolated at the static
    thrust of the runs' engine (the first engine when the runs name none).
    Cached on the battery file, the run files and the propulsion model. A battery with keys
    changed by ``--set`` is characterised as its file reads (:attr:`Battery.as_read`): the
    runs are checked against the file, the what-if flies the pack they give.
    """
    battery = battery.as_read
    key = fingerprint(
        file_key(battery.path),
        [file_key(r.path) for r in battery.runs],
        battery,
        case.propulsion,
    )
    return _characterisation_cache.get(key, lambda: _characterise(battery, case))


def _stored_fit(battery: Battery) -> tuple[tuple[Any, ...], DischargeFit, tuple[Any, ...]]:
    """The pack model a fitted battery file carries (written by ``fit``; no run is opened:
    check reads parameters only, issue 43 item 2; the report, which draws the runs, checks
    their sha256 where it reads them)."""
    from tuflexperf.io.discharge import RunSummary

    stored = battery.fitted
    assert stored is not None
    summaries = tuple(
        RunSummary(ref.path, r.sha256, r.throttle, r.airspeed_m_s, r.mean_power_w,
                   r.mean_force_n, r.start_charge_ah, r.time_to_cutoff_s, r.charge_drawn_ah)
        for ref, r in zip(battery.runs, stored.runs, strict=True)
    )
    fit = DischargeFit(
        DischargeParameters(**stored.parameters.model_dump()), stored.rms_v, stored.max_abs_v,
        stored.n_points, tuple(s.path.name for s in summaries),
    )
    checks = tuple(CrossValidation(c.fitted_on, c.predicted_run, c.observed_min,
                                   c.predicted_min) for c in stored.cross_validation)
    return summaries, fit, checks


def _characterise(battery: Battery, case: Case) -> BatteryCharacterisation:
    if battery.fitted is None:
        # SPEC 4: check, endurance and report read the pack model and never fit it
        raise InputError(
            f"{battery.path}: no fitted pack model (its 'fit:' block); write one with "
            f"`tuflexperf fit {battery.path.name} --out FILE` and name FILE in the case"
        )
    runs, fit, stored_checks = _stored_fit(battery)
    drawn_of = [r.charge_drawn_ah for r in runs]
    # one pack per run: it cannot give more than it holds (issue 10)
    refuse_contradicted_capacity(
        battery, [(run.path.name, drawn) for run, drawn in zip(runs, drawn_of, strict=True)]
    )
    refuse_unreproduced_runs(battery, fit.parameters, runs)
    power = fan_power_of(battery, case.propulsion, runs, case.propulsion_path)
    correction = run_engine(battery, case.propulsion).power_correction
    if correction is not None:  # a reading flown on the measured power (power_reading.py)
        power = replace(power, model=replace(power.model, power_correction=correction))
    return BatteryCharacterisation(battery, runs, fit, power, stored_checks)


def cached_case_battery(case: Case) -> Battery:
    """:func:`case_battery`, its YAML parsed once per file version, not per call (the
    endurance and the point analyses' packs read it)."""
    return case_battery(case, lambda path: _battery_cache.get(
        fingerprint(file_key(path)), lambda: load_battery(path)))
