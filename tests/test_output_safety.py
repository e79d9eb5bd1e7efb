"""Nothing is lost (SPEC 5): what an output path may replace, found by a hostile audit.

- an earlier output folder the user has added files to is not replaced (they were deleted);
- a symbolic link given as the output is refused (it was replaced and left as debris);
- a user's CSV that only looks like an output (an extra column) is not replaced;
- an interrupt during the swap of an earlier output leaves no hidden folder behind.

The commands run in this process (``tests.conftest.tuflexperf``, the CLI's entry with its
exit status); in a subprocess only what needs one: a FIFO or /dev/zero where a regression
would block or fill memory, names that are no UTF-8 (the bytes printed), a user without
root's right to write, a forked helper's own stderr.
"""

from __future__ import annotations

import ast
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import Ran, tuflexperf
from tuflexperf.errors import InputError
from tuflexperf.io import artefacts, files

ROOT = Path(__file__).resolve().parent.parent
TUFLEXPERF = [sys.executable, "-m", "tuflexperf"]


def _run(cwd: Path, *args: str) -> Ran:
    return tuflexperf(*args, cwd=cwd)


def _process(cwd: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*TUFLEXPERF, *args], cwd=cwd, capture_output=True, text=True,
                          timeout=300)


def _tree(folder: Path) -> dict[str, bytes]:
    return {p.relative_to(folder).as_posix(): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.mark.parametrize("added", ["NOTES.txt", "sub/keep.c"])
def test_an_earlier_output_with_the_users_files_in_it_is_not_replaced(tmp_path, added) -> None:
    assert _run(tmp_path, "export", "--out", "exp").returncode == 0
    assert _run(tmp_path, "export", "--out", "exp").returncode == 0  # its own: replaced
    user_file = tmp_path / "exp" / added
    user_file.parent.mkdir(exist_ok=True)
    user_file.write_text("the user's own\n")
    before = _tree(tmp_path / "exp")
    again = _run(tmp_path, "export", "--out", "exp")
    assert again.returncode == 2, again.stderr
    assert added in again.stderr and len(again.stderr.strip().splitlines()) == 1
    assert _tree(tmp_path / "exp") == before


def test_the_marker_lists_every_file_written_nested_ones_too(tmp_path) -> None:
    with files.staged_directory(tmp_path / "out", "probe") as staging:
        (staging / "a.txt").write_text("a")
        (staging / "kept").mkdir()
        (staging / "kept" / "b.pdf").write_text("b")
    import json

    marker = json.loads((tmp_path / "out" / files.MARKER).read_text())
    assert marker == {"command": "probe", "files": ["a.txt", "kept/b.pdf"],
                      "sha256": {"a.txt": files.sha256_of(tmp_path / "out" / "a.txt"),
                                 "kept/b.pdf": files.sha256_of(tmp_path / "out" / "kept/b.pdf")}}


def test_a_symbolic_link_as_the_output_is_refused_and_left_alone(tmp_path) -> None:
    (tmp_path / "target").mkdir()
    (tmp_path / "link").symlink_to("target")
    out = _run(tmp_path, "export", "--out", "link")
    assert out.returncode == 2 and "symbolic link" in out.stderr
    assert (tmp_path / "link").is_symlink() and not any((tmp_path / "target").iterdir())
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link", "target"]  # no debris
    (tmp_path / "mine.csv").write_text("the user's own\n")
    (tmp_path / "grid.csv").symlink_to("mine.csv")
    csv = _run(tmp_path, "sweep", "--vary", "aircraft.mass_kg=20:22:2", "--csv", "grid.csv")
    assert csv.returncode == 2 and "symbolic link" in csv.stderr
    assert (tmp_path / "mine.csv").read_text() == "the user's own\n"


@pytest.mark.parametrize(("flag_args", "header"), [
    (("fit", "{campaign}", "--out", "f.yaml", "--table", "mine.csv"),
     "engine,throttle,airspeed_m_s,thrust_n,comment"),
    # the user's own thrust table in SPEC 4's input format, also from a table refit: it was
    # taken for the refit's four-column output and replaced (outside audit)
    (("fit", "{campaign}", "--out", "f.yaml", "--table", "mine.csv"),
     "engine,throttle,airspeed_m_s,thrust_n"),
    (("fit", "{table}", "--out", "f.yaml", "--table", "mine.csv"),
     "engine,throttle,airspeed_m_s,thrust_n"),
    (("mission", "{mission}", "--csv", "mine.csv"), "time_s,segment,my_notes"),
    (("sweep", "--vary", "aircraft.mass_kg=20:22:2", "--csv", "mine.csv"),
     "aircraft.mass_kg,my_value,my_limit,my_passed"),
])
def test_a_users_csv_that_looks_like_an_output_is_not_replaced(tmp_path, flag_args,
                                                               header) -> None:
    mine = tmp_path / "mine.csv"
    mine.write_text(header + "\n1,2,3,4\n")
    campaign = ROOT / "data/tuflex/campaign/campaign.yaml"
    mission = next((ROOT / "data/tuflex/missions").glob("*.yaml"))
    table = tmp_path / "input_table.csv"
    table.write_text("engine,throttle,airspeed_m_s,thrust_n\n" + "".join(
        f"E,{x / 10:g},{v},{30 * x / 10 + 20 * (x / 10) ** 2 - 0.2 * v:g}\n"
        for v in (0, 10, 20, 30) for x in range(1, 11)))
    args = [a.format(campaign=campaign, mission=mission, table=table) for a in flag_args]
    out = _run(tmp_path, *args)
    assert out.returncode == 2 and "mine.csv" in out.stderr, out.stderr
    assert mine.read_text() == header + "\n1,2,3,4\n"
    # the command's own earlier output is replaced as before
    own = [a.replace("mine.csv", "own.csv") for a in args]
    assert _run(tmp_path, *own).returncode == 0
    assert _run(tmp_path, *own).returncode == 0


def test_a_command_never_replaces_what_another_command_wrote(tmp_path, shipped_report) -> None:
    """SPEC 5: no command replaces a file it did not write itself. A mission's --csv onto
    fit's propulsion file, a sweep's plot onto a report page, were accepted as "an earlier
    output of tuflexperf" (outside audit)."""
    campaign = ROOT / "data/tuflex/campaign/campaign.yaml"
    mission = next((ROOT / "data/tuflex/missions").glob("*.yaml"))
    assert _run(tmp_path, "fit", str(campaign), "--out", "p.yaml").returncode == 0
    assert _run(tmp_path, "mission", str(mission), "--csv", "m.csv").returncode == 0
    vary = ("sweep", "--vary", "aircraft.mass_kg=24:26:2")
    assert _run(tmp_path, *vary, "--csv", "s.csv", "--plot", "s.png").returncode == 0
    shutil.copytree(shipped_report.out, tmp_path / "rv")  # an earlier report's output
    written = {name: (tmp_path / name).read_bytes() for name in
               ("p.yaml", "p_thrust_table.csv", "m.csv", "s.csv", "s.png",
                "rv/01_requirements.png")}
    attempts = [
        ("mission", ("mission", str(mission), "--csv", "p.yaml"), "fit"),
        ("mission", ("mission", str(mission), "--csv", "p_thrust_table.csv"), "fit"),
        ("mission", ("mission", str(mission), "--csv", "s.csv"), "sweep"),
        ("sweep", (*vary, "--csv", "m.csv"), "mission"),
        ("sweep", (*vary, "--csv", "p_thrust_table.csv"), "fit"),
        ("sweep", (*vary, "--plot", "rv/01_requirements.png"), "report"),
        ("fit", ("fit", str(campaign), "--out", "q.yaml", "--table", "m.csv"), "mission"),
    ]
    for command, args, owner in attempts:
        out = _run(tmp_path, *args)
        assert out.returncode == 2, (args, out.stderr)
        assert f"written by `tuflexperf {owner}`, not by `tuflexperf {command}`" in out.stderr
        assert len(out.stderr.strip().splitlines()) == 1
    assert {name: (tmp_path / name).read_bytes() for name in written} == written
    assert not (tmp_path / "q.yaml").exists()
    # each command still replaces its own
    assert _run(tmp_path, "mission", str(mission), "--csv", "m.csv").returncode == 0
    assert _run(tmp_path, *vary, "--csv", "s.csv", "--plot", "s.png").returncode == 0


def test_artefact_of_reads_the_png_software_chunk() -> None:
    import io

    from PIL import Image
    from PIL.PngImagePlugin import PngInfo

    def png(software: str | None) -> bytes:
        info = PngInfo()
        if software is not None:
            info.add_text("Software", software)
        buffer = io.BytesIO()
        Image.new("RGB", (4, 4)).save(buffer, format="png", pnginfo=info)
        return buffer.getvalue()

    assert artefacts.artefact_of(png("tuflexperf sweep")) == "sweep plot"
    assert artefacts.artefact_of(png("tuflexperf 0.1.0")) == "report page"
    # carpet plots of earlier versions
    assert artefacts.artefact_of(png("tuflexperf")) == "sweep plot"
    assert artefacts.artefact_of(png("tuflexperfX")) is None
    assert artefacts.artefact_of(png("GIMP")) is None
    assert artefacts.artefact_of(png(None)) is None


def test_the_recognised_sweep_names_are_every_requirement_check_can_name() -> None:
    # every verdict the analyses name, wherever in analysis/ it is made (the mission's
    # solved time is made beside the mission, not in requirements.py)
    names = {call.args[0].value for path in sorted((ROOT / "tuflexperf/analysis").glob("*.py"))
             for call in ast.walk(ast.parse(path.read_text()))
             if isinstance(call, ast.Call) and getattr(call.func, "id", None) == "Verdict"
             and call.args and isinstance(call.args[0], ast.Constant)}
    assert {"takeoff_ground_roll", "mission_solved_time"} <= names
    assert names == set(artefacts.REQUIREMENT_NAMES)


def _stage_new_output_interrupted(tmp_path: Path, monkeypatch) -> None:
    """Stage 'new.txt' over tmp_path/out with tuflexperf's own SIGINT handler installed; the
    patched file operation sends the interrupt, which must come out as KeyboardInterrupt."""
    monkeypatch.setattr(files, "_signals_received", [])
    monkeypatch.setattr(files, "_committed", [False])
    previous = signal.signal(signal.SIGINT, files._raise_interrupt)
    try:
        with pytest.raises(KeyboardInterrupt):
            with files.staged_directory(tmp_path / "out", "probe") as staging:
                (staging / "new.txt").write_text("new")
    finally:
        signal.signal(signal.SIGINT, previous)


@pytest.mark.parametrize("exchange", [True, False])
def test_an_interrupt_during_the_renames_keeps_the_earlier_output(tmp_path, monkeypatch,
                                                                  exchange):
    """SIGINT a few ms after report's last page landed while the folders were renamed: the
    new output replaced the earlier one and the run still said "aborted" (outside audit).
    Interrupted before the swap is done, the earlier output is put back: after the one
    exchange, or between the two renames where the file system has no exchange."""
    from tuflexperf.io import swap

    with files.staged_directory(tmp_path / "out", "probe") as staging:
        (staging / "old.txt").write_text("earlier")
    before = _tree(tmp_path / "out")
    real_replace, real_exchange = os.replace, swap.exchange
    calls = []

    def interrupted_replace(src, dst):
        calls.append(Path(dst).name)
        if len(calls) == 2:  # the new output moves in: the interrupt lands right there
            os.kill(os.getpid(), signal.SIGINT)
        real_replace(src, dst)

    def interrupted_exchange(a, b):
        calls.append(Path(b).name)
        done = real_exchange(a, b)
        if len(calls) == 1:  # the new output is in: the interrupt lands right there
            os.kill(os.getpid(), signal.SIGINT)
        return done

    if exchange:
        monkeypatch.setattr(swap, "exchange", interrupted_exchange)
    else:
        monkeypatch.setattr(swap, "exchange", lambda a, b: False)
        monkeypatch.setattr(files.os, "replace", interrupted_replace)
    _stage_new_output_interrupted(tmp_path, monkeypatch)
    assert len(calls) == 2 if exchange else len(calls) == 4  # there, and back
    assert _tree(tmp_path / "out") == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]  # no .old-*, no .tmp-*


