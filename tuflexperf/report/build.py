"""``tuflexperf report``: every figure of the design review as PNG, and one PDF (``review.pdf``).

All or nothing: the case is loaded and validated before anything is written; the
report is then built in a temporary directory beside ``--out`` and moved into place
at the end (``os.replace``), so a failing run leaves no partial output. An existing
``--out`` is replaced only when it is empty or holds an earlier report (a
``review.pdf``); any other directory is refused rather than overwritten.

Progress goes to stderr as a step counter; stdout stays for the result.
"""

from __future__ import annotations

import os
import re
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tuflexperf.analysis.verdict import overall_verdict
from tuflexperf.errors import InputError
from tuflexperf.io import swap
from tuflexperf.report.footer import footer_texts, reserve, stamp

if TYPE_CHECKING:
    from tuflexperf.io.case import Case

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
    verdict: str = "FAIL"  # PASS, FAIL or UNPROVEN, as check's overall line
    # --compare: each other configuration's name, file and whether it meets every requirement
    compared: list[dict[str, Any]] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        return {
            "compared": self.compared,
            "out": str(self.out_dir),
            "files": [str(p) for p in self.files],
            "pdf": str(self.pdf),
            "pages": self.pages,
            "figures": [str(p) for p in self.files if p.suffix == ".png"],
            "verdict": self.verdict,
            "passed": self.passed,
            "seconds": self.seconds,
            "notes": self.notes,
        }


class StepCounter:
    """``report [k/n] label`` lines on stderr (never stdout: ``--json`` keeps it clean).

    The number of steps is known once the measured data are reduced (which pages they
    give): until then a step is ``[k]``, never a guessed total that later changes.
    """

    def __init__(self, stream: Any = None, enabled: bool = True,
                 bar: Callable[[int, int | None, str], None] | None = None) -> None:
        self.total: int | None = None
        self.done, self.enabled, self.bar = 0, enabled, bar
        self.stream = stream if stream is not None else sys.stderr
        self.started = time.perf_counter()

    def __call__(self, label: str) -> None:
        self.done += 1
        if self.bar is not None:  # a terminal's bar (cli/progress.py) instead of lines
            self.bar(self.done, self.total, label)
        if self.enabled:
            elapsed = time.perf_counter() - self.started
            of = f"/{self.total}" if self.total is not None else ""
            self.stream.write(f"report [{self.done}{of}] {label} ({elapsed:.1f} s)\n")
            self.stream.flush()

    def detail(self, done: int, total: int, label: str) -> None:
        """Progress of the campaign's reduction (``fit_campaign``'s progress callback
        signature); it runs beside the steps, in a helper process, so it carries no step
        number of its own."""
        if self.enabled and done < total:
            elapsed = time.perf_counter() - self.started
            self.stream.write(
                f"report   reducing {done + 1}/{total} {label} ({elapsed:.1f} s)\n"
            )
            self.stream.flush()


