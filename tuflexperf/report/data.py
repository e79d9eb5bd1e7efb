"""What the design-review report draws: the case's analyses and the data behind the model.

Everything here is computed by the project's own modules; nothing is re-derived:

- verdicts, take-off, trim, OEI, endurance: one :class:`tuflexperf.analysis.study.Study`
  of the case, so each is solved once and the figure draws the result the verdict read;
- measured thrust points, delay, structure drag: :func:`tuflexperf.reduction.pipeline.fit_campaign`
  on the campaign (or :func:`tuflexperf.io.runs.read_thrust_table` on a table);
- one reduced run, its cleaned force and change points, and the sine sweeps: kept by that
  same ``fit_campaign`` (``FitResult.step_runs``, ``sweep_runs``), never reduced again;
- endurance: :func:`tuflexperf.analysis.endurance.solve_endurance` and its battery
  characterisation (fitted pack model and discharge runs).

Where the measured data come from (first that applies):

1. ``--campaign FILE`` (a campaign manifest or a thrust-table CSV);
2. the propulsion file's ``source.input`` as written by ``tuflexperf fit``;
3. ``campaign/campaign.yaml`` beside the propulsion file (the shipped TU-Flex layout).

When none applies, the report draws the model alone and says so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from tuflexperf.analysis.review_views import thrust_at_points
from tuflexperf.errors import InputError, NotAttainable
from tuflexperf.io.case import Case
from tuflexperf.models.thrust import (
    delay_samples,
    engine_thrust_n,
    lag_factor,
    reference_basis_scale,
)

if TYPE_CHECKING:
    from tuflexperf.analysis.study import Study

CAMPAIGN_BESIDE_PROPULSION = Path("campaign") / "campaign.yaml"


# --- measured data ----------------------------------------------------------------------------
@dataclass(frozen=True)
class MeasuredPoints:
    """Thrust-table points (per engine name): throttle fraction, airspeed m/s, thrust N."""

    engine: tuple[str, ...]
    throttle: np.ndarray
    airspeed_m_s: np.ndarray
    thrust_n: np.ndarray

    def select(self, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        mask = np.array([e == name for e in self.engine], dtype=bool)
        return self.throttle[mask], self.airspeed_m_s[mask], self.thrust_n[mask]


@dataclass(frozen=True)
class ProcessedRun:
    """One throttle-step run, raw and cleaned, with its change points and steady segments."""

    file: str
    engine: str
    time_s: np.ndarray
    throttle: np.ndarray
    airspeed_m_s: np.ndarray
    force_raw_n: np.ndarray
    force_clean_n: np.ndarray
    changepoints: tuple[int, ...]
    segments: tuple[tuple[int, int, float], ...]  # (start, stop, mean force N)
    outliers_replaced: int
    # the basis of the forces (Measured.basis_scale applied): None = as measured
    reference_density_kg_m3: float | None = None

    @property
    def mean_airspeed_m_s(self) -> float:
        return float(np.mean(self.airspeed_m_s))


@dataclass(frozen=True)
class SweepRun:
    """A sine-sweep run and its measured dead time (s)."""

    file: str
    engine: str
    time_s: np.ndarray
    throttle: np.ndarray
    force_n: np.ndarray
    airspeed_m_s: float
    delay_s: float
    lag_s: float
    # a 20 ms moving median takes the balance's spikes out without shifting the phase
    force_median_n: np.ndarray


@dataclass
class Measured:
    """The measured side of the report; any part may be missing (``notes`` say why)."""

    source: Path | None = None
    kind: str = "none"  # "campaign", "table" or "none"
    points: MeasuredPoints | None = None
    fit_summary: dict[str, Any] | None = None
    processed: ProcessedRun | None = None
    sweep: SweepRun | None = None
    comparisons: list[ProcessedRun] = field(default_factory=list)
    density_kg_m3: float | None = None  # the test's air density (the campaign's)
    # rho_ref / rho_test: every measured force here (points, runs, sweep) is already on the
    # propulsion file's reference density, the model's own basis (issue 47 item 3)
    basis_scale: float = 1.0
    reference_density_kg_m3: float | None = None
    drag_c1_c2: tuple[float, float] | None = None  # as measured, at density_kg_m3
    files: list[Path] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    # the measured data are not those the propulsion file was fitted to (provenance_notes):
    # caveats of the first page as well as notes
    provenance: list[str] = field(default_factory=list)
    # (run file, delay s, lag s) -> the model's balance force over that run [N]
    model_force: dict[tuple[str, float, float], np.ndarray | None] = field(
        default_factory=dict
    )
    # the sweep's first-harmonic amplitude per frequency, measured and per model of
    # model_dynamics(..., steps=True) in its order (reduction.delay.sweep_amplitudes)
    sweep_amplitude: Any | None = None
    points_model_n: np.ndarray | None = None  # the thrust model at each point (its basis)
    sweep_amplitude_labels: tuple[tuple[str, float, float], ...] = ()


def find_measured_source(case: Case, explicit: Path | None) -> Path | None:
    """Where the measured data for ``case``'s propulsion model are (module docstring)."""
    if explicit is not None:
        if not explicit.is_file():
            from tuflexperf.io.files import why_not_a_file

            raise InputError(f"--campaign: {why_not_a_file(explicit)}: {explicit}")
        return explicit
    fitted = _fitted_input(case)
    if fitted is not None and fitted[1].is_file():
        return fitted[1]
    beside = case.propulsion_path.parent / CAMPAIGN_BESIDE_PROPULSION
    return beside if beside.is_file() else None