def test_an_interrupt_after_the_swap_leaves_the_new_output_whole_and_the_run_done(
    tmp_path, monkeypatch
) -> None:
    """Once the new output has replaced the earlier one the run is done: an interrupt while
    the earlier output is removed is not the run's (it said "aborted", exit 130, with the
    earlier output gone; outside audit), and leaves no debris."""
    with files.staged_directory(tmp_path / "out", "probe") as staging:
        (staging / "old.txt").write_text("earlier")
    removed = []
    real_rmtree = __import__("shutil").rmtree

    def interrupted_rmtree(path, ignore_errors=False):
        os.kill(os.getpid(), signal.SIGINT)  # lands while the earlier output is removed
        removed.append(Path(path).name)
        real_rmtree(path, ignore_errors=ignore_errors)

    monkeypatch.setattr("shutil.rmtree", interrupted_rmtree)
    monkeypatch.setattr(files, "_signals_received", [])
    monkeypatch.setattr(files, "_committed", [False])
    previous = signal.signal(signal.SIGINT, files._raise_interrupt)
    try:
        with files.staged_directory(tmp_path / "out", "probe") as staging:
            (staging / "new.txt").write_text("new")
        assert files.output_committed() and not files.interrupted()
    finally:
        signal.signal(signal.SIGINT, previous)
    assert removed and removed[0].startswith((".out.old-", ".out.tmp-"))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]  # no .old-*, no .tmp-*
    assert _tree(tmp_path / "out").keys() == {"new.txt", files.MARKER}