def _safe_name(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", text).strip("_") or "engine"


def build_report(
    case_file: Path | str | Case | None,
    out: Path | str,
    campaign: Path | str | None = None,
    progress: bool = True,
    stream: Any = None,
    bar: Callable[[int, int | None, str], None] | None = None,
    compare: list[Any] | None = None,
) -> ReportResult:
    """Build the design-review report for a case (``None``: the shipped TU-Flex case).

    Parameters
    ----------
    case_file : path, Case or None
        Requirement file, or the case already loaded (with ``--set`` applied).
    out : path
        Directory to write; created, or replaced if it holds an earlier report.
    campaign : path or None
        Campaign manifest or thrust table with the measured data (default: see
        :func:`tuflexperf.report.data.find_measured_source`).
    progress : bool
        Write the step counter to ``stream`` (stderr).
    bar : callable or None
        ``bar(done, total, label)`` after each step (the command line's progress bar).
    compare : list of path or Case, optional
        Other configurations (``--compare``), drawn over this one on every comparable
        figure, their verdicts beside its own (they are B, C, ... in that order).

    Returns
    -------
    ReportResult
    """
    from tuflexperf.io.case import Case, load_case
    from tuflexperf.io.files import staged_directory

    started = time.perf_counter()
    out = Path(out).absolute()
    # bad input fails here, before anything is written; a Case is one already loaded (--set)
    case = case_file if isinstance(case_file, Case) else load_case(case_file)
    compared = [_compared_case(given) for given in compare or []]
    campaign_path = Path(campaign) if campaign is not None else None
    if campaign_path is not None and not campaign_path.is_file():
        from tuflexperf.io.files import why_not_a_file

        raise InputError(f"--campaign: {why_not_a_file(campaign_path)}: {campaign_path}")
    if campaign_path is not None:
        _check_campaign(campaign_path)  # before any step is shown or anything is written
    inputs = _report_inputs(case, campaign_path)
    from tuflexperf.io.case import case_files

    inputs += [path for other in compared for _, path in case_files(other)]
    with (staged_directory(out, "report", inputs) as staging,
          swap.scratch("report") as kept):
        result = _render(case, staging, campaign_path, StepCounter(stream, progress, bar),
                         Path(kept), compared)
    files = [out / p.name for p in result.files]
    return ReportResult(
        out_dir=out,
        files=files,
        pdf=out / PDF_NAME,
        pages=result.pages,
        passed=result.passed,
        seconds=time.perf_counter() - started,
        notes=result.notes,
        verdict=result.verdict,
        compared=result.compared,
    )


def _compared_case(given: Any) -> Any:
    """A ``--compare`` configuration: a Case as given, or a requirement file loaded (its
    errors named as the flag's)."""
    from tuflexperf.io.case import Case, load_case

    if isinstance(given, Case):
        return given
    try:
        return load_case(Path(given))
    except InputError as exc:
        raise InputError.of([f"--compare {given}: {p}" for p in exc.problems]) from None


def _report_inputs(case: Any, campaign: Path | None) -> list[Path]:
    """Every file the report reads: the case's, and the measured data's (the campaign
    manifest or thrust table and the manifest's runs); the output folder may hold none."""
    from tuflexperf.io.campaign import load_campaign
    from tuflexperf.io.case import case_files
    from tuflexperf.report.data import find_measured_source

    inputs = [path for _, path in case_files(case)]
    try:
        source = find_measured_source(case, campaign)
    except InputError:
        return inputs  # said where the measured data are read
    if source is None:
        return inputs
    inputs.append(source)
    try:
        inputs.extend(run.path for run in load_campaign(source).runs)
    except InputError:
        pass  # a thrust table, a propeller manifest, or a manifest reported where it is read
    return inputs


def _check_campaign(path: Path) -> None:
    """A campaign manifest given to ``--campaign`` is validated here, its errors named as the
    flag's: a case file given there failed after the first step, without the flag's name
    (outside audit). Tables and propeller manifests are read where they are reduced."""
    from tuflexperf.io.campaign import load_campaign
    from tuflexperf.io.proptables import is_propeller_manifest
    from tuflexperf.reduction.pipeline import is_thrust_table

    if is_thrust_table(path) or is_propeller_manifest(path):
        return
    try:
        load_campaign(path)
    except InputError as exc:
        raise InputError(f"--campaign: {exc}") from None


def _render(case: Any, folder: Path, campaign: Path | None, step: StepCounter,
            kept: Path, compared: list[Any]) -> ReportResult:
    """Draw every page into ``folder``; ``kept`` is a private temporary folder for the
    one-page PDFs that the PDF is assembled from."""
    writers: list[Any] = []
    try:  # bad campaign, interrupt: every forked helper stopped, no page written after
        return _render_pages(case, folder, campaign, step, kept, writers, compared)
    finally:
        from tuflexperf.io.files import stop_helpers

        stop_helpers(writers)


def _render_pages(case: Any, folder: Path, campaign: Path | None, step: StepCounter,
                  kept: Path, writers: list[Any], compared: list[Any]) -> ReportResult:
    """:func:`_render`'s work; each forked helper is listed in ``writers`` as it starts."""
    from tuflexperf.io.files import raise_if_interrupted

    # The campaign is reduced by a forked copy of this process from the start (before
    # matplotlib is imported: it needs none), while this one solves the analyses and a
    # second copy draws their pages (the two need nothing of each other's).
    reduced = _start_campaign_reduction(case, campaign, kept, step.detail, writers)
    from tuflexperf.report import analysis_figures as af
    from tuflexperf.report import figures as fg
    from tuflexperf.report import review_figures as rf

    fg.use_agg()
    from tuflexperf.analysis.study import Study
    from tuflexperf.report.data import run_analyses

    fg.preload()  # once here, inherited by every writer forked below
    analyses = run_analyses(Study(case))
    # the other configurations are solved by whichever process first draws a page that
    # compares (Analyses.others): the first writer, beside the campaign's reduction
    analyses.compare = [(f"{chr(ord('B') + k)}: {other.name}", other)
                        for k, other in enumerate(compared)]
    step("analyses: check, take-off, trim, OEI, endurance, performance, margins, mission")
    # Each page is drawn once, as a vector PDF page (``kept/NAME.pdf``); its PNG is that
    # page rasterised by PDFium, so the PNG is the PDF's page, and the PDF is those pages
    # put together (issue 9: a page was drawn twice, once per backend). The pages of the
    # analyses alone are drawn by a forked writer while the campaign is still reduced;
    # those of the measured data by a second writer (last page first) while this process
    # draws from the first page on. Whoever claims a page first (a file created
    # exclusively in ``kept``) draws it.
    analysis_pages: dict[str, Callable[[], Any]] = {
        "01_requirements": lambda: fg.requirement_table(case, analyses),
        **({"01b_compared": lambda: rf.compare_verdicts(case, analyses)} if compared else {}),
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
    # issue 47 item 4: the views no requirement asks for (solved in the writer that draws them)
    analysis_pages["07b_takeoff_profile"] = lambda: rf.takeoff_profile(case, analyses)
    analysis_pages["08c_flight_envelope"] = lambda: rf.flight_envelope(case, analyses)
    if case.battery_path is not None:
        analysis_pages["09b_mass_trade"] = lambda: rf.mass_trade(case, analyses)
    # issue 45 item 3; without flights page 1 says none is given (--compare: any configuration's)
    if analyses.flights or any(flights for _, flights in analyses.compared_flights):
        from tuflexperf.report.flown_figures import predicted_vs_flown

        analysis_pages["06d_predicted_flown"] = lambda: predicted_vs_flown(case, analyses)
    # The first writer starts with the tornado: the margins behind it (about 1 s of batch
    # solves) are then solved while the campaign is reduced, not at the end.
    first = sorted(analysis_pages.items(), key=lambda item: item[0] != "11_tornado")
    if compared:  # the comparison first: its configurations' analyses are solved there
        first = sorted(first, key=lambda item: item[0] != "01b_compared")
    _start_helper(_draw_pages, (first, folder, kept), writers)
    measured = reduced()
    raise_if_interrupted()
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
    measured_pages["06c_predicted_measured"] = lambda: rf.predicted_vs_measured(
        case, analyses, measured)
    named = sorted({**analysis_pages, **measured_pages}.items())  # the report's page order
    notes = measured.notes + analyses.notes
    from tuflexperf import __version__
    from tuflexperf.report.data import inputs_digest
    from tuflexperf.report.first_page import first_page, timestamp

    # The page count is known now: every page's footer is written down for the writers,
    # who stamp each page they draw from here on (and those drawn before) and render its PNG.
    now = timestamp()  # one date for the first page and every footer
    hashed = input_hashes(case, measured, compared)
    digest = inputs_digest([h for h, _, _ in hashed])
    order = ["_title", *(name for name, _ in named), *(["_notes"] if notes else []), "_hashes"]
    also = [other.name for other in compared]
    texts = {name: footer_texts(case, k, len(order), digest, __version__, now, also)
             for k, name in enumerate(order, start=1)}
    _write_footers(kept, texts)
    _start_helper(_draw_pages, (list(measured_pages.items())[::-1], folder, kept), writers)
    step.total = step.done + len(named) + 2
    # the title page carries the PDF's metadata: the assembled PDF keeps the first page's
    _save_pdf_pages(
        [first_page(case, measured, analyses, now,
                    notes_page=len(named) + 2 if notes else None)],
        kept / "_title.pdf",
        metadata={"Title": f"Design review: {' vs '.join([case.name, *also])}",
                  "Creator": f"tuflexperf {__version__}"},
    )
    _stamp_page(kept, "_title", [texts["_title"]]).close()
    step("title page")
    _draw_pages(named, folder, kept, step)  # what the writers have not claimed yet
    # the inputs' sha256 last, as the title page says, after what the report leaves out
    end = [fg.text_page("What this report leaves out, and why", [f"- {n}" for n in notes])
           ] if notes else []
    end.append(_hash_page(case, measured, hashed))
    for fig in end:
        reserve(fig)
    _save_pdf_pages(end, kept / "_end.pdf")
    _stamp_page(kept, "_end", [texts[n] for n in order[len(named) + 1:]]).close()
    for writer in writers:
        writer.join()
    # never a report without its figures: a page a writer did not finish is drawn here
    for part in folder.glob("*.part"):
        part.unlink()
    for name, draw in named:
        if not (kept / f"{name}.pdf").is_file():
            _draw_page(name, draw, folder, kept)
        if not (kept / f"{name}.footed.pdf").is_file() or not (folder / f"{name}.png").is_file():
            _finish_page(name, folder, kept, texts[name])
    raise_if_interrupted()
    pdf_path = folder / PDF_NAME
    page_count = _assemble_pdf(
        [kept / f"{name}.footed.pdf" for name in ("_title", *(n for n, _ in named), "_end")],
        pdf_path,
    )
    step("review.pdf")
    return ReportResult(
        out_dir=folder,
        files=[*(folder / f"{name}.png" for name, _ in named), pdf_path],
        pdf=pdf_path,
        pages=page_count,
        passed=all(v.passed for v in analyses.verdicts),
        seconds=0.0,
        notes=notes,
        verdict=overall_verdict([v.verdict for v in analyses.verdicts]),
        compared=[{"label": label, "name": other.name, "case": str(other.path)}
                  for label, other in analyses.compare],
    )


def _start_campaign_reduction(case: Any, campaign: Path | None, keep: Path,
                              progress: Callable[..., None],
                              helpers: list[Any]) -> Callable[[], Any]:
    """Start reducing the campaign (:func:`~tuflexperf.report.data.load_measured`) in a
    forked helper (:func:`_start_helper`); the function returned waits for it and returns
    the :class:`~tuflexperf.report.data.Measured` (or raises its error here). Without a
    helper, that function reduces the campaign here."""
    import pickle

    from tuflexperf.report.data import load_measured

    def here() -> Any:
        return load_measured(case, campaign, progress=progress)

    path = keep / "measured.pickle"
    process = _start_helper(_reduce_campaign, (case, campaign, path, progress), helpers)
    if process is None:
        return here

    def result() -> Any:
        process.join()
        if not path.is_file():  # the process died without an answer: reduce here instead
            return here()
        with open(path, "rb") as handle:
            ok, value = pickle.load(handle)
        if not ok:
            raise value
        return value

    return result


def _reduce_campaign(case: Any, campaign: Path | None, path: Path,
                     progress: Callable[..., None]) -> None:
    """The forked reduction's body: the Measured, or the error it raised, pickled to
    ``path``."""
    import pickle

    from tuflexperf.report.data import load_measured

    try:
        answer: tuple[bool, Any] = (True, load_measured(case, campaign, progress=progress))
    except Exception as exc:  # raised again by the report's own process
        answer = (False, exc)
    staged = path.with_name(path.name + ".part")
    try:
        with open(staged, "wb") as handle:
            pickle.dump(answer, handle, protocol=pickle.HIGHEST_PROTOCOL)
    except Exception:  # an error that does not pickle: the report's process reduces again
        staged.unlink(missing_ok=True)
        return
    os.replace(staged, path)  # never read half-written


def _save_pdf_pages(figures: list[Any], path: Path,
                    metadata: dict[str, str] | None = None) -> None:
    """Vector PDF pages, written beside ``path`` and renamed (never read half-written)."""
    from matplotlib.backends.backend_pdf import PdfPages

    staged = path.with_name(path.name + ".part")
    with PdfPages(staged, metadata=metadata) as pdf:
        for fig in figures:
            pdf.savefig(fig)
    os.replace(staged, path)


def rasterise_page(pdf_page: Any, png: Path, index: int = 0) -> None:
    """Page ``index`` of ``pdf_page`` (a path or an open pypdfium2 document) as a PNG at
    :data:`PNG_DPI` (PDFium)."""
    import pypdfium2
    from PIL.PngImagePlugin import PngInfo

    from tuflexperf import __version__

    if isinstance(pdf_page, pypdfium2.PdfDocument):
        image = pdf_page[index].render(scale=PNG_DPI / 72.0).to_pil()
    else:
        document = pypdfium2.PdfDocument(pdf_page)
        try:
            image = document[index].render(scale=PNG_DPI / 72.0).to_pil()
        finally:
            document.close()
    info = PngInfo()
    info.add_text("Software", f"tuflexperf {__version__}")  # whose file it is (SPEC 5)
    staged = png.with_name(png.name + ".part")
    image.save(staged, format="png", dpi=(PNG_DPI, PNG_DPI), pnginfo=info,
               compress_level=PNG_COMPRESSION)
    os.replace(staged, png)  # a writer stopped half-way leaves no half PNG


def _draw_page(name: str, draw: Callable[[], Any], folder: Path, kept: Path) -> None:
    """One page drawn once: ``kept/NAME.pdf`` (vector), with the footer's strip kept free;
    once the footers are known it is stamped and rendered (:func:`_finish_pages`)."""
    fig = draw()
    reserve(fig)
    _save_pdf_pages([fig], kept / f"{name}.pdf")


FOOTERS = "_footers.json"


def _write_footers(kept: Path, texts: dict[str, Any]) -> None:
    """Every page's footer (left, right), by page name, for the forked writers."""
    import json

    staged = kept / (FOOTERS + ".part")
    staged.write_text(json.dumps(texts), encoding="utf-8")
    os.replace(staged, kept / FOOTERS)  # never read half-written


def _stamp_page(kept: Path, name: str, texts: list[Any]) -> Any:
    """``kept/NAME.pdf`` with its footers stamped, as ``kept/NAME.footed.pdf``; returns the
    stamped document (open: the caller closes it)."""
    import pypdfium2

    document = pypdfium2.PdfDocument(kept / f"{name}.pdf")
    try:
        stamp(document, [tuple(t) for t in texts])
        staged = kept / f"{name}.footed.pdf.part"
        document.save(staged)
        os.replace(staged, kept / f"{name}.footed.pdf")
    except BaseException:
        document.close()
        raise
    return document


def _finish_page(name: str, folder: Path, kept: Path, text: Any) -> None:
    """A drawn page stamped with its footer, and its PNG rendered from the stamped page."""
    document = _stamp_page(kept, name, [text])
    try:
        rasterise_page(document, folder / f"{name}.png")
    finally:
        document.close()


def _finish_pages(names: list[str], folder: Path, kept: Path) -> None:
    """Stamp and render each drawn page of ``names`` that this process claims first, once
    the footers are known (before that: nothing)."""
    import json

    if not (kept / FOOTERS).is_file():
        return
    texts = json.loads((kept / FOOTERS).read_text(encoding="utf-8"))
    for name in names:
        if (kept / f"{name}.pdf").is_file() and _claim(kept, f"{name}.footer"):
            _finish_page(name, folder, kept, texts[name])


def _assemble_pdf(pages: list[Path], path: Path) -> int:
    """The PDFs (each page stamped with its footer) put together in order (PDFium); returns
    the page count."""
    import pypdfium2

    document = pypdfium2.PdfDocument(pages[0])
    try:
        for page in pages[1:]:
            part = pypdfium2.PdfDocument(page)
            try:
                document.import_pages(part)
            finally:
                part.close()
        count = len(document)
        document.save(path)
    finally:
        document.close()
    return count


def _claim(keep: Path, name: str) -> bool:
    """True for the one process that first claims page ``name`` (an exclusive create)."""
    try:
        os.close(os.open(keep / f"{name}.claim", os.O_CREAT | os.O_EXCL | os.O_WRONLY))
    except FileExistsError:
        return False
    return True


def _draw_pages(named: list[tuple[str, Callable[[], Any]]], folder: Path, keep: Path,
                step: Callable[[str], None] | None = None) -> None:
    """Draw each page that this process claims (:func:`_draw_page`), then stamp and render
    each drawn page it claims (:func:`_finish_pages`), as soon as the footers are known."""
    from tuflexperf.io.files import raise_if_interrupted

    for name, draw in named:
        raise_if_interrupted()
        if _claim(keep, name):
            _draw_page(name, draw, folder, keep)
            _finish_pages([name], folder, keep)
        if step is not None:
            step(name)
    raise_if_interrupted()
    _finish_pages([name for name, _ in named], folder, keep)  # those drawn before the count


def _start_helper(target: Callable[..., None], args: tuple[Any, ...],
                  helpers: list[Any]) -> Any:
    """``target(*args)`` in a forked helper (:func:`tuflexperf.io.files.start_helper`),
    listed in ``helpers``; None where fork is not available or
    ``TUFLEXPERF_SERIAL_REPORT`` is set (the caller then does the work)."""
    from tuflexperf.io.files import start_helper

    if os.environ.get("TUFLEXPERF_SERIAL_REPORT") or not hasattr(os, "fork"):
        return None
    return start_helper(target, args, helpers)


def _hash_page(case: Any, measured: Any, hashed: list[tuple[str, str, str]]) -> Any:
    from tuflexperf.report import figures as fg

    return fg.text_page("Inputs of this report (sha256)", hash_lines(case, measured, hashed))


def input_hashes(case: Any, measured: Any,
                 compared: list[Any] | None = None) -> list[tuple[str, str, str]]:
    """(sha256, role, path as shown) of every input of the report, in the last page's order
    (each ``--compare`` configuration's files last, their role led by its letter)."""
    from tuflexperf.io.case import case_files
    from tuflexperf.io.files import sha256_of
    from tuflexperf.io.inputs import path_text
    from tuflexperf.report.data import input_files

    hashed = []
    root = case.path.parent
    files = list(input_files(case, measured))
    for k, other in enumerate(compared or []):
        files += [(f"{chr(ord('B') + k)}: {role}", path) for role, path in case_files(other)]
    for role, path in files:
        try:
            shown = os.path.relpath(path, root)
        except ValueError:
            shown = str(path)
        hashed.append((sha256_of(path), role, path_text(shown)))  # \xfc: fonts take it
    return hashed


def hash_lines(case: Any, measured: Any,
               hashed: list[tuple[str, str, str]] | None = None) -> list[str]:
    """Every input of the report with its sha256 (the last page), and how the footer's
    short hash is made from them."""
    from tuflexperf.report.data import inputs_digest

    hashed = input_hashes(case, measured) if hashed is None else hashed
    lines = [f"  {digest}  {role:<13} {shown}" for digest, role, shown in hashed]
    lines += ["", f"inputs {inputs_digest([h for h, _, _ in hashed])} in every page's footer: "
              "the first 8 hex digits of the sha256 of the hashes above, each followed by a "
              "newline, in this order"]
    return lines
