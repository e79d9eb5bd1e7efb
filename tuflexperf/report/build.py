"""``tuflexperf report``: every figure of the design review as PNG, and one PDF (``review.pdf``).

All or nothing: the case is loaded and validated before anything is written; the
report is then built in a temporary directory beside ``--out`` and moved into place
at the end (``os.replace``), so a failing run leaves no partial output. An existing
``--out`` is replaced only when it is empty or holds an earlier report (a
``review.pdf``); any other directory is refused rather than overwritten.

Progress goes to stderr as a step counter; stdout stays for the result.
"""

from __future__ import annotations

import math
import os
import re
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

from tuflexperf.errors import InputError

PDF_NAME = "review.pdf"
PNG_DPI = 150
PNG_COMPRESSION = 3  # zlib level: 3 writes about as small as the default 6, in half the time


@dataclass
class ReportResult:
    """What ``report`` wrote: the directory, its files (PNGs then the PDF) and the PDF's pages."""

    out_dir: Path
    files: list[Path]
    pdf: Path
    pages: int
    passed: bool
    seconds: float
    notes: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        return {
            "out": str(self.out_dir),
            "files": [str(p) for p in self.files],
            "pdf": str(self.pdf),
            "pages": self.pages,
            "figures": [str(p) for p in self.files if p.suffix == ".png"],
            "passed": self.passed,
            "seconds": self.seconds,
            "notes": self.notes,
        }


class StepCounter:
    """``report [k/n] label`` lines on stderr (never stdout: ``--json`` keeps it clean)."""

    def __init__(self, total: int, stream: Any = None, enabled: bool = True) -> None:
        self.total, self.done, self.enabled = total, 0, enabled
        self.stream = stream if stream is not None else sys.stderr
        self.started = time.perf_counter()

    def __call__(self, label: str) -> None:
        self.done += 1
        self.total = max(self.total, self.done)
        if self.enabled:
            elapsed = time.perf_counter() - self.started
            self.stream.write(f"report [{self.done}/{self.total}] {label} ({elapsed:.1f} s)\n")
            self.stream.flush()

    def detail(self, done: int, total: int, label: str) -> None:
        """A sub-step of the next step (``fit_campaign``'s progress callback signature)."""
        if self.enabled and done < total:
            elapsed = time.perf_counter() - self.started
            self.stream.write(
                f"report [{self.done + 1}/{self.total}]   reducing {done + 1}/{total} {label} "
                f"({elapsed:.1f} s)\n"
            )
            self.stream.flush()