def test_an_interrupt_a_library_dropped_earlier_keeps_the_earlier_output(
    tmp_path, monkeypatch
) -> None:
    """An interrupt noted before the swap (raised inside a library, which dropped it) means
    the run was interrupted: its output does not replace the earlier one."""
    with files.staged_directory(tmp_path / "out", "probe") as staging:
        (staging / "old.txt").write_text("earlier")
    before = _tree(tmp_path / "out")
    monkeypatch.setattr(files, "_signals_received", [signal.SIGINT])
    monkeypatch.setattr(files, "_committed", [False])
    with pytest.raises(KeyboardInterrupt):
        with files.staged_directory(tmp_path / "out", "probe") as staging:
            (staging / "new.txt").write_text("new")
    assert _tree(tmp_path / "out") == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]
    with pytest.raises(KeyboardInterrupt):
        files.write_files_atomically({tmp_path / "a.csv": "new"})
    assert not (tmp_path / "a.csv").exists()


def test_an_output_folder_that_holds_an_input_is_not_replaced(tmp_path) -> None:
    """A case saved in an earlier export's folder under a name export writes was replaced
    by export's JSON (outside audit); the report's folder likewise."""
    assert _run(tmp_path, "export", "--format", "json", "--out", "ex").returncode == 0
    case = tmp_path / "ex" / "tfp_thrust.json"
    shipped = ROOT / "requirements" / "tuflex.yaml"
    text = shipped.read_text().replace("../data/", str(ROOT / "data") + "/")
    case.write_text(text)
    done = _run(tmp_path, "export", "--case", str(case), "--format", "json", "--out", "ex")
    assert done.returncode == 2, done.stderr
    # refused as the input it is, or as a file changed since export wrote it
    assert ("an input of this command" in done.stderr or "tfp_thrust.json, changed since"
            in done.stderr) and len(done.stderr.splitlines()) == 1
    assert case.read_text() == text
    with pytest.raises(InputError, match="an input of this command"):
        files.check_output_dir(tmp_path / "ex", "export", [case])


