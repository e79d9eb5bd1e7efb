"""Nothing lost under any kill (issue 46): SIGKILL at random moments and at each step of
the output swap of ``report``, ``export``, ``fit`` and ``sweep --csv``.

After each kill the output is whole under its name (the earlier one, or the new one
complete), and after the next run no hidden staging or earlier copy is left. The moment
without an output (two renames: ``report --out D`` and ``export --out D`` left only
``.D.old-*`` and ``.D.tmp-*`` for 9-24 ms) is gone where the kernel exchanges folders in
one step; where it refuses, the earlier output is whole under its ``.old-`` name and the
next run puts it back. The kills run in tests/kill_driver.py: one warm interpreter forks
each run in-process, so a kill costs the run's own time, not the imports'.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tuflexperf.io import files, swap

ROOT = Path(__file__).resolve().parent.parent
CASE = str(ROOT / "requirements" / "tuflex.yaml")
DRIVER = str(Path(__file__).resolve().parent / "kill_driver.py")
SWAP_STEPS = [["tuflexperf.io.swap.exchange", 1, "before"],
              ["tuflexperf.io.swap.exchange", 1, "after"],
              ["shutil.rmtree", 1, "before"], ["shutil.rmtree", 1, "after"]]


def _thrust_table(path: Path) -> None:
    """A made-up thrust table (SPEC 4): two engines over throttle and airspeed."""
    rows = ["engine,throttle,airspeed_m_s,thrust_n"]
    for engine, gain in (("L", 30.0), ("R", 28.0)):
        for x in (0.2, 0.4, 0.6, 0.8, 1.0):
            for v in (0.0, 10.0, 20.0, 30.0):
                rows.append(f"{engine},{x},{v},{gain * x * x + 5 * x - 0.1 * x * v:.4f}")
    path.write_text("\n".join(rows) + "\n")


def _drive(folder: Path, jobs: list[dict], refuse_exchange: bool = False) -> dict:
    config = folder / "config.json"
    config.write_text(json.dumps({"cwd": str(folder), "seed": 46, "jobs": jobs,
                                  "refuse_exchange": refuse_exchange}))
    scratch = folder / "scratch"  # the temporary directory: what killed runs left there
    scratch.mkdir()
    done = subprocess.run([sys.executable, DRIVER, str(config)], capture_output=True,
                          text=True, timeout=600, env={**os.environ, "TMPDIR": str(scratch)})
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout)


def _assert_nothing_lost(result: dict) -> None:
    for complete in result["complete"]:
        assert complete["status"] == 0, complete["log"][-2000:]
    for trial in result["trials"]:
        assert set(trial["states"].values()) == {"whole"}, trial
    for job, after in result["after"].items():
        assert set(after["states"].values()) == {"whole"}, job
        assert after["hidden"] == {}, (job, after)  # the next run cleaned what kills left
        assert after["scratch"] == [], (job, after)


def test_sigkill_anywhere_in_export_fit_and_sweep_loses_nothing(tmp_path: Path) -> None:
    _thrust_table(tmp_path / "table.csv")
    export = ["export", "--case", CASE, "--out", "E"]
    sweep = ["sweep", "--case", CASE, "--csv", "grid.csv", "--vary"]
    fit = ["fit", "table.csv", "--out", "fitted.yaml"]
    result = _drive(tmp_path, [
        {"name": "export", "variants": [[*export, "--format", "c,json"],
                                        [*export, "--format", "c,casadi,json"]],
         "outputs": ["E"], "kills": 24, "inject": SWAP_STEPS},
        {"name": "sweep", "variants": [[*sweep, "aircraft.mass_kg=20:30:3"],
                                       [*sweep, "aircraft.mass_kg=20:30:4"]],
         "outputs": ["grid.csv"], "kills": 12,
         "inject": [["os.replace", 1, "before"], ["os.replace", 1, "after"],
                    ["os.link", 1, "after"], ["os.fsync", 1, "after"]]},
        {"name": "fit", "variants": [fit, [*fit, "--delay-s", "0.07"]],
         "outputs": ["fitted.yaml"], "kills": 12,
         "inject": [["os.replace", 1, "before"], ["os.replace", 1, "after"]]},
    ])
    _assert_nothing_lost(result)
    trials = result["trials"]
    assert len(trials) == 24 + 12 + 12 + 4 + 4 + 2  # with report's 2: 50 random kills
    # the kills did land mid-run, and left debris that the next run removed, said so
    assert sum(t["killed"] for t in trials) >= 30
    assert any(t["hidden"] for t in trials)
    logs = [c["log"] for c in result["complete"]] + [
        (tmp_path / "logs" / f"{t['job']}-{k}.txt").read_text() for k, t in enumerate(trials)]
    assert any("left by a run that was killed" in log for log in logs)


@pytest.mark.slow  # the swap is export's (many more kills above); a report takes seconds
def test_sigkill_anywhere_in_report_loses_nothing(tmp_path: Path) -> None:
    _thrust_table(tmp_path / "table.csv")
    report = ["report", "--case", CASE, "--campaign", "table.csv", "--out", "R"]
    # few: a report takes seconds; the swap steps are export's, which has many more kills
    result = _drive(tmp_path, [{"name": "report", "variants": [report], "outputs": ["R"],
                                "kills": 2, "inject": SWAP_STEPS[1:2]}])
    _assert_nothing_lost(result)
    assert result["trials"][-1]["killed"]  # right after the exchange: the new output whole


def test_where_the_exchange_is_refused_the_earlier_output_is_whole_and_put_back(
        tmp_path: Path) -> None:
    """Two renames: a kill between them leaves the output's name empty for that moment;
    the earlier output is whole under its hidden name and the next run puts it back."""
    export = ["export", "--case", CASE, "--out", "E"]
    steps = [["os.replace", k, when] for k in (1, 2) for when in ("before", "after")]
    result = _drive(tmp_path, [
        {"name": "export", "variants": [[*export, "--format", "c,json"],
                                        [*export, "--format", "c,casadi,json"]],
         "outputs": ["E"], "kills": 6, "inject": steps}], refuse_exchange=True)
    between = [t for t in result["trials"] if t["states"]["E"] == "missing"]
    assert between, "no kill landed between the two renames"
    for trial in result["trials"]:
        if trial["states"]["E"] != "whole":
            old = {name: state for name, state in trial["hidden"].items() if ".old-" in name}
            assert list(old.values()) == ["whole"], trial
    assert result["after"]["export"] == {"states": {"E": "whole"}, "hidden": {}, "scratch": []}
    logs = (tmp_path / "logs").glob("*.txt")
    assert any("put the earlier output back" in p.read_text() for p in logs)


def test_the_swap_exchanges_the_folders_in_one_step(tmp_path: Path, monkeypatch) -> None:
    """renameat2(RENAME_EXCHANGE) where the kernel has it: the output's name never
    empty; the two-rename fallback only where it is refused."""
    if not sys.platform.startswith("linux"):
        pytest.skip("renameat2 is Linux's")
    with files.staged_directory(tmp_path / "out", "probe") as staging:
        (staging / "a.txt").write_text("earlier")
    calls: list[bool] = []
    real_exchange, real_replace = swap.exchange, os.replace

    def watched_exchange(a: Path, b: Path) -> bool:
        done = real_exchange(a, b)
        calls.append(done)
        assert (tmp_path / "out").is_dir()
        return done

    def no_replace_of_out(src, dst):  # the output is never renamed away
        assert Path(src).name != "out", "moved aside: not exchanged"
        return real_replace(src, dst)

    monkeypatch.setattr(swap, "exchange", watched_exchange)
    monkeypatch.setattr(files.os, "replace", no_replace_of_out)
    with files.staged_directory(tmp_path / "out", "probe") as staging:
        (staging / "b.txt").write_text("new")
    assert calls == [True]
    assert (tmp_path / "out" / "b.txt").read_text() == "new"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


@pytest.mark.parametrize("refusal", ["EINVAL", "ENOSYS", "EOPNOTSUPP"])
def test_a_refused_exchange_falls_back_to_two_renames(tmp_path: Path, monkeypatch,
                                                      refusal: str) -> None:
    """A kernel or file system without RENAME_EXCHANGE: the exchange changes nothing and
    says so; the two renames replace the output."""
    import ctypes
    import errno

    with files.staged_directory(tmp_path / "out", "probe") as staging:
        (staging / "a.txt").write_text("earlier")

    def refused(a: bytes, b: bytes, flags: int) -> int:
        ctypes.set_errno(getattr(errno, refusal))
        return -1

    monkeypatch.setattr(swap, "_call", [refused])
    assert swap.exchange(tmp_path / "out", tmp_path) is False
    with files.staged_directory(tmp_path / "out", "probe") as staging:
        (staging / "b.txt").write_text("new")
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == [files.MARKER, "b.txt"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


def test_another_failure_of_the_exchange_is_an_error_not_a_fallback(tmp_path: Path,
                                                                    monkeypatch) -> None:
    import ctypes
    import errno

    def denied(a: bytes, b: bytes, flags: int) -> int:
        ctypes.set_errno(errno.EACCES)
        return -1

    monkeypatch.setattr(swap, "_call", [denied])
    with pytest.raises(PermissionError):
        swap.exchange(tmp_path / "a", tmp_path / "b")


def test_only_debris_the_tool_can_prove_stale_is_removed(tmp_path: Path, capsys) -> None:
    """A hidden name of a dead process on this machine goes, with a note; one of a live
    process, of another machine, of an earlier version's scheme, or the user's, stays."""
    out = tmp_path / "R"
    out.mkdir()
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    dead_pid = int(dead.stdout)
    mine = swap.hidden_name("R", "tmp")  # this live process's
    machine = mine.split("-")[1]
    stale = f".R.tmp-{machine}-{dead_pid}-5-{'a' * 12}"
    stale_file = f".R.old-{machine}-{dead_pid}-5-{'b' * 12}"
    kept = [mine, f".R.tmp-{'0' * 8}-{dead_pid}-5-{'c' * 12}",  # another machine's
            ".R.tmp-0123456789ab", ".R.old-0123456789ab",  # an earlier version's scheme
            ".R.notes", "R.tmp-x"]
    for name in [stale, *kept]:
        (tmp_path / name).mkdir()
        (tmp_path / name / "f.txt").write_text("x")
    (tmp_path / stale_file).write_text("earlier copy")
    swap.clean_stale(out, "R")
    left = sorted(p.name for p in tmp_path.iterdir())
    assert left == sorted(["R", *kept])
    note = capsys.readouterr().err
    assert note.count("\n") == 1 and "removed" in note and "killed" in note


def test_an_earlier_output_left_only_under_its_old_name_is_put_back(tmp_path: Path,
                                                                    capsys) -> None:
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    machine = swap.hidden_name("R", "tmp").split("-")[1]
    old = tmp_path / f".R.old-{machine}-{int(dead.stdout)}-5-{'a' * 12}"
    old.mkdir()
    (old / "page.png").write_bytes(b"earlier")
    swap.clean_stale(tmp_path / "R", "R")
    assert (tmp_path / "R" / "page.png").read_bytes() == b"earlier"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["R"]
    assert "put the earlier output back" in capsys.readouterr().err


def test_a_hidden_name_fits_beside_the_longest_output_name() -> None:
    name = swap.hidden_name(files._short("x" * 255), "tmp")
    assert len(os.fsencode(name)) <= 255


def test_the_system_call_serves_where_the_c_library_has_no_wrapper(tmp_path: Path) -> None:
    """glibc before 2.28 has no renameat2(): the system call by its number does the same."""
    import ctypes

    machine = os.uname().machine
    if not sys.platform.startswith("linux") or machine not in swap._SYS_RENAMEAT2:
        pytest.skip("the system call numbers are Linux's, per machine")

    class WithoutWrapper:
        syscall = ctypes.CDLL(None, use_errno=True).syscall

    call = swap._from_libc(WithoutWrapper(), machine)
    assert call is not None
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    (tmp_path / "a" / "in_a").write_text("")
    assert call(os.fsencode(tmp_path / "a"), os.fsencode(tmp_path / "b"),
                swap.RENAME_EXCHANGE) == 0
    assert [p.name for p in (tmp_path / "b").iterdir()] == ["in_a"]
    assert not any((tmp_path / "a").iterdir())


def test_a_killed_runs_folder_holding_more_than_its_marker_lists_stays(tmp_path: Path,
                                                                        capsys) -> None:
    """Killed right after the exchange, before the earlier output (now under the hidden
    name) was checked: a note the user put into it during the run is theirs; that folder
    stays. The same folder as written goes."""
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    machine = swap.hidden_name("R", "tmp").split("-")[1]
    (tmp_path / "R").mkdir()
    names = []
    for k, note in enumerate((False, True)):
        with files.staged_directory(tmp_path / f"e{k}", "probe") as staging:
            (staging / "page.png").write_bytes(b"earlier")
        if note:
            (tmp_path / f"e{k}" / "NOTES.txt").write_text("mine")
        names.append(f".R.tmp-{machine}-{int(dead.stdout)}-5-{k:012x}")
        os.rename(tmp_path / f"e{k}", tmp_path / names[-1])
    swap.clean_stale(tmp_path / "R", "R")
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["R", names[1]])
    assert (tmp_path / names[1] / "NOTES.txt").read_text() == "mine"
    assert "removed" in capsys.readouterr().err
