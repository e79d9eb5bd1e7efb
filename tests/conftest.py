"""Shared fixtures: write made-up cases to a temporary directory."""

from __future__ import annotations

from pathlib import Path
from typing import Any, NamedTuple

import pytest
import yaml


@pytest.fixture(autouse=True)
def _a_new_run(monkeypatch: pytest.MonkeyPatch) -> None:
    """Each test starts as a new process would: no interrupt noted, no output committed
    (tuflexperf.io.files keeps both per run; a test that wrote an output in-process left
    the next one's Ctrl-C "after the commit", not raised)."""
    from tuflexperf.io import files

    monkeypatch.setattr(files, "_signals_received", [])
    monkeypatch.setattr(files, "_committed", [False])
    monkeypatch.setattr(files, "_holding", [False])

ROOT = Path(__file__).resolve().parent.parent
SHIPPED_CASE = ROOT / "requirements" / "tuflex.yaml"


def copy_shipped_case(folder: Path) -> Path:
    """The shipped case (its requirements/ and data/ folders) copied into ``folder``;
    returns the copy's case file."""
    import shutil

    for name in ("requirements", "data"):
        shutil.copytree(ROOT / name, folder / name)
    return folder / "requirements" / "tuflex.yaml"

MADE_UP_AIRCRAFT: dict[str, Any] = {
    "name": "Made-up",
    "mass_kg": 18.0,
    "wing_area_m2": 1.1,
    "cd0": 0.03,
    "k": 0.04,
    "cl_max": 1.4,
    "takeoff": {"cl_ground": 0.4, "rolling_friction": 0.05},
}
# Unequal engines; thrust falls with airspeed, drag at idle.
MADE_UP_PROPULSION: dict[str, Any] = {
    "name": "Made-up fans",
    "model": "poly22",
    "tested_airspeed_m_s": [0, 25],
    "delay_s": 0.04,
    "engines": [
        {
            "name": "left",
            "coefficients": {
                "p00": 0.2,
                "p10": 6.0,
                "p01": -0.12,
                "p20": 30.0,
                "p11": -0.35,
                "p02": 0.0008,
            },
        },
        {
            "name": "right",
            "coefficients": {
                "p00": 0.0,
                "p10": 9.0,
                "p01": -0.09,
                "p20": 24.0,
                "p11": -0.30,
                "p02": 0.0005,
            },
        },
    ],
}
MADE_UP_REQUIREMENTS: dict[str, Any] = {
    "takeoff": {"max_ground_roll_m": 60},
    "envelope": {"min_airspeed_m_s": 14, "max_airspeed_m_s": 30, "max_trim_throttle": 1.0},
    "oei": {"dead_engine": "windmilling", "max_throttle": 1.0},
}


class ShippedReport(NamedTuple):
    parent: Path  # holds nothing but ``out``
    out: Path
    data: dict[str, Any]  # the command's --json


@pytest.fixture(scope="session")
def shipped_report(tmp_path_factory: pytest.TempPathFactory) -> ShippedReport:
    """``tuflexperf report --out .../review --json`` of the shipped case, run once per session
    in a subprocess as a user runs it. Tests read it, never change it; one that needs an
    earlier report to protect copies it (``shutil.copytree``) instead of drawing its own."""
    import json
    import os
    import subprocess
    import sys

    parent = tmp_path_factory.mktemp("shipped_report")
    out = parent / "review"
    done = subprocess.run([sys.executable, "-m", "tuflexperf", "report", "--out", str(out),
                           "--json"], cwd=parent, capture_output=True, text=True, timeout=300,
                          env={**os.environ, "PYTHONWARNINGS": "ignore"})
    assert done.returncode == 0, done.stderr
    return ShippedReport(parent, out, json.loads(done.stdout))


def write_case(
    folder: Path,
    aircraft: dict[str, Any] | None = None,
    propulsion: dict[str, Any] | None = None,
    requirements: dict[str, Any] | None = None,
    atmosphere: dict[str, Any] | None = None,
    **extra: Any,
) -> Path:
    """Write aircraft, propulsion and case YAML files; return the case path."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "aircraft.yaml").write_text(yaml.safe_dump(aircraft or MADE_UP_AIRCRAFT))
    (folder / "propulsion.yaml").write_text(yaml.safe_dump(propulsion or MADE_UP_PROPULSION))
    case = {
        "name": "made-up case",
        "aircraft": "aircraft.yaml",
        "propulsion": "propulsion.yaml",
        "atmosphere": atmosphere or {"altitude_m": 0, "temperature_offset_k": 0},
        "requirements": MADE_UP_REQUIREMENTS if requirements is None else requirements,
        **extra,
    }
    path = folder / "case.yaml"
    path.write_text(yaml.safe_dump(case, sort_keys=False))
    return path


@pytest.fixture
def made_up_case(tmp_path: Path) -> Path:
    return write_case(tmp_path / "made_up")