def test_a_fifo_as_an_output_is_refused_not_waited_on(tmp_path) -> None:
    """Opening a FIFO to see who wrote it blocked for ever (outside audit)."""
    fifo = tmp_path / "out.fifo"
    os.mkfifo(fifo)
    done = subprocess.run([*TUFLEXPERF, "sweep", "--vary", "aircraft.mass_kg=20:30:2",
                           "--csv", str(fifo)], cwd=tmp_path, capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 2 and "not a regular file" in done.stderr


def test_an_interrupt_between_two_files_puts_both_earlier_files_back(tmp_path, monkeypatch):
    """fit writes the propulsion file and its thrust table together: a SIGINT between the two
    renames left the new file beside the earlier table, "aborted" (outside audit)."""
    first, second = tmp_path / "p.yaml", tmp_path / "p_table.csv"
    files.write_files_atomically({first: "earlier p\n", second: "earlier table\n"})
    real_replace = os.replace
    calls = []

    def interrupted_replace(src, dst):
        calls.append(Path(dst).name)
        real_replace(src, dst)
        if Path(dst) == first:  # the first new file is in place: the interrupt lands here
            os.kill(os.getpid(), signal.SIGINT)

    monkeypatch.setattr(files.os, "replace", interrupted_replace)
    monkeypatch.setattr(files, "_signals_received", [])
    monkeypatch.setattr(files, "_committed", [False])
    previous = signal.signal(signal.SIGINT, files._raise_interrupt)
    try:
        with pytest.raises(KeyboardInterrupt):
            files.write_files_atomically({first: "new p\n", second: "new table\n"})
    finally:
        signal.signal(signal.SIGINT, previous)
    assert first.read_text() == "earlier p\n" and second.read_text() == "earlier table\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.yaml", "p_table.csv"]
    assert any(name == first.name for name in calls)


def test_a_failed_write_leaves_no_folder_it_made(tmp_path) -> None:
    """--out new/sub/p.yaml with an unwritable table: new/ and new/sub/ stayed (audit)."""
    blocker = tmp_path / "blocker"
    blocker.write_text("a file where a folder is wanted")
    with pytest.raises(InputError, match="blocker"):
        files.write_files_atomically({tmp_path / "new" / "sub" / "p.yaml": "x",
                                      blocker / "t.csv": "y"})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["blocker"]


def test_a_file_being_replaced_is_there_at_every_moment(tmp_path, monkeypatch) -> None:
    """The earlier output moved aside before the new one moved in: a crash between the two
    renames would have left no file at all (outside review). It keeps its name throughout."""
    target = tmp_path / "p.yaml"
    files.write_files_atomically({target: "earlier\n"})
    real_replace = os.replace
    seen = []

    def watched_replace(src, dst):
        seen.append(target.exists())
        real_replace(src, dst)
        seen.append(target.exists())

    monkeypatch.setattr(files.os, "replace", watched_replace)
    files.write_files_atomically({target: "new\n"})
    assert seen and all(seen) and target.read_text() == "new\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.yaml"]


_MISSION = str(ROOT / "data" / "tuflex" / "missions" / "test_flight.yaml")
_CAMPAIGN = str(ROOT / "data" / "tuflex" / "campaign" / "campaign.yaml")


@pytest.mark.parametrize(("args", "target"), [
    (("export", "--out", "missing/../mine"), "mine"),
    (("report", "--out", "missing/../mine"), "mine"),
    (("fit", _CAMPAIGN, "--out", "missing/../notes.yaml"), "notes.yaml"),
    (("mission", _MISSION, "--csv", "missing/../notes.csv"), "notes.csv"),
    (("sweep", "--vary", "aircraft.mass_kg=20:22:2", "--csv", "missing/../notes.csv"),
     "notes.csv"),
], ids=["export", "report", "fit", "mission", "sweep"])
def test_a_path_through_a_missing_folder_and_back_is_checked_where_it_lands(
        tmp_path, args, target) -> None:
    """``missing/../mine`` is ``mine``: checked as written nothing was there, the missing
    folder was made, and the user's folder deleted or file replaced, exit 0 (outside audit)."""
    if "." in target:
        (tmp_path / target).write_text("the user's own\n")
    else:
        (tmp_path / target).mkdir()
        (tmp_path / target / "thesis.txt").write_text("the user's own\n")
    before = _tree(tmp_path)
    done = _run(tmp_path, *args)
    assert done.returncode == 2, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1 and "refusing" in done.stderr
    assert _tree(tmp_path) == before
    assert not (tmp_path / "missing").exists()  # no folder made on the way


def test_a_new_output_through_a_missing_folder_and_back_makes_no_folder(tmp_path) -> None:
    assert _run(tmp_path, "export", "--out", "missing/../fresh").returncode == 0
    assert (tmp_path / "fresh" / files.MARKER).is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fresh"]


