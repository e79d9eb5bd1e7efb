"""One verdict rule (issue 9): every command's passed equals check's for the same requirement."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from tuflexperf.cli import app

COMMANDS = {
    "trim_throttle_max": ["trim"],
    "oei_min_throttle": ["oei"],
    "flight_endurance": ["endurance", "--throttle", "0.5"],
}


@pytest.mark.parametrize("mass", ["26.71", "31", "40"])
def test_each_command_agrees_with_check(mass: str) -> None:
    runner = CliRunner()
    check = runner.invoke(app, ["check", "--json", "--set", f"aircraft.mass_kg={mass}"])
    verdicts = {r["name"]: r["passed"] for r in json.loads(check.stdout)["results"]}
    for name, command in COMMANDS.items():
        out = runner.invoke(app, [*command, "--json", "--set", f"aircraft.mass_kg={mass}"])
        assert out.exit_code in (0, 1), out.output
        assert json.loads(out.stdout)["passed"] == verdicts[name], (mass, name)
        assert out.exit_code == (0 if verdicts[name] else 1)
