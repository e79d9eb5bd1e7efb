"""Envelope bounds as equivalent airspeeds (SPEC 3: true airspeeds unless a key says _eas).

Verification: an EAS bound is the true airspeed ``EAS sqrt(rho0 / rho)`` at the case's ISA
density, so a case with EAS bounds solves exactly the case with those true bounds.
"""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import pytest
from typer.testing import CliRunner

from tuflexperf.analysis.margins import margin_parameters
from tuflexperf.analysis.requirements import check_case
from tuflexperf.cli import app
from tuflexperf.io.case import load_case
from tuflexperf.io.dotted import with_values
from tuflexperf.models.aircraft import EAS_REFERENCE_DENSITY_KG_M3
from tuflexperf.models.atmosphere import isa_density_kg_m3

ROOT = Path(__file__).resolve().parents[2]
SHIPPED_ENVELOPE = ("  envelope: {min_airspeed_m_s: 15, max_airspeed_m_s: 45, "
                    "max_trim_throttle: 1.0}\n")
runner = CliRunner()


def _case(tmp_path: Path, envelope: str, altitude_m: float = 2000.0) -> Path:
    for folder in ("requirements", "data"):
        if not (tmp_path / folder).exists():
            shutil.copytree(ROOT / folder, tmp_path / folder)
    path = tmp_path / "requirements" / f"case_{abs(hash(envelope))}.yaml"
    text = (ROOT / "requirements" / "tuflex.yaml").read_text()
    text = text.replace(SHIPPED_ENVELOPE, f"  envelope: {envelope}\n")
    text = text.replace("altitude_m: 0,", f"altitude_m: {altitude_m:g},")
    path.write_text(text)
    return path


def _same(a, b) -> bool:
    """Two verdicts with the same value on every reading (not attainable on both: None)."""
    pairs = [(a.value, b.value)] + [(x.value, y.value)
                                    for x, y in zip(a.readings, b.readings, strict=True)]
    return all(x is None and y is None or (x is not None and y is not None
                                           and x == pytest.approx(y, rel=1e-12))
               for x, y in pairs)


def test_eas_bounds_solve_the_case_with_those_true_bounds(tmp_path):
    rho = float(isa_density_kg_m3(2000.0, 0.0))
    factor = math.sqrt(EAS_REFERENCE_DENSITY_KG_M3 / rho)
    eas = load_case(_case(tmp_path, "{min_airspeed_eas_m_s: 15, max_airspeed_eas_m_s: 40}"))
    true = load_case(_case(tmp_path, f"{{min_airspeed_m_s: {15 * factor!r}, "
                                     f"max_airspeed_m_s: {40 * factor!r}}}"))
    assert eas.requirements.envelope.bounds_m_s(rho) == pytest.approx((15 * factor,
                                                                       40 * factor), rel=1e-15)
    for a, b in zip(check_case(eas), check_case(true), strict=True):
        assert a.name == b.name and a.passed == b.passed
        assert _same(a, b)
    trim = json.loads(runner.invoke(app, ["trim", "--case", str(eas.path), "--json"]).stdout)
    assert trim["airspeed_m_s"][0] == pytest.approx(15 * factor)
    assert trim["airspeed_m_s"][-1] == pytest.approx(40 * factor)


def test_at_sea_level_eas_and_true_bounds_agree(tmp_path):
    eas = load_case(_case(tmp_path, "{min_airspeed_eas_m_s: 15, max_airspeed_eas_m_s: 45}", 0.0))
    shipped = load_case(None)
    for a, b in zip(check_case(eas), check_case(shipped), strict=True):
        assert _same(a, b)


@pytest.mark.parametrize(("envelope", "message"), [
    ("{min_airspeed_m_s: 15, min_airspeed_eas_m_s: 15, max_airspeed_m_s: 45}", "not both"),
    ("{max_airspeed_m_s: 45}", "give min_airspeed_m_s (true airspeed) or min_airspeed_eas_m_s"),
    ("{min_airspeed_eas_m_s: 30, max_airspeed_eas_m_s: 20}", "must be below"),
    ("{min_airspeed_m_s: 45, max_airspeed_eas_m_s: 40}", "is not below the greatest"),
])
def test_bounds_each_given_once_and_in_order(tmp_path, envelope, message):
    result = runner.invoke(app, ["check", str(_case(tmp_path, envelope))])
    assert result.exit_code == 2 and message in result.stderr, result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