def test_an_earlier_output_the_user_edited_is_not_replaced(tmp_path) -> None:
    """The marker keeps each file's sha256: an edited tfp_thrust.c, or a folder of notes made
    where a written file was, went with the folder on the next export (outside audit)."""
    assert _run(tmp_path, "export", "--out", "exp").returncode == 0
    source = tmp_path / "exp" / "tfp_thrust.c"
    source.write_text(source.read_text() + "/* the user's fix */\n")
    before = _tree(tmp_path / "exp")
    again = _run(tmp_path, "export", "--out", "exp")
    assert again.returncode == 2 and "tfp_thrust.c, changed since" in again.stderr
    assert _tree(tmp_path / "exp") == before
    source.unlink()
    source.mkdir()
    (source / "notes.txt").write_text("the user's own\n")
    again = _run(tmp_path, "export", "--out", "exp")
    assert again.returncode == 2 and "tfp_thrust.c/notes.txt" in again.stderr
    assert (source / "notes.txt").read_text() == "the user's own\n"


@pytest.mark.parametrize("spoil", ["no hashes", "files a number", "deep", "fifo", "zero"])
def test_a_marker_that_cannot_be_trusted_keeps_the_folder(tmp_path, spoil) -> None:
    """A marker without its hashes let an edited file go; "files": 5 and deep nesting gave
    tracebacks; a FIFO there hung; /dev/zero ran out of memory (outside re-audit)."""
    import json

    assert _run(tmp_path, "export", "--out", "exp").returncode == 0
    marker = tmp_path / "exp" / files.MARKER
    data = json.loads(marker.read_text())
    if spoil == "no hashes":
        del data["sha256"]
        marker.write_text(json.dumps(data))
    elif spoil == "files a number":
        data["files"] = 5
        marker.write_text(json.dumps(data))
    elif spoil == "deep":
        marker.write_text('{"command": "export", "x": ' + "[" * 100_000 + "]" * 100_000 + "}")
    else:
        marker.unlink()
        if spoil == "fifo":
            os.mkfifo(marker)
        else:
            marker.symlink_to("/dev/zero")
    (tmp_path / "exp" / "tfp_thrust.c").write_text("/* the user's edit */\n")
    before = {p.name for p in (tmp_path / "exp").iterdir()}
    # a FIFO or /dev/zero in a process: a regression would block or fill this one's memory
    done = (_process if spoil in ("fifo", "zero") else _run)(tmp_path, "export", "--out", "exp")
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1 and "refusing" in done.stderr
    assert {p.name for p in (tmp_path / "exp").iterdir()} == before
    assert (tmp_path / "exp" / "tfp_thrust.c").read_text() == "/* the user's edit */\n"


def test_an_output_with_a_long_name_is_replaced_like_any(tmp_path) -> None:
    """A 240-character output name was written once and then never replaced: the earlier
    file's hidden second name went past 255 bytes (outside re-audit)."""
    name = "p" * 240 + ".csv"
    for _ in range(2):
        done = _run(tmp_path, "sweep", "--vary", "aircraft.mass_kg=20:22:2", "--csv", name)
        assert done.returncode in (0, 1), done.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]
    folder = "d" * 250
    for _ in range(2):
        assert _run(tmp_path, "export", "--format", "json", "--out", folder).returncode == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([name, folder])


@pytest.mark.parametrize("args", [
    ("sweep", "--vary", "aircraft.mass_kg=20:22:2", "--csv", "newdir/"),
    ("sweep", "--vary", "aircraft.mass_kg=20:22:2", "--plot", "newdir/"),
    ("mission", _MISSION, "--csv", "newdir/"),
    ("fit", _CAMPAIGN, "--out", "newdir/"),
    ("fit", _CAMPAIGN, "--out", "p.yaml", "--table", "newdir/"),
], ids=["sweep csv", "sweep plot", "mission", "fit out", "fit table"])
def test_a_file_output_named_as_a_folder_is_refused(tmp_path, args) -> None:
    """``--csv newdir/`` wrote a file named ``newdir``: as a Path the slash was lost
    (outside re-audit)."""
    done = _run(tmp_path, *args)
    assert done.returncode == 2 and "names a folder; give a file name" in done.stderr
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("edit", ["coefficient", "note", "seal dropped", "earlier version"])
def test_a_fitted_yaml_the_user_edited_is_not_replaced(tmp_path, edit) -> None:
    """fit's YAML ends with the sha256 of what precedes it. A propulsion file the user had
    tuned by hand below its first line was replaced by the next fit into the same path: only
    the first line was looked at."""
    from tests.test_fit_cli import write_table

    table = write_table(tmp_path / "table.csv")
    assert _run(tmp_path, "fit", str(table), "--out", "p.yaml").returncode == 0
    path = tmp_path / "p.yaml"
    assert files.seal_intact(path.read_bytes())
    assert _run(tmp_path, "fit", str(table), "--out", "p.yaml").returncode == 0  # its own
    text = path.read_text()
    lines = text.splitlines(keepends=True)
    edited = {
        "coefficient": text.replace("p00: ", "p00: -", 1),
        "note": "".join(lines[:-1]) + "# the user's note\n" + lines[-1],
        "seal dropped": "".join(lines[:-1]),
        # an earlier version's output: the same first line, no seal; edits cannot be told
        "earlier version": "".join(lines[:-1]).replace("delay_s", "delay_s", 1),
    }[edit]
    assert edited != text
    path.write_text(edited)
    again = _run(tmp_path, "fit", str(table), "--out", "p.yaml")
    assert again.returncode == 2, again.stderr
    assert "written by `tuflexperf fit` and changed since" in again.stderr
    assert len(again.stderr.strip().splitlines()) == 1
    assert path.read_text() == edited