def _fitted_input(case: Case) -> tuple[str, Path] | None:
    """The propulsion file's ``source.input`` as written by ``fit`` and as a path (relative
    to the propulsion file), or None without one."""
    source = case.propulsion.metadata.get("source") or {}
    given = source.get("input") if isinstance(source, dict) else None
    if not isinstance(given, str):
        return None
    path = Path(given)
    return given, path if path.is_absolute() else case.propulsion_path.parent / path


def provenance_notes(case: Case, used: Path | None) -> list[str]:
    """Notes where the measured data drawn are not those the propulsion file was fitted to:
    its ``source.input`` missing or another file than the one used, or that file or a run
    changed since (sha256 against ``source``). A campaign edited after the fit was drawn
    against the model as if it were the fit's own data, unsaid (outside audit)."""
    import os

    from tuflexperf.io.files import sha256_of, why_not_a_file

    found = _fitted_input(case)
    if found is None:
        return []
    given, fitted = found
    source = case.propulsion.metadata["source"]
    name = case.propulsion_path.name
    if used is None or not fitted.is_file():
        what = "nothing" if used is None else str(used)
        return [f"{name} was fitted to {given} ({why_not_a_file(fitted)}); the measured data "
                f"drawn are {what}"]
    if os.path.realpath(fitted) != os.path.realpath(used):
        return [f"{name} was fitted to {given}; the measured data drawn are {used}'s"]
    changed = []
    if isinstance(source.get("input_sha256"), str) and sha256_of(used) != source["input_sha256"]:
        changed.append(used.name)
    for entry in source.get("files") or []:
        if not (isinstance(entry, dict) and isinstance(entry.get("file"), str)
                and isinstance(entry.get("sha256"), str)):
            continue
        run = used.parent / entry["file"]
        if not run.is_file():
            changed.append(f"{entry['file']} (gone)")
        elif sha256_of(run) != entry["sha256"]:
            changed.append(entry["file"])
    if not changed:
        return []
    listed = ", ".join(changed[:3]) + (f" and {len(changed) - 3} more" if len(changed) > 3
                                       else "")
    return [f"the measured data changed since {name} was fitted ({listed}): the figures draw "
            "today's data against a model fitted to other data (fit again to compare them)"]


def _points_from_rows(rows: list[dict[str, Any]]) -> MeasuredPoints:
    return MeasuredPoints(
        engine=tuple(str(r["engine"]) for r in rows),
        throttle=np.array([float(r["throttle"]) for r in rows]),
        airspeed_m_s=np.array([float(r["airspeed_m_s"]) for r in rows]),
        thrust_n=np.array([float(r["thrust_n"]) for r in rows]),
    )