def _safe_name(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", text).strip("_") or "engine"


def build_report(
    case_file: Path | str | None,
    out: Path | str,
    campaign: Path | str | None = None,
    progress: bool = True,
    stream: Any = None,
) -> ReportResult:
    """Build the design-review report for a case (``None``: the shipped TU-Flex case).

    Parameters
    ----------
    case_file : path or None
        Requirement file.
    out : path
        Directory to write; created, or replaced if it holds an earlier report.
    campaign : path or None
        Campaign manifest or thrust table with the measured data (default: see
        :func:`tuflexperf.report.data.find_measured_source`).
    progress : bool
        Write the step counter to ``stream`` (stderr).

    Returns
    -------
    ReportResult
    """
    from tuflexperf.io.case import load_case
    from tuflexperf.io.files import staged_directory

    started = time.perf_counter()
    out = Path(out).absolute()
    case = load_case(case_file)  # bad input fails here, before anything is written
    campaign_path = Path(campaign) if campaign is not None else None
    if campaign_path is not None and not campaign_path.is_file():
        raise InputError(f"--campaign: file not found: {campaign_path}")
    with (staged_directory(out, "report") as staging,
          tempfile.TemporaryDirectory(prefix="tuflexperf-report-") as kept):
        result = _render(case, staging, campaign_path, StepCounter(18, stream, progress),
                         Path(kept))
    files = [out / p.name for p in result.files]
    return ReportResult(
        out_dir=out,
        files=files,
        pdf=out / PDF_NAME,
        pages=result.pages,
        passed=result.passed,
        seconds=time.perf_counter() - started,
        notes=result.notes,
    )


def _render(case: Any, folder: Path, campaign: Path | None, step: StepCounter,
            kept: Path) -> ReportResult:
    """Draw every page into ``folder``; ``kept`` is a private temporary folder for the
    laid-out figures the PNG writer hands to the PDF."""
    from tuflexperf.report import analysis_figures as af
    from tuflexperf.report import figures as fg

    fg.use_agg()
    from matplotlib.backends.backend_pdf import PdfPages

    from tuflexperf.analysis.study import Study
    from tuflexperf.report.data import load_measured, run_analyses

    analyses = run_analyses(Study(case))
    step("analyses: check, take-off, trim, OEI, endurance, performance, margins, mission")
    # The figures of the analyses alone are drawn (PNG) by a forked copy of this process
    # while this one reduces the campaign; those of the measured data by a second copy
    # while this one writes the PDF (issue 9: the report in half its earlier time).
    # Each page is drawn once: whoever claims it first (a file created exclusively in
    # ``kept``) draws its PNG and lays it out; a writer then keeps the laid-out figure (a
    # pickle) for this process to put in the PDF. The second writer works from the last
    # page back while this process writes the PDF from the first page on.
    analysis_pages: dict[str, Callable[[], Any]] = {
        "01_requirements": lambda: fg.requirement_table(case, analyses),
        "02_thrust_required_available": lambda: fg.thrust_required_available(case, analyses),
        "07_takeoff": lambda: fg.takeoff_history(case, analyses),
    }
    if analyses.trim is not None:
        analysis_pages["08_trim_oei_throttle"] = lambda: fg.trim_oei_throttle(case, analyses)
    analysis_pages["08b_performance"] = lambda: af.performance(case, analyses)
    if analyses.characterisation is not None:
        analysis_pages["09_endurance"] = lambda: fg.endurance(case, analyses)
    if analyses.mission is not None or analyses.mission_note is not None:
        analysis_pages["10_mission"] = lambda: af.mission(case, analyses)
    analysis_pages["11_tornado"] = lambda: af.tornado(case, analyses)
    # The first writer starts with the tornado: the margins behind it (about 1 s of batch
    # solves) are then solved while this process reduces the campaign, not at the PDF's end.
    first = sorted(analysis_pages.items(), key=lambda item: item[0] != "11_tornado")
    writers = [_start_png_writer(first, folder, kept)]
    try:
        measured = load_measured(case, campaign, progress=step.detail)
    except BaseException:  # bad campaign, interrupt: no PNG written after the cleanup
        _stop(writers)
        raise
    step(
        f"measured data: {measured.kind}" + (f" {measured.source.name}" if measured.source else "")
    )
    measured_pages: dict[str, Callable[[], Any]] = {}
    for index, engine in enumerate(case.propulsion.engines):
        measured_pages[f"03_thrust_surface_{_safe_name(engine.name)}"] = (
            lambda i=index: fg.thrust_surface(case, measured, i)
        )
    if measured.processed is not None:
        measured_pages["04_run_processing"] = lambda: fg.run_processing(measured.processed)
    if measured.sweep is not None:
        measured_pages["05_sine_sweep"] = lambda: fg.sine_sweep(measured, case)
    if measured.comparisons:
        measured_pages["06_model_vs_measured"] = lambda: fg.model_vs_measured(case, measured)
    measured_pages["06b_thrust_band"] = lambda: af.thrust_band(case, analyses, measured)
    writers.append(_start_png_writer(list(measured_pages.items())[::-1], folder, kept))
    writer_of = {name: writers[0] for name in analysis_pages}
    writer_of.update({name: writers[1] for name in measured_pages})

    named = sorted({**analysis_pages, **measured_pages}.items())  # the report's page order
    pages: list[tuple[str | None, Callable[[], Any]]] = [
        (None, lambda: _title_page(case, measured, analyses)),
        *named,
    ]
    notes = measured.notes + analyses.notes
    step.total = step.done + len(pages) + 1

    pdf_path = folder / PDF_NAME
    from tuflexperf import __version__

    files = [folder / f"{name}.png" for name, _ in named]
    serial = any(writer is None for writer in writers)
    try:
        with PdfPages(
            pdf_path,
            metadata={"Title": f"Design review: {case.name}",
                      "Creator": f"tuflexperf {__version__}"},
        ) as pdf:
            for name, draw in pages:
                fig, mine = None, serial
                if name is not None and not serial:
                    fig, mine = _kept_figure(kept, name, writer_of[name])
                if fig is None:
                    fig = draw()
                if mine and name is not None:
                    _save_png(fig, folder / f"{name}.png")
                    fig.set_layout_engine("none")  # solved by the PNG's draw; the page keeps it
                pdf.savefig(fig)
                step(name or "title page")
            pdf.savefig(_hash_page(case, measured))
            page_count = len(pages) + 1
            if notes:
                pdf.savefig(
                    fg.text_page("What this report leaves out, and why", [f"- {n}" for n in notes])
                )
                page_count += 1
            step("review.pdf")
        for writer in writers:
            if writer is not None:
                writer.join()
        if not serial and any(writer.exitcode != 0 for writer in writers):
            for name, draw in named:  # never a report without its figures: draw them here
                _save_png(draw(), folder / f"{name}.png")
    finally:
        _stop(writers)  # interrupted: no PNG written after the cleanup
    files.append(pdf_path)
    return ReportResult(
        out_dir=folder,
        files=files,
        pdf=pdf_path,
        pages=page_count,
        passed=all(v.passed for v in analyses.verdicts),
        seconds=0.0,
        notes=notes,
    )


def _stop(writers: list[Any]) -> None:
    for writer in writers:
        if writer is not None and writer.is_alive():
            writer.terminate()
            writer.join()


def _save_png(fig: Any, path: Path) -> None:
    fig.savefig(path, dpi=PNG_DPI, pil_kwargs={"compress_level": PNG_COMPRESSION})


def _claim(keep: Path, name: str) -> bool:
    """True for the one process that first claims page ``name`` (an exclusive create)."""
    try:
        os.close(os.open(keep / f"{name}.claim", os.O_CREAT | os.O_EXCL | os.O_WRONLY))
    except FileExistsError:
        return False
    return True


def _write_pngs(named: list[tuple[str, Callable[[], Any]]], folder: Path,
                keep: Path | None = None) -> None:
    """Draw each page's PNG; with ``keep``, only the pages this process claims, each then
    kept laid out (``NAME.pickle``, or ``NAME.drawn`` when it cannot be pickled)."""
    import pickle

    for name, draw in named:
        if keep is not None and not _claim(keep, name):
            continue  # the PDF's process is drawing it
        fig = draw()
        _save_png(fig, folder / f"{name}.png")
        if keep is None:
            continue
        fig.set_layout_engine("none")  # solved by the PNG's draw; the PDF page keeps it
        staged = keep / f"{name}.pickle.part"
        try:
            with open(staged, "wb") as handle:
                pickle.dump(fig, handle, protocol=pickle.HIGHEST_PROTOCOL)
            os.replace(staged, keep / f"{name}.pickle")  # never read half-written
        except Exception:  # not picklable: the PDF's process draws this page itself
            staged.unlink(missing_ok=True)
            (keep / f"{name}.drawn").touch()


def _png_writer(named: list[tuple[str, Callable[[], Any]]], folder: Path,
                keep: Path | None) -> None:
    """A forked writer's body: on Ctrl-C or SIGTERM (sent to the whole process group) it
    just ends; the report's own process reports the interrupt and removes what was staged."""
    import signal

    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, signal.SIG_DFL)
    _write_pngs(named, folder, keep)