def test_a_fitted_battery_file_is_sealed_and_refit_beside_its_input(tmp_path) -> None:
    """A battery file fit wrote is an input to a later fit (it keeps the text, drops the
    earlier seal) and is replaced by the same fit while unedited."""
    from tests.conftest import copy_shipped_case

    copy_shipped_case(tmp_path)
    folder = tmp_path / "data" / "tuflex"
    assert _run(folder, "fit", "battery.yaml", "--out", "b1.yaml").returncode == 0
    assert _run(folder, "fit", "b1.yaml", "--out", "b2.yaml").returncode == 0
    assert _run(folder, "fit", "b1.yaml", "--out", "b2.yaml").returncode == 0
    first, second = (folder / "b1.yaml").read_text(), (folder / "b2.yaml").read_text()
    assert second.count(files.SEAL) == 1 and files.seal_intact(second.encode())
    def body(text: str) -> str:
        return text[: text.index(files.SEAL)]

    assert body(second).replace("from b1.yaml", "from battery.yaml") == body(first)


def test_seal_intact_needs_the_whole_text_as_sealed() -> None:
    text = files.sealed("a: 1\n# comment\n")
    assert files.seal_intact(text.encode())
    assert files.sealed("a: 1") == files.sealed("a: 1\n")
    for spoiled in (text[:-1], text.replace("a: 1", "a: 2"), text + "\n", "a: 1\n",
                    text.replace(files.SEAL, files.SEAL + " ")):
        assert not files.seal_intact(spoiled.encode()), spoiled


def test_a_file_put_into_the_earlier_output_during_a_run_is_not_deleted(tmp_path) -> None:
    """The folder was checked when the run began and swapped out at its end: a note the
    user saved into the earlier report meanwhile was deleted with it (outside audit)."""
    out = tmp_path / "out"
    with files.staged_directory(out, "probe") as staging:
        (staging / "page.txt").write_text("first\n")
    for late in ("notes.txt", "page.txt"):
        before = _tree(out)
        with pytest.raises(InputError, match=late.replace(".", r"\.")):
            with files.staged_directory(out, "probe") as staging:
                (staging / "page.txt").write_text("second\n")
                (out / late).write_text("the user's, written while the run worked\n")
        assert (out / late).read_text() == "the user's, written while the run worked\n"
        assert set(_tree(out)) == set(before) | {late}
        assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]  # no staging left
        (out / late).unlink() if late == "notes.txt" else (out / late).write_text("first\n")
    # a folder made where nothing was when the run began is not replaced either
    fresh = tmp_path / "fresh"
    with pytest.raises(InputError, match="did not write"):
        with files.staged_directory(fresh, "probe") as staging:
            (staging / "page.txt").write_text("new\n")
            fresh.mkdir()
            (fresh / "mine.txt").write_text("the user's\n")
    assert (fresh / "mine.txt").read_text() == "the user's\n"


def test_a_replaced_output_keeps_the_mode_the_user_gave_it(tmp_path) -> None:
    """Replacing a 0700 folder (or an earlier output the user had made private) left it
    0755, its files readable by all (outside audit); a 0600 file stays 0600 too."""
    out = tmp_path / "private"
    out.mkdir(mode=0o700)
    for _ in range(2):
        with files.staged_directory(out, "probe") as staging:
            (staging / "page.txt").write_text("x\n")
        assert (out.stat().st_mode & 0o777) == 0o700
    single = tmp_path / "table.csv"
    files.atomic_write_text(single, "a\n")
    single.chmod(0o600)
    files.atomic_write_text(single, "b\n")
    assert (single.stat().st_mode & 0o777) == 0o600 and single.read_text() == "b\n"


def test_a_fitted_battery_file_and_a_propulsion_file_never_replace_each_other(
        tmp_path) -> None:
    """Both begin 'written by `tuflexperf fit`': a campaign's fit replaced a fitted battery
    file (its runs and fit block) with a propulsion model, exit 0 (outside audit)."""
    from tests.conftest import copy_shipped_case
    from tests.test_fit_cli import write_table

    copy_shipped_case(tmp_path)
    folder = tmp_path / "data" / "tuflex"
    table = write_table(tmp_path / "table.csv")
    assert _run(folder, "fit", "battery.yaml", "--out", "b.yaml").returncode == 0
    assert _run(folder, "fit", str(table), "--out", "p.yaml").returncode == 0
    written = {n: (folder / n).read_bytes() for n in ("b.yaml", "p.yaml")}
    for args, found in (((str(table), "--out", "b.yaml"), "battery"),
                        (("battery.yaml", "--out", "p.yaml"), "propulsion")):
        out = _run(folder, "fit", *args)
        assert out.returncode == 2, out.stderr
        assert f"is a {found} file written by `tuflexperf fit`" in out.stderr
    assert {n: (folder / n).read_bytes() for n in written} == written