def _processed_run(result: Any, scale: float, reference: float | None) -> ProcessedRun:
    """One throttle-step run as ``fit_campaign`` reduced it (paper Fig. 10); no re-reduction;
    its forces times ``scale`` (onto the reference density, :attr:`Measured.basis_scale`)."""
    data = result.data
    return ProcessedRun(
        file=result.run.file,
        engine=str(result.run.engine),
        time_s=data.time_s,
        throttle=data["throttle"],
        airspeed_m_s=data["airspeed_m_s"],
        force_raw_n=scale * data["force_n"],
        force_clean_n=scale * result.cleaned_force_n,
        changepoints=result.changepoints,
        segments=tuple((s.start, s.stop, scale * s.force_n) for s in result.segments),
        outliers_replaced=result.outliers_replaced,
        reference_density_kg_m3=reference,
    )


def _mean_airspeed(summary_runs: dict[str, dict[str, Any]], file: str) -> float:
    """A run's airspeed from the fit's points (mean of its segments), else NaN."""
    return summary_runs.get(file, {}).get("airspeed", math.nan)


def load_measured(case: Case, explicit: Path | None, progress: Any = None) -> Measured:
    """Measured points, one processed run, one sweep and two model comparisons."""
    source = find_measured_source(case, explicit)
    measured = Measured(source=source)
    measured.provenance = provenance_notes(case, source)
    measured.reference_density_kg_m3 = case.propulsion.reference_density_kg_m3
    measured.notes.extend(measured.provenance)
    if source is None:
        measured.notes.append(
            "no measured data for this propulsion model (no --campaign, no source.input in "
            f"{case.propulsion_path.name}, no {CAMPAIGN_BESIDE_PROPULSION} beside it): "
            "the thrust surfaces are drawn alone"
        )
        return measured
    measured.files.append(source)
    from tuflexperf.io.proptables import is_propeller_manifest
    from tuflexperf.reduction.pipeline import is_thrust_table

    table_file = is_thrust_table(source)
    tables = not table_file and is_propeller_manifest(source)
    if table_file or tables:
        # a published propeller table is points too (throttle = rpm / max rpm), like a CSV
        if tables:
            from tuflexperf.io.proptables import read_propeller_tables

            table = read_propeller_tables(source)
            what = "the propeller tables of"
        else:
            from tuflexperf.io.runs import read_thrust_table

            table = read_thrust_table(source)
            what = "the thrust table"
        measured.kind = "table"
        measured.points = MeasuredPoints(
            table.engine, table.throttle, table.airspeed_m_s, table.thrust_n
        )
        measured.points_model_n = thrust_at_points(case, tuple(table.engine),
                                                   np.asarray(table.throttle, dtype=float),
                                                   np.asarray(table.airspeed_m_s, dtype=float))
        measured.notes.append(
            f"measured points from {what} {source.name}; no raw runs, so the run, "
            "sine-sweep and model-vs-run figures are left out"
        )
        return measured

    from tuflexperf.io.campaign import load_campaign
    from tuflexperf.reduction.campaign_fit import fit_campaign

    campaign = load_campaign(source)
    measured.kind = "campaign"
    measured.density_kg_m3 = campaign.air_density_kg_m3
    scale = reference_basis_scale(case.propulsion, campaign.air_density_kg_m3)
    measured.basis_scale = scale
    measured.files.extend(run.path for run in campaign.runs)
    result = fit_campaign(source, progress=progress)
    summary = result.summary
    measured.fit_summary = summary
    points = _points_from_rows(summary["points"])
    # the thrust points onto the model's basis: the campaign's points are at its own density
    measured.points = MeasuredPoints(points.engine, points.throttle, points.airspeed_m_s,
                                     scale * points.thrust_n)
    measured.points_model_n = thrust_at_points(case, points.engine, points.throttle,
                                               points.airspeed_m_s)
    drag = summary.get("structure_drag")
    if drag:
        measured.drag_c1_c2 = (drag["c1_n_per_m_s"], drag["c2_n_per_m2_s2"])

    airspeeds: dict[str, dict[str, Any]] = {}
    for row in summary["points"]:
        entry = airspeeds.setdefault(row["run"], {"values": []})
        entry["values"].append(float(row["airspeed_measured_m_s"]))
    for entry in airspeeds.values():
        entry["airspeed"] = float(np.mean(entry["values"]))

    steps = result.step_runs
    engines = list(dict.fromkeys(str(r.run.engine) for r in steps))
    if steps:
        # Paper Fig. 10: the run at the highest airspeed (30 m/s) of the first engine.
        first = [r for r in steps if str(r.run.engine) == engines[0]]
        fastest = max(first, key=lambda r: _mean_airspeed(airspeeds, r.run.file))
        measured.processed = _processed_run(fastest, scale, measured.reference_density_kg_m3)
        # Paper Figs. 16-17: first engine at its lowest airspeed, last at its highest.
        slowest = min(first, key=lambda r: _mean_airspeed(airspeeds, r.run.file))
        last = [r for r in steps if str(r.run.engine) == engines[-1]]
        top = max(last, key=lambda r: _mean_airspeed(airspeeds, r.run.file))
        measured.comparisons = [
            _processed_run(run, scale, measured.reference_density_kg_m3) for run in (slowest, top)
        ]

    if result.sweep_runs:
        # Paper Figs. 13-14: the sweep at the highest airspeed, of the last engine on a tie.
        sweep = max(
            enumerate(result.sweep_runs),
            key=lambda item: (round(float(np.mean(item[1].data["airspeed_m_s"])), 0), item[0]),
        )[1]
        from tuflexperf.reduction.filters import movmedian, window_samples

        t = sweep.data.time_s
        rate = (t.size - 1) / (t[-1] - t[0])
        measured.sweep = SweepRun(
            file=sweep.run.file,
            engine=str(sweep.run.engine),
            time_s=t,
            throttle=sweep.data["throttle"],
            force_n=scale * sweep.data["force_n"],
            airspeed_m_s=float(np.mean(sweep.data["airspeed_m_s"])),
            delay_s=sweep.estimate.delay_s,
            lag_s=sweep.estimate.lag_s,
            force_median_n=scale * movmedian(sweep.data["force_n"],
                                             window_samples(0.02, rate) | 1),
        )
    else:
        measured.notes.append(f"{source.name}: no sine_sweep run, delay figure left out")
    _model_responses(case, measured)
    return measured


