"""One meaning per key (issue 43 item 5): ``fan_area_m2`` is the fan's disk area, the jet area
is ``jet_area_m2``; a file in the old form is refused naming the key to rename; ``fit``
estimates the windmilling drag coefficient from the throttle-0 holds and says so."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from tests.conftest import ROOT, tuflexperf
from tuflexperf.errors import InputError
from tuflexperf.io.case import load_case, load_propulsion
from tuflexperf.models.powertrain import figure_of_merit, jet_area_m2, static_jet_velocity_m_s

PROPULSION = ROOT / "data" / "tuflex" / "propulsion.yaml"
CAMPAIGN = ROOT / "data" / "tuflex" / "campaign" / "campaign.yaml"
TRUTH = yaml.safe_load((CAMPAIGN.parent / "truth.yaml").read_text(encoding="utf-8"))


def _write(tmp_path: Path, document: dict) -> Path:
    path = tmp_path / "propulsion.yaml"
    path.write_text(yaml.safe_dump(document, sort_keys=False))
    return path


def test_the_shipped_file_states_the_disk_and_the_jet_area() -> None:
    prop = load_propulsion(PROPULSION)
    assert prop.fan_area_m2 == pytest.approx(math.pi * 0.093**2 / 4, rel=1e-4)  # 93 mm disk
    assert prop.jet_area_m2 == pytest.approx(0.004342)
    # the windmilling drag in N is the reconstruction's 0.2 on the jet area, restated
    for engine in prop.engines:
        assert engine.windmilling_drag_coefficient * prop.fan_area_m2 == pytest.approx(
            0.2 * prop.jet_area_m2, rel=1e-3)


def test_each_relation_takes_its_area() -> None:
    """The jet velocity on the jet area (else the disk), the figure of merit on the disk."""
    case = load_case()
    prop, rho = case.propulsion, case.density_kg_m3
    static = min(e.coefficients["p10"] + e.coefficients["p20"] for e in prop.engines)
    static *= rho / prop.reference_density_kg_m3
    assert float(static_jet_velocity_m_s(prop, rho)) == pytest.approx(
        math.sqrt(static / (rho * prop.jet_area_m2)), rel=1e-9)
    import dataclasses

    no_jet = dataclasses.replace(prop, jet_area_m2=None)
    assert jet_area_m2(no_jet) == prop.fan_area_m2
    assert float(static_jet_velocity_m_s(no_jet, rho)) < float(static_jet_velocity_m_s(prop, rho))
    # figure of merit on the disk: P_i = T v_e / 2, v_e = sqrt(T / (rho A_disk)) at rest
    thrust, power = 50.0, 3000.0
    expected = thrust * math.sqrt(thrust / (rho * prop.fan_area_m2)) / 2 / power
    assert float(figure_of_merit(thrust, 0.0, rho, prop.fan_area_m2, power)) == pytest.approx(
        expected, rel=1e-12)


@pytest.mark.parametrize("area", [0.004342, 0.006793])
def test_a_file_in_the_old_form_names_the_key_to_rename(tmp_path, area) -> None:
    """The old shipped file (jet area as fan_area_m2) and an old `fit` file (disk area):
    the tool does not guess which, it says what to do (exit 2)."""
    document = yaml.safe_load(PROPULSION.read_text())
    for key in ("format", "jet_area_m2"):
        del document[key]
    document["fan_area_m2"] = area
    path = _write(tmp_path, document)
    with pytest.raises(InputError) as caught:
        load_propulsion(path)
    message = str(caught.value)
    assert str(path) in message and "fan_area_m2" in message
    assert "rename the key to jet_area_m2" in message and "format: 2" in message
    ran = tuflexperf("check", "--propulsion", str(path))
    assert ran.returncode == 2 and "rename the key to jet_area_m2" in ran.stderr
    assert "Traceback" not in ran.stderr
    # the same number with format: 2 is the disk area, and loads
    document["format"] = 2
    assert load_propulsion(_write(tmp_path, document)).fan_area_m2 == area


def test_a_file_without_areas_needs_no_format(tmp_path) -> None:
    document = yaml.safe_load(PROPULSION.read_text())
    for key in ("format", "jet_area_m2", "fan_area_m2"):
        del document[key]
    for engine in document["engines"]:
        del engine["windmilling_drag_coefficient"]
    assert load_propulsion(_write(tmp_path, document)).fan_area_m2 is None
    document["jet_area_m2"] = 0.004  # a jet area alone is new: still format 2 to be said
    with pytest.raises(InputError, match="format: 2"):
        load_propulsion(_write(tmp_path, document))


def test_fit_estimates_the_windmilling_coefficient_from_the_throttle_0_holds(tmp_path) -> None:
    """The generated campaign (scripts/generate_campaign.py) holds throttle 0 at 15-30 m/s:
    the coefficient on the disk area is the least-squares ``-T(0, V) / (q A)`` of its truth."""
    out = tmp_path / "fit.yaml"
    ran = tuflexperf("fit", str(CAMPAIGN), "--out", str(out), "--json")
    assert ran.returncode == 0, ran.stderr
    said = json.loads(ran.stdout)["windmilling"]
    area = said["fan_area_m2"]
    assert area == pytest.approx(math.pi * 0.093**2 / 4, rel=1e-4)
    written = yaml.safe_load(out.read_text())
    assert written["format"] == 2 and written["fan_area_m2"] == area
    assert "estimated from the throttle-0 holds" in out.read_text().splitlines()[2]
    v = np.array([15.0, 20.0, 22.5, 25.0, 27.5, 30.0])
    qa = 0.5 * TRUTH["air_density_kg_m3"] * v * v * area
    for engine in TRUTH["engines"]:
        c = engine["coefficients"]
        idle = c["p00"] + c["p01"] * v + c["p02"] * v * v
        truth = -(idle @ qa) / (qa @ qa)
        mine = said["engines"][engine["name"]]
        assert mine["estimated"] and mine["n_points"] == 6 and mine["source"] == "throttle-0 holds"
        assert mine["windmilling_drag_coefficient"] == pytest.approx(truth, rel=0.05)
        entry = next(e for e in written["engines"] if e["name"] == engine["name"])
        assert entry["windmilling_drag_coefficient"] == pytest.approx(
            mine["windmilling_drag_coefficient"], abs=1e-4)
    table = tuflexperf("fit", str(CAMPAIGN), "--out", str(tmp_path / "again.yaml"))
    assert table.stdout.count("estimated from 6 throttle-0 holds") == 2


def test_fit_says_when_there_are_no_throttle_0_holds() -> None:
    from tuflexperf.reduction.campaign_fit import windmilling_summary
    from tuflexperf.reduction.electrical_fit import ElectricalFits

    class Holds:
        fan_area_m2 = 0.006793

    said = windmilling_summary(Holds(), ["EDF1"], ElectricalFits())  # type: ignore[arg-type]
    assert said["engines"]["EDF1"]["estimated"] is False
    assert "throttle-0 holds" in said["engines"]["EDF1"]["reason"]