def test_an_output_of_one_kind_never_replaces_another_of_the_same_command(tmp_path) -> None:
    """fit's --table replaced a fitted propulsion model with a CSV, a battery fit's --out a
    thrust table, sweep's --csv its own carpet plot: all exit 0 (outside audit)."""
    from tests.conftest import copy_shipped_case

    copy_shipped_case(tmp_path)
    folder = tmp_path / "data" / "tuflex"
    campaign = str(folder / "campaign" / "campaign.yaml")
    assert _run(tmp_path, "fit", campaign, "--out", "model.yaml").returncode == 0
    assert _run(tmp_path, "sweep", "--case", "requirements/tuflex.yaml", "--vary",
                "aircraft.mass_kg=20:30:2", "--plot", "carpet.png").returncode == 0
    before = _tree(tmp_path)
    for args, found, wanted in (
            (("fit", campaign, "--out", "other.yaml", "--table", "model.yaml"),
             "propulsion file", "thrust table"),
            (("fit", str(folder / "battery.yaml"), "--out", "model_thrust_table.csv"),
             "thrust table", "battery file"),
            (("sweep", "--case", "requirements/tuflex.yaml", "--vary",
              "aircraft.mass_kg=20:30:2", "--csv", "carpet.png"), "sweep plot", "sweep grid")):
        out = _run(tmp_path, *args)
        assert out.returncode == 2, (args, out.stderr)
        assert f"is a {found} written by `tuflexperf" in out.stderr
        assert f"not a {wanted}" in out.stderr
        assert len(out.stderr.strip().splitlines()) == 1
    assert _tree(tmp_path) == before
    # the same artefact is still replaced: a refit, a new carpet plot
    assert _run(tmp_path, "fit", campaign, "--out", "model.yaml").returncode == 0
    assert _run(tmp_path, "sweep", "--case", "requirements/tuflex.yaml", "--vary",
                "aircraft.mass_kg=20:30:3", "--plot", "carpet.png").returncode == 0


def test_an_output_named_with_bytes_that_are_no_utf8_is_written(tmp_path) -> None:
    """Every writer raised UnicodeEncodeError on such a name (outside audit); CasADi's own
    save got '' for it."""
    mission = next((ROOT / "data/tuflex/missions").glob("*.yaml"))
    csv = os.fsdecode(b"h\xfe.csv")
    def run(*args: str) -> subprocess.CompletedProcess[bytes]:  # it prints the name's bytes
        return subprocess.run([*TUFLEXPERF, *args], cwd=tmp_path, capture_output=True,
                              timeout=300)

    for _ in range(2):  # written, then replaced as its own
        done = run("mission", str(mission), "--csv", csv)
        assert done.returncode == 0, done.stderr
    folder = os.fsdecode(b"e\xfe")
    done = run("export", "--out", folder, "--format", "casadi,json")
    assert done.returncode == 0, done.stderr
    assert (tmp_path / folder / "tfp_thrust.casadi").stat().st_size > 0


def test_a_helper_that_fails_leaves_the_report_to_say_it_once(tmp_path) -> None:
    """On a full disk the report's forked page writer printed its 35-line traceback before
    the report's own one-line error (outside audit); the parent draws what a helper left
    undone and reports the error there."""
    script = (
        "import errno\n"
        "from tuflexperf.io.files import start_helper\n"
        "def fail():\n"
        "    raise OSError(errno.ENOSPC, 'No space left on device')\n"
        "helpers = []\n"
        "process = start_helper(fail, (), helpers)\n"
        "process.join()\n"
        "print(process.exitcode)\n"
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=60, cwd=tmp_path)
    assert done.stdout.strip() == "1" and done.stderr == ""


@pytest.mark.parametrize("out", [".", "..", "sub/.."])
def test_the_working_directory_is_no_output_folder(tmp_path, out) -> None:
    """`export --out .` in an empty folder replaced it and left the shell in a deleted one
    (outside audit)."""
    here = tmp_path / "empty"
    here.mkdir()
    done = _run(here, "export", "--out", out)
    assert done.returncode == 2 and "is the working directory or holds it" in done.stderr
    assert here.is_dir() and not list(here.iterdir())


def test_a_file_saved_at_an_output_while_the_command_ran_is_not_replaced(tmp_path):
    """The guard looked at single-file outputs before the computation and the rename did not
    look again: a CSV the user saved there meanwhile was overwritten with exit 0 (outside
    audit). The rename refuses (exit 2), the user's file and no temporary file remain."""
    from tuflexperf.errors import InputError
    from tuflexperf.io.files import guard_outputs, write_files_atomically

    target = tmp_path / "grid.csv"
    guard_outputs({"--csv": target}, [], "sweep", {"--csv": "sweep grid"})
    target.write_text("the user's own table\n")  # saved while the sweep computes
    with pytest.raises(InputError, match="changed while this command ran"):
        write_files_atomically({target: "new grid\n"})
    assert target.read_text() == "the user's own table\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["grid.csv"]
    # a path the guard allowed and nobody touched is written, and may be written again
    other = tmp_path / "other.csv"
    guard_outputs({"--csv": other}, [], "sweep", {"--csv": "sweep grid"})
    write_files_atomically({other: "first\n"})
    write_files_atomically({other: "second\n"})
    assert other.read_text() == "second\n"