# --- the model against the measured force (paper Figs. 13-17) ----------------------------
def dynamic_thrust_n(
    engine: Any,
    time_s: np.ndarray,
    throttle: np.ndarray,
    airspeed_m_s: Any,
    scale: float,
    delay_s: float,
    lag_s: float,
) -> np.ndarray:
    """The exports' discrete dynamic model evaluated on a logged throttle [N].

    Per sample: the command ``round(delay_s / dt)`` samples ago (the first sample held
    before that, as the C ring buffer and the CasADi step start), its poly22 thrust, then
    the exact discrete first-order lag ``T_k = a T_(k-1) + (1 - a) T_static,k`` with
    ``a = exp(-dt / lag_s)``, started at rest (``tfp_step`` in the exported C,
    ``thrust_step_function`` in CasADi). Nothing is solved: the model is evaluated.

    Parameters
    ----------
    engine : Engine
        The fan's poly22 coefficients [N].
    time_s : numpy.ndarray
        Sample times [s], evenly spaced.
    throttle : numpy.ndarray
        Throttle command per sample [fraction].
    airspeed_m_s : float or numpy.ndarray
        Airspeed [m/s], scalar or per sample.
    scale : float
        Thrust scale ``rho / rho_ref`` [-].
    delay_s, lag_s : float
        Dead time and spool-lag time constant [s].

    Returns
    -------
    numpy.ndarray
        Thrust per sample [N].
    """
    from tuflexperf.reduction.filters import first_order_lag

    x = np.asarray(throttle, dtype=float)
    dt = float(time_s[-1] - time_s[0]) / max(x.size - 1, 1)
    steps = min(delay_samples(delay_s, dt), x.size)
    delayed = np.concatenate([np.full(steps, x[0]), x[: x.size - steps]]) if steps else x
    static = np.asarray(engine_thrust_n(engine, delayed, airspeed_m_s, scale), dtype=float)
    return first_order_lag(np.broadcast_to(static, x.shape), lag_factor(lag_s, dt))


