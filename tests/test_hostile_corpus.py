"""Hostile inputs, table-driven (issue 10): every case ends as SPEC 5 says.

Each case runs the real CLI in a subprocess inside a private copy of the shipped data and
checks: the exit code; on exit 2 exactly one stderr line that names the file, key or flag;
no traceback; no file of the user's changed; no staging or temporary debris left behind.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _tree(folder: Path) -> dict[str, str]:
    return {
        str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(folder.rglob("*")) if p.is_file()
    }


def _run(folder: Path, *args: str, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "tuflexperf", *args], cwd=folder, capture_output=True,
        text=True, timeout=timeout, env={**os.environ, "PYTHONWARNINGS": "ignore"},
    )


def _edit(path: Path, old: str, new: str) -> None:
    text = path.read_text()
    assert old in text, (path, old)
    path.write_text(text.replace(old, new))


@dataclass(frozen=True)
class Case:
    name: str
    args: tuple[str, ...]
    exit_code: int
    names: str  # what the stderr line must mention (exit 2) or stdout must hold
    setup: Callable[[Path], None] | None = None


def _typo(w: Path) -> None:
    _edit(w / "requirements/tuflex.yaml", "max_ground_roll_m", "max_groundroll_m")


def _exponent(w: Path) -> None:
    text = (w / "data/tuflex/aircraft.yaml").read_text().splitlines()
    text = [("mass_kg: 2.671e1" if line.startswith("mass_kg:") else line) for line in text]
    (w / "data/tuflex/aircraft.yaml").write_text("\n".join(text) + "\n")


def _heavy(w: Path) -> None:
    text = (w / "data/tuflex/aircraft.yaml").read_text().splitlines()
    text = [("mass_kg: 200" if line.startswith("mass_kg:") else line) for line in text]
    (w / "data/tuflex/aircraft.yaml").write_text("\n".join(text) + "\n")


def _notes(w: Path) -> None:
    (w / "requirements/notes.txt").write_text("the user's own notes\n")


CASES = [
    Case("misspelt requirement key", ("check", "requirements/tuflex.yaml"), 2,
         "did you mean 'max_ground_roll_m'", _typo),
    Case("exponent notation is a number", ("check", "--case", "requirements/tuflex.yaml"), 0,
         "overall", _exponent),
    Case("check --case", ("check", "--case", "requirements/tuflex.yaml"), 0, "overall"),
    Case("report over the user's folder", ("report", "--case", "requirements/tuflex.yaml",
                                           "--out", "requirements"), 2, "--out", _notes),
    Case("fit over its own manifest", ("fit", "data/tuflex/campaign/campaign.yaml", "--out",
                                       "data/tuflex/campaign/campaign.yaml"), 2, "--out"),
    Case("fit over a run file", ("fit", "data/tuflex/campaign/campaign.yaml", "--out",
                                 "data/tuflex/campaign/runs/edf1_v00p0.csv.gz"), 2, "--out"),
    Case("fit table over a run", ("fit", "data/tuflex/campaign/campaign.yaml", "--out", "p.yaml",
                                  "--table", "data/tuflex/campaign/runs/structure_drag.csv"),
         2, "--table"),
    Case("fit given a case file", ("fit", "requirements/tuflex.yaml"), 2,
         "not a campaign manifest or thrust table"),
    Case("export over the user's folder", ("export", "--out", "data"), 2, "--out"),
    Case("percent throttle", ("endurance", "--throttle", "50"), 2, "did you mean 0.5"),
    Case("dead engine in capitals", ("oei", "--dead-engine", "Zero"), 0, "zero"),
    Case("json on not attainable take-off",
         ("takeoff", "--json", "--case", "requirements/tuflex.yaml"), 1, '"passed": false',
         _heavy),
    Case("json on not attainable endurance", ("endurance", "--throttle", "0.5", "--json", "--case",
                                           "requirements/tuflex.yaml"), 1,
         '"passed": false', _heavy),
    Case("missing case file", ("check", "nowhere.yaml"), 2, "nowhere.yaml"),
    Case("unknown flag", ("trim", "--tabel"), 2, "--tabel"),
    Case("version", ("--version",), 0, "tuflexperf"),
    Case("short help", ("-h",), 0, "Usage"),
]


@pytest.fixture()
def workdir(tmp_path: Path) -> Path:
    for folder in ("requirements", "data"):
        shutil.copytree(ROOT / folder, tmp_path / folder)
    return tmp_path


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_hostile_case(workdir: Path, case: Case) -> None:
    if case.setup is not None:
        case.setup(workdir)
    before = _tree(workdir)
    result = _run(workdir, *case.args)
    assert result.returncode == case.exit_code, (result.stdout, result.stderr)
    assert "Traceback" not in result.stderr
    if case.exit_code == 2:
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1, result.stderr
        assert case.names in lines[0]
    else:
        assert case.names in result.stdout
    after = _tree(workdir)
    changed = {k for k in before if before[k] != after.get(k)}
    assert not changed, changed  # no file of the user's changed or deleted
    debris = [p for p in workdir.rglob(".*") if p.name not in (".tuflexperf-output.json",)]
    assert not debris


def test_sigterm_during_report_leaves_earlier_output_intact(workdir: Path) -> None:
    assert _run(workdir, "report", "--out", "review").returncode == 0
    earlier = _tree(workdir / "review")
    process = subprocess.Popen(
        [sys.executable, "-m", "tuflexperf", "report", "--out", "review"], cwd=workdir,
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
    )
    deadline = time.monotonic() + 60
    while not any(workdir.glob(".review.tmp-*")) and time.monotonic() < deadline:
        time.sleep(0.05)
    process.send_signal(signal.SIGTERM)
    _, err = process.communicate(timeout=60)
    assert process.returncode != 0 and "Traceback" not in err
    assert _tree(workdir / "review") == earlier
    assert not [p for p in workdir.iterdir() if p.name.startswith(".review")]


def test_fit_writes_with_the_users_umask(workdir: Path) -> None:
    result = _run(workdir, "fit", "data/tuflex/campaign/campaign.yaml", "--out", "p.yaml")
    assert result.returncode == 0, result.stderr
    mask = os.umask(0o022)
    os.umask(mask)
    assert (workdir / "p.yaml").stat().st_mode & 0o777 == 0o666 & ~mask
