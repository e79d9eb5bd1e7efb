"""The battery file is a fitted artefact (issue 9): fit writes it, check reads it, never fits."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
import yaml

from tuflexperf.analysis.requirements import check_case
from tuflexperf.io.battery import load_battery
from tuflexperf.io.case import load_case
from tuflexperf.reduction.battery import fit_battery_block

ROOT = Path(__file__).resolve().parents[2]
BATTERY = ROOT / "data" / "tuflex" / "battery.yaml"


def test_shipped_fit_block_is_a_refit_of_the_shipped_runs() -> None:
    battery = load_battery(BATTERY)
    assert battery.fitted is not None
    refit = fit_battery_block(battery, BATTERY.parent)
    stored = battery.fitted.model_dump()
    for key, value in refit["parameters"].items():
        assert stored["parameters"][key] == pytest.approx(value, rel=1e-9, abs=1e-12)
    assert stored["rms_v"] == pytest.approx(refit["rms_v"], rel=1e-9)
    assert [r["sha256"] for r in stored["runs"]] == [r["sha256"] for r in refit["runs"]]


def test_check_neither_reads_nor_fits_the_discharge_runs(monkeypatch: pytest.MonkeyPatch) -> None:
    import tuflexperf.analysis.endurance as endurance
    import tuflexperf.reduction.battery as fits

    def forbidden(*args: object, **kwargs: object) -> None:
        raise AssertionError("check read or fitted the discharge runs")

    monkeypatch.setattr(endurance, "read_discharge_run", forbidden)
    monkeypatch.setattr(endurance, "fit_discharge", forbidden)
    monkeypatch.setattr(fits, "fit_discharge", forbidden)
    endurance._characterisation_cache = endurance.BoundedCache()
    endurance._model_cache = endurance.BoundedCache()
    verdicts = check_case(load_case(None))
    assert any(v.name == "flight_endurance" and v.passed for v in verdicts)


def test_unfitted_and_fitted_battery_give_the_same_endurance(tmp_path: Path) -> None:
    """Without its fit block a battery file is fitted on the fly (with a note): same answer."""
    from tuflexperf.analysis.endurance import solve_endurance

    for folder in ("requirements", "data"):
        shutil.copytree(ROOT / folder, tmp_path / folder)
    path = tmp_path / "data" / "tuflex" / "battery.yaml"
    data = yaml.safe_load(path.read_text())
    fitted = solve_endurance(load_case(tmp_path / "requirements" / "tuflex.yaml"), 0.5)
    data.pop("fit")
    path.write_text(yaml.safe_dump(data))
    unfitted = solve_endurance(load_case(tmp_path / "requirements" / "tuflex.yaml"), 0.5)
    assert unfitted.flight_endurance_min == pytest.approx(fitted.flight_endurance_min, rel=1e-9)
    assert any("no fitted pack model" in w for w in unfitted.warnings)
    assert not any("no fitted pack model" in w for w in fitted.warnings)