def balance_model_n(
    case: Case, measured: Measured, engine_name: str, time_s: np.ndarray, throttle: np.ndarray,
    airspeed_m_s: Any, delay_s: float, lag_s: float,
) -> np.ndarray | None:
    """The balance force the model predicts, ``F = T - D`` (drag positive rearward), on the
    propulsion file's reference density as the measured forces are (:attr:`Measured.basis_scale`):
    the model's thrust as it stands, the structure drag measured at the test's density scaled
    onto it [N]."""
    names = [e.name for e in case.propulsion.engines]
    if engine_name not in names:
        return None
    engine = case.propulsion.engines[names.index(engine_name)]
    force = dynamic_thrust_n(engine, time_s, throttle, airspeed_m_s, 1.0, delay_s, lag_s)
    if measured.drag_c1_c2 is not None:
        c1, c2 = measured.drag_c1_c2
        force = force - measured.basis_scale * (c1 * airspeed_m_s + c2 * np.square(airspeed_m_s))
    return force


def model_dynamics(case: Case, measured: Measured,
                   steps: bool = False) -> list[tuple[str, float, float]]:
    """(label, delay [s], lag [s]) of the models to draw: the propulsion file's (what the
    exports carry) and, where it differs, what ``fit`` measured on this campaign's sine
    sweeps (the model ``fit`` writes); with ``steps`` also the fit on its throttle steps."""
    prop = case.propulsion
    shown = [("propulsion file", prop.delay_s, prop.lag_s)]
    summary = measured.fit_summary or {}
    delay, lag = summary.get("delay_s"), summary.get("lag_s")
    if delay is not None and math.isfinite(delay):
        lag = float(lag) if lag is not None and math.isfinite(lag) else 0.0
        if abs(delay - prop.delay_s) > 5e-4 or abs(lag - prop.lag_s) > 5e-4:
            shown.append(("sine-sweep fit", float(delay), lag))
    fitted = (summary.get("dynamics_fits") or {}).get("throttle_steps")
    if steps and fitted:
        shown.append(("throttle-step fit", float(fitted["delay_s"]), float(fitted["lag_s"])))
    return shown


def model_force_n(
    case: Case, measured: Measured, run: ProcessedRun | SweepRun,
    delay_s: float | None = None, lag_s: float | None = None,
) -> np.ndarray | None:
    """The model's balance force over a run (a step run or the sine sweep): the dynamic
    thrust minus the structure drag [N].

    The thrust is :func:`dynamic_thrust_n` of the logged throttle (the propulsion file's
    ``delay_s`` and ``lag_s`` unless given), ``D`` the structure drag ``c1 V + c2 V^2``
    fitted from the campaign (the paper compared a model "without the drag correction",
    section 4). Computed once per run and dynamics (kept in ``measured.model_force``).
    """
    prop = case.propulsion
    delay = prop.delay_s if delay_s is None else delay_s
    lag = prop.lag_s if lag_s is None else lag_s
    key = (run.file, float(delay), float(lag))
    if key not in measured.model_force:
        measured.model_force[key] = balance_model_n(
            case, measured, run.engine, run.time_s, run.throttle, run.airspeed_m_s, delay, lag
        )
    return measured.model_force[key]


def _model_responses(case: Case, measured: Measured) -> None:
    """Every model response the report draws, computed with the reduction (the figures
    then evaluate nothing; the forked page writers need no filter code of their own)."""
    for _, delay, lag in model_dynamics(case, measured):
        for run in measured.comparisons:
            model_force_n(case, measured, run, delay, lag)
    sweep = measured.sweep
    if sweep is None:
        return
    from tuflexperf.reduction.delay import sweep_amplitudes

    dynamics = model_dynamics(case, measured, steps=True)
    models = [model_force_n(case, measured, sweep, delay, lag) for _, delay, lag in dynamics]
    if any(m is None for m in models):  # the case's propulsion has no such engine
        return
    measured.sweep_amplitude = sweep_amplitudes(
        sweep.time_s, sweep.throttle, np.vstack([sweep.force_median_n, *models]))
    measured.sweep_amplitude_labels = tuple(dynamics)