def _kept_figure(keep: Path, name: str, writer: Any) -> tuple[Any, bool]:
    """(figure, mine) for the PDF page ``name``.

    ``mine`` is True when this process claimed the page: it draws it and writes its PNG.
    Otherwise the writer has it: its kept figure once written, or ``(None, False)`` when
    the writer could not keep it or stopped (then the page is drawn for the PDF alone).
    """
    import pickle

    if _claim(keep, name):
        return None, True
    path, drawn = keep / f"{name}.pickle", keep / f"{name}.drawn"
    while not (path.exists() or drawn.exists()) and writer.is_alive():
        writer.join(0.01)
    if not path.exists():
        return None, False
    try:
        with open(path, "rb") as handle:
            return pickle.load(handle), False
    except Exception:  # a figure that does not survive the round trip is drawn again
        return None, False


def _start_png_writer(named: list[tuple[str, Callable[[], Any]]], folder: Path,
                      keep: Path | None = None) -> Any:
    """A forked process drawing the PNGs (and keeping the figures in ``keep``), or None
    where fork is not available (then serial)."""
    import multiprocessing

    if os.environ.get("TUFLEXPERF_SERIAL_REPORT") or not hasattr(os, "fork"):
        return None
    writer = multiprocessing.get_context("fork").Process(
        target=_png_writer, args=(named, folder, keep), daemon=True
    )
    writer.start()
    return writer


def _title_page(case: Any, measured: Any, analyses: Any) -> Any:
    from tuflexperf.report import figures as fg

    return fg.text_page(f"Design review: {case.name}", title_lines(case, measured, analyses),
                        font_size=12.5)