def _as_a_user() -> list[str]:
    """The prefix that runs a command without root's right to write anywhere (the suite may
    run as root, whom a folder's mode does not stop)."""
    import shutil

    if os.geteuid() != 0:
        return []
    setpriv = shutil.which("setpriv")
    if setpriv is None:
        pytest.skip("root without setpriv: a write-protected folder does not stop root")
    return [setpriv, "--bounding-set=-dac_override,-dac_read_search,-fowner"]


def test_a_write_protected_earlier_output_is_refused_not_left_as_a_hidden_copy(tmp_path):
    """chmod 555 on an earlier export: the rerun put the new output in place, could not
    remove the old one, and left `.exp.old-*` behind on every run, exit 0 (outside audit)."""
    user = _as_a_user()

    def run(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run([*user, *TUFLEXPERF, *args], cwd=tmp_path, capture_output=True,
                              text=True, timeout=300)

    assert run("export", "--format", "json", "--out", "exp").returncode == 0
    before = _tree(tmp_path / "exp")
    (tmp_path / "exp").chmod(0o555)
    try:
        again = run("export", "--format", "json,c", "--out", "exp")
        assert again.returncode == 2 and again.stderr.count("\n") == 1, again.stderr
        assert "exp is write-protected" in again.stderr
        assert sorted(p.name for p in tmp_path.iterdir()) == ["exp"]  # no hidden copy
        assert _tree(tmp_path / "exp") == before
    finally:
        (tmp_path / "exp").chmod(0o755)
    assert run("export", "--format", "json,c", "--out", "exp").returncode == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["exp"]


def test_a_copy_or_an_edit_of_a_written_csv_is_not_replaced(tmp_path) -> None:
    """A CSV was taken for the tool's by its header alone: the user's corrected copy of a
    thrust table, saved under another name, was replaced by the next fit (outside audit).
    Each file the tool writes carries the sha256 of its bytes as an extended attribute."""
    probe = tmp_path / "probe"
    files.atomic_write_text(probe, "x\n")
    if artefacts.written_mark(probe) == artefacts._UNKNOWN:
        pytest.skip("this file system keeps no extended attributes")
    manifest = str(ROOT / "data" / "tuflex" / "campaign" / "campaign.yaml")

    def fit(table: str) -> subprocess.CompletedProcess[str]:
        return _run(tmp_path, "fit", manifest, "--out", "f.yaml", "--table", table)

    assert fit("t.csv").returncode == 0
    assert fit("t.csv").returncode == 0  # its own output, as written: replaced
    written = (tmp_path / "t.csv").read_bytes()
    (tmp_path / "mine.csv").write_bytes(written + b"EDF1,0.5,10.0,1.0\n")  # a corrected copy
    copied = fit("mine.csv")
    assert copied.returncode == 2 and "was not written there by it" in copied.stderr
    (tmp_path / "t.csv").write_bytes(written.replace(b"\n", b"\n", 1) + b"EDF1,0.5,10,1\n")
    edited = fit("t.csv")
    assert edited.returncode == 2 and "changed since" in edited.stderr
    assert (tmp_path / "mine.csv").read_bytes().endswith(b"EDF1,0.5,10.0,1.0\n")
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []


def test_an_input_unreadable_inside_a_staged_run_is_named_not_the_output(tmp_path: Path) -> None:
    """report with an unreadable campaign run said "--out folder: cannot write: Permission
    denied" (outside audit): an OS error naming a file outside the staging is its read."""
    import errno


    source = tmp_path / "runs" / "edf1.csv.gz"
    with pytest.raises(InputError, match=r"edf1\.csv\.gz: cannot read: Permission denied"), \
            files.staged_directory(tmp_path / "review", "report"):
        raise PermissionError(errno.EACCES, "Permission denied", str(source))
    with pytest.raises(InputError, match=r"review: cannot write: disk full"), \
            files.staged_directory(tmp_path / "review", "report") as staging:
        raise OSError(errno.ENOSPC, "No space left on device", str(staging / "01.png"))
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_a_mission_history_with_a_long_header_is_replaced_by_the_next_run(tmp_path: Path) -> None:
    """Four engines of 200-character names make a header of ~5 kB: its first 4 KiB alone
    were no mission history, and the tool refused to replace its own CSV (outside audit)."""
    engines = [f"E{i}" + "x" * 198 for i in range(4)]
    per_engine = artefacts.MISSION_CSV_ENGINE_COLUMNS
    header = ",".join([*artefacts.MISSION_CSV_COLUMNS,
                       *(f"{c}_{e}" for e in engines for c in per_engine)])
    assert len(header) > 4096
    out = tmp_path / "history.csv"
    files.atomic_write_text(out, header + "\n" + ",".join(["0"] * header.count(",")) + ",0\n")
    files.refuse_foreign_files({"--csv": out}, "mission", {"--csv": "mission history"})