# --- the case's analyses ----------------------------------------------------------------------
@dataclass
class Analyses:
    """The performance results the figures draw (``None`` where the case has no input)."""

    verdicts: list[Any]
    takeoff: Any | None
    takeoff_note: str | None
    trim: Any | None
    oei: Any | None
    # trim on the thrust beyond the tested airspeeds at its required-probability bound (the
    # extrapolation reading's Study: the curve its verdict read), with the reading's label
    trim_bound: Any | None = None
    trim_bound_label: str | None = None
    endurance_curve: list[tuple[float, Any]] = field(default_factory=list)
    endurance_at_requirement: Any | None = None
    best_endurance: Any | None = None  # Study.best_endurance(): the longest flight (BestResult)
    characterisation: Any | None = None
    battery: Any | None = None  # the pack flown: the file's, with any --set battery.* values
    notes: list[str] = field(default_factory=list)
    study: Any | None = None  # the Study these came from: later pages ask it, never re-solve
    # point performance (Study.performance), or why there is none
    performance: Any | None = None
    performance_note: str | None = None
    # the thrust model's 95 % band per engine at BAND_THROTTLES (analysis.thrust_band)
    thrust_bands: list[Any] = field(default_factory=list)
    # per requirement the tornado (Study.tornado) and every limit value (Study.limit_values):
    # filled by margins() when the tornado page is first drawn (about 1 s of batch solves,
    # spent in the forked PNG writer while this process reduces the campaign)
    tornadoes: list[Any] = field(default_factory=list)
    limit_values: dict[Any, Any] | None = None
    margins_note: str | None = None
    _margins_done: bool = field(default=False, repr=False)
    # the case's mission flown (Study.mission), or why not; both None: the case has none
    mission: Any | None = None
    mission_note: str | None = None
    # issue 47 item 4's views (analysis.review_views), filled by views() when first drawn,
    # in the forked writer; a view that does not exist has its reason in view_notes
    envelope: Any | None = None
    mass_sweep: Any | None = None
    height_profile: Any | None = None
    run_powers: list[tuple[str, str, float, float, float, float]] = field(default_factory=list)
    view_notes: dict[str, str] = field(default_factory=dict)
    _views_done: bool = field(default=False, repr=False)
    # --compare: (label, case) of each other configuration, and once compared() has solved
    # them (in whichever process draws a comparable page first) (label, case, analyses)
    compare: list[tuple[str, Any]] = field(default_factory=list)
    # the case's validation flights (analysis.flown_reading.flown_flights), read once
    flights: tuple[Any, ...] = ()
    _others: list[tuple[str, Any, Any]] | None = field(default=None, repr=False)
    _compared_flights: list[tuple[str, tuple[Any, ...]]] | None = field(default=None,
                                                                        repr=False)

    @property
    def compared_flights(self) -> list[tuple[str, tuple[Any, ...]]]:
        """(label, validation flights) of each ``--compare`` configuration: summaries beside
        its model only, nothing solved (so cheap in whichever process draws the page)."""
        if self._compared_flights is None:
            from tuflexperf.analysis.flown_reading import flown_flights

            self._compared_flights = [(label, flown_flights(other))
                                      for label, other in self.compare]
        return self._compared_flights

    @property
    def others(self) -> list[tuple[str, Any, Any]]:
        """Each ``--compare`` configuration with its analyses (solved on first use)."""
        if self._others is None:
            from tuflexperf.analysis.study import Study

            self._others = [(label, case, run_analyses(Study(case)))
                            for label, case in self.compare]
        return self._others


ENDURANCE_CURVE_POINTS = 15
BAND_THROTTLES = (0.4, 0.7, 1.0)  # measured step levels of the shipped campaign
BAND_STEP_M_S = 0.5