def _hash_page(case: Any, measured: Any) -> Any:
    from tuflexperf.report import figures as fg

    return fg.text_page("Inputs of this report (sha256)", hash_lines(case, measured))


def _fmt(value: Any, unit: str = "", digits: int = 3) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "not attainable"
    return f"{value:.{digits}f}{(' ' + unit) if unit else ''}"


def key_figures(analyses: Any) -> list[str]:
    """The numbers a reviewer asks for first, from the analyses already run (no physics)."""
    lines = []
    t = analyses.takeoff
    if t is not None:
        lines.append(f"  stall speed          {_fmt(t.stall_speed_m_s, 'm/s', 2)} (TAS)")
        lines.append(f"  lift-off speed       {_fmt(t.liftoff_speed_m_s, 'm/s', 2)} "
                     f"({_fmt(t.liftoff_speed_eas_m_s, 'm/s', 2)} EAS)")
        lines.append(f"  ground roll          {_fmt(t.ground_roll_m, 'm', 1)}; to the "
                     f"{t.obstacle_height_m:g} m obstacle {_fmt(t.distance_to_obstacle_m, 'm', 1)}")
    else:
        import textwrap

        note = textwrap.shorten(str(analyses.takeoff_note), 70, placeholder=" ...")
        lines.append(f"  take-off             not attainable: {note}")
    if analyses.trim is not None:
        lines.append(f"  least trim throttle  {_fmt(analyses.trim.min_throttle)}")
    if analyses.oei is not None:
        worst = analyses.oei.critical
        lines.append(f"  OEI least throttle   {_fmt(worst.min_throttle)} "
                     f"({worst.dead_engine} dead)")
    e = analyses.endurance_at_requirement
    if e is not None:
        lines.append(f"  flight endurance     {_fmt(e.flight_endurance_min, 'min', 1)} at "
                     f"throttle {e.throttle:g}, {_fmt(e.airspeed_m_s, 'm/s', 1)}")
    return lines


def title_lines(case: Any, measured: Any, analyses: Any) -> list[str]:
    """The first page: verdicts with value, limit and margin, key figures, provenance, tool."""
    from tuflexperf import __version__
    from tuflexperf.report.data import provenance_class

    verdicts = analyses.verdicts
    failed = sum(not v.passed for v in verdicts)
    now = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    verdict = ("no requirements stated" if not verdicts else "ALL REQUIREMENTS MET"
               if not failed else f"{failed} OF {len(verdicts)} REQUIREMENTS NOT MET")
    lines = [f"VERDICT: {verdict}", "",
             f"  {'requirement':<26}{'value':>16}{'limit':>10}{'unit':>10}{'margin':>16}  verdict"]
    for v in verdicts:
        lines.append(f"  {v.name:<26}{_fmt(v.value):>16}{v.limit:>10g}{v.unit:>10}"
                     f"{_fmt(v.margin):>16}  {'PASS' if v.passed else 'FAIL'}")
    lines += ["", "KEY FIGURES", *key_figures(analyses), "", "INPUTS AND THEIR PROVENANCE"]
    lines.append(f"  aircraft     {case.aircraft.name}, {case.aircraft.mass_kg:g} kg: "
                 f"{provenance_class(case.aircraft_path)}")
    lines.append(f"  propulsion   {case.propulsion.name}: "
                 f"{provenance_class(case.propulsion_path)}")
    if case.battery_path is not None:
        lines.append(f"  battery      {provenance_class(case.battery_path)}")
    if measured.source is not None:
        lines.append(f"  test data    {measured.kind} {measured.source.name}: "
                     f"{provenance_class(measured.source)}")
    else:
        lines.append("  test data    none (the thrust model is drawn alone)")
    lines.append(f"  atmosphere   ISA {case.atmosphere.altitude_m:g} m, "
                 f"dT {case.atmosphere.temperature_offset_k:+g} K, "
                 f"rho = {case.density_kg_m3:.4f} kg/m\u00b3")
    lines += ["", f"case {case.path}", f"tuflexperf {__version__}, {now}; "
              "every input file with its sha256 on the last page"]
    return lines


def hash_lines(case: Any, measured: Any) -> list[str]:
    """Every input of the report with its sha256 (the last page)."""
    from tuflexperf.io.files import sha256_of
    from tuflexperf.report.data import input_files

    lines = []
    root = case.path.parent
    for role, path in input_files(case, measured):
        try:
            shown = os.path.relpath(path, root)
        except ValueError:
            shown = str(path)
        lines.append(f"  {sha256_of(path)}  {role:<13} {shown}")
    return lines