def test_a_batch_over_the_atmosphere_flies_each_densitys_eas_bounds(tmp_path):
    """The batch refused EAS bounds with a varied atmosphere (one grid for all rows) and
    margins left the atmosphere out; each row now flies its own density's true bounds."""
    path = _case(tmp_path, "{min_airspeed_eas_m_s: 15, max_airspeed_eas_m_s: 40}")
    swept = runner.invoke(app, ["sweep", "--case", str(path), "--json", "--vary",
                                "atmosphere.altitude_m=0:1000:2"])
    assert swept.exit_code in (0, 1), swept.stderr
    case = load_case(path)
    for row in json.loads(swept.stdout)["rows"]:
        single = check_case(with_values(case, {"atmosphere.altitude_m":
                                               row["atmosphere.altitude_m"]}))
        for verdict in single:
            value = row[verdict.name]["value"]
            assert (value is None) == (verdict.value is None)
            if value is not None:
                assert value == pytest.approx(verdict.value, rel=1e-6)
    assert "atmosphere.altitude_m" in margin_parameters(case)


def test_set_moves_an_eas_bound(tmp_path):
    path = _case(tmp_path, "{min_airspeed_eas_m_s: 15, max_airspeed_eas_m_s: 40}")
    result = runner.invoke(app, ["trim", "--case", str(path), "--json", "--set",
                                 "requirements.envelope.max_airspeed_eas_m_s=30"])
    rho = float(isa_density_kg_m3(2000.0, 0.0))
    assert json.loads(result.stdout)["airspeed_m_s"][-1] == pytest.approx(
        30 * math.sqrt(EAS_REFERENCE_DENSITY_KG_M3 / rho))


def test_set_switches_a_bound_between_true_and_equivalent(tmp_path):
    result = runner.invoke(app, ["trim", "--json", "--set", "atmosphere.altitude_m=2000",
                                 "--set", "requirements.envelope.min_airspeed_eas_m_s=16"])
    assert result.exit_code in (0, 1), result.stderr
    rho = float(isa_density_kg_m3(2000.0, 0.0))
    speeds = json.loads(result.stdout)["airspeed_m_s"]
    assert speeds[0] == pytest.approx(16 * math.sqrt(EAS_REFERENCE_DENSITY_KG_M3 / rho))
    assert speeds[-1] == 45.0  # the other bound stays true
    both = runner.invoke(app, ["trim", "--set", "requirements.envelope.min_airspeed_eas_m_s=16",
                               "--set", "requirements.envelope.min_airspeed_m_s=16"])
    assert both.exit_code == 2 and "not both" in both.stderr


def test_set_on_the_bounds_of_a_case_without_an_envelope_is_one_line(tmp_path):
    """It raised an AttributeError traceback (second review)."""
    for folder in ("requirements", "data"):
        shutil.copytree(ROOT / folder, tmp_path / folder, dirs_exist_ok=True)
    case = tmp_path / "requirements" / "tuflex.yaml"
    case.write_text(case.read_text().replace(SHIPPED_ENVELOPE, ""))
    for key in ("min_airspeed_m_s", "min_airspeed_eas_m_s"):
        result = runner.invoke(app, ["check", str(case), "--set",
                                     f"requirements.envelope.{key}=15"])
        assert result.exit_code == 2 and "no requirements.envelope block" in result.stderr


@pytest.mark.parametrize(("envelope", "altitude", "message"), [
    ("{min_airspeed_eas_m_s: 40, max_airspeed_m_s: 42}", 1500.0, "is not below the greatest"),
    ("{min_airspeed_eas_m_s: 30, max_airspeed_eas_m_s: 300}", 10000.0, "beyond the speed of"),
])
def test_a_batch_refuses_the_envelopes_a_single_case_refuses(tmp_path, envelope, altitude,
                                                             message):
    """sweep solved a reversed or supersonic grid that check refused (second review)."""
    path = _case(tmp_path, envelope, altitude)
    for args in (["check", str(path)],
                 ["sweep", "--case", str(path), "--vary", "aircraft.mass_kg=25:27:2"]):
        result = runner.invoke(app, args)
        assert result.exit_code == 2 and message in result.stderr, (args, result.stderr)