def run_analyses(study: Study | Case) -> Analyses:
    """Every analysis the case allows, read from its :class:`Study` (solved once, shared
    with the verdicts); "not attainable" becomes a note, never a crash."""
    from tuflexperf.analysis.requirements import study_verdicts
    from tuflexperf.analysis.study import Study

    if not isinstance(study, Study):
        study = Study(study)
    case = study.case
    verdicts = study_verdicts(study)
    notes: list[str] = []
    takeoff, takeoff_note = None, None
    try:
        takeoff = study.takeoff()
    except NotAttainable as exc:
        takeoff_note = str(exc)
    trim = oei = None
    if case.requirements.envelope is not None:
        trim = study.trim()
        if len(case.propulsion.engines) >= 2:
            oei = study.oei()
        else:
            notes.append("one engine only: no one-engine-inoperative case")
    else:
        notes.append("the case has no envelope requirement: trim and OEI are not drawn")
    analyses = Analyses(verdicts, takeoff, takeoff_note, trim, oei, notes=notes, study=study)
    if trim is not None:
        bound = [r for r in study.readings() if r.key == "extrapolation_bound"
                 and "envelope" in r.affects]
        if bound and trim.extrapolated:
            analyses.trim_bound = study.on_reading(bound[0]).trim()
            analyses.trim_bound_label = bound[0].label
    if case.validation_flights:  # summaries only: no log is opened
        from tuflexperf.analysis.flown_reading import flown_flights

        analyses.flights = flown_flights(case)
    _performance(study, analyses)
    _thrust_bands(study, analyses)
    _mission(study, analyses)
    if case.battery_path is None:
        notes.append("the case names no battery file: the endurance figure is left out")
        return analyses
    try:
        _endurance(study, analyses)
    except NotAttainable as exc:  # a failing aircraft still gets its review (issue 10)
        notes.append(f"endurance: not attainable: {exc}")
    return analyses


def _performance(study: Study, analyses: Analyses) -> None:
    try:
        analyses.performance = study.performance()
    except NotAttainable as exc:
        analyses.performance_note = str(exc)
        analyses.notes.append(f"point performance: not attainable: {exc}")


def _thrust_bands(study: Study, analyses: Analyses) -> None:
    """Each engine's thrust at BAND_THROTTLES over 0 to the envelope's top (or 1.5x the
    tested range), with the fit's 95 % band; on the model's reference density (its own basis,
    the measured points are scaled onto it)."""
    from tuflexperf.analysis.thrust_band import thrust_band

    case = study.case
    top = 1.5 * case.propulsion.tested_airspeed_m_s[1]
    if case.requirements.envelope is not None:
        top = max(top, case.requirements.envelope.bounds_m_s(case.density_kg_m3)[1])
    airspeed = np.linspace(0.0, top, int(math.ceil(top / BAND_STEP_M_S)) + 1)
    for index in range(len(case.propulsion.engines)):
        for throttle in BAND_THROTTLES:
            analyses.thrust_bands.append(thrust_band(case.propulsion, index, throttle, airspeed))


def margins(analyses: Analyses) -> Analyses:
    """Fill ``analyses`` with the tornado bars and limit values of every requirement the
    batch evaluates (from its Study, once); a failure becomes ``margins_note``."""
    from tuflexperf.analysis.batch import present_requirements

    if analyses._margins_done or analyses.study is None:
        return analyses
    analyses._margins_done = True
    study = analyses.study
    names = [r.name for r in present_requirements(study.case)]
    if not names:
        analyses.margins_note = "the case states no requirement that the margins cover"
        return analyses
    try:
        analyses.tornadoes = [study.tornado(name) for name in names]
        analyses.limit_values = study.limit_values()
    except (NotAttainable, InputError) as exc:
        analyses.margins_note = f"margins: {exc}"
    return analyses


def views(analyses: Analyses) -> Analyses:
    """Fill the review's views (envelope, endurance against mass, the take-off's height, the
    discharge runs against the power model) from the Study, once; each failure a note."""
    from tuflexperf.analysis.review_views import takeoff_height_profile

    if analyses._views_done or analyses.study is None:
        return analyses
    analyses._views_done = True
    study = analyses.study
    try:
        analyses.envelope = study.flight_envelope()
    except NotAttainable as exc:
        analyses.view_notes["envelope"] = str(exc)
    if study.case.battery_path is None:
        analyses.view_notes["mass"] = "the case names no battery file"
    else:
        try:
            analyses.mass_sweep = study.mass_sweep()
            analyses.run_powers = [(run.path.name, engine.name, x, v, measured, modelled)
                                   for run, engine, x, v, measured, modelled
                                   in study.endurance_model().run_powers()]
        except (NotAttainable, InputError) as exc:
            analyses.view_notes["mass"] = str(exc)
    if analyses.takeoff is not None:
        analyses.height_profile = takeoff_height_profile(analyses.takeoff)
    else:
        analyses.view_notes["takeoff"] = analyses.takeoff_note or "no take-off"
    return analyses


def _mission(study: Study, analyses: Analyses) -> None:
    if study.case.requirements.mission is None:
        return
    try:
        analyses.mission = study.mission()
    except NotAttainable as exc:
        analyses.mission_note = str(exc)


def _endurance(study: Study, analyses: Analyses) -> None:
    model = study.endurance_model()
    analyses.characterisation = model.ch
    analyses.battery = model.battery
    least = model.min_throttle
    if not math.isfinite(least):
        analyses.notes.append("no throttle up to full holds level flight: no endurance curve")
        return
    for x in np.linspace(min(max(least, 0.0), 1.0), 1.0, ENDURANCE_CURVE_POINTS):
        try:
            analyses.endurance_curve.append((float(x), study.endurance(float(x))))
        except NotAttainable:
            continue
    try:
        analyses.best_endurance = study.best_endurance()
    except NotAttainable as exc:
        analyses.notes.append(f"best endurance: not attainable: {exc}")
    requirement = study.case.requirements.endurance
    if requirement is not None:
        try:
            analyses.endurance_at_requirement = study.endurance(requirement.throttle)
        except NotAttainable as exc:
            analyses.notes.append(f"endurance at throttle {requirement.throttle:g}: {exc}")


def input_files(case: Case, measured: Measured) -> list[tuple[str, Path]]:
    """(role, path) of every file the report's numbers come from, for the title page."""
    from tuflexperf.io.case import case_files

    files = case_files(case)
    for k, path in enumerate(measured.files):
        files.append(
            (
                "campaign"
                if k == 0 and measured.kind == "campaign"
                else "thrust table"
                if measured.kind == "table"
                else "campaign run",
                path,
            )
        )
    return files


def provenance_class(path: Path) -> str:
    """What a file's own header says it is: measured, synthetic or reconstructed.

    Read from the comment lines at the top of the file (the shipped data state it there;
    ``fit`` writes its source). A file that says nothing is "as given".
    """
    try:
        with open(path, encoding="utf-8", errors="replace") as handle:
            head = "".join(handle.readline() for _ in range(8)).lower()
    except OSError:
        return "unreadable"
    for word in ("synthetic", "reconstructed", "estimated", "measured"):
        if word in head:
            return word
    return "as given (no provenance stated)"


CAVEAT_CLASSES = ("synthetic", "reconstructed", "estimated")


def input_caveats(case: Case, measured: Measured) -> list[str]:
    """The inputs' own caveats, in words, for the first page: each case file or measured
    source whose header says it is synthetic, reconstructed or estimated
    (:func:`provenance_class`), then the measured data that are not the fit's
    (:func:`provenance_notes`, kept by :func:`load_measured`)."""
    from tuflexperf.io.case import case_files

    files = [(role, path) for role, path in case_files(case) if role != "discharge run"]
    if measured.source is not None:
        files.append(("test data", measured.source))
    caveats = []
    for role, path in files:
        said = provenance_class(path)
        if said in CAVEAT_CLASSES:
            caveats.append(f"{role} {path.name}: {said} (its header says so), not measured: "
                           "the verdicts above rest on it")
    if not case.validation_flights:  # a board asks first whether it has flown
        caveats.append("no flight log: the case lists no validation.flights, so no power "
                       "or endurance here is checked against a flight and the page "
                       "\"predicted vs flown\" is left out (flightlog LOG --case CASE "
                       "--summary FILE writes one)")
    return caveats + list(getattr(measured, "provenance", []))


def inputs_digest(hashes: list[str]) -> str:
    """The inputs' short hash of the footer: the first 8 hex digits of the sha256 of the
    inputs' sha256 (the last page's, in its order), one per line."""
    import hashlib

    return hashlib.sha256("".join(f"{h}\n" for h in hashes).encode("ascii")).hexdigest()[:8]
