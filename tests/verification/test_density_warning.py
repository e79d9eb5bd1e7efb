"""SPEC 3: a thrust model without reference density is used as measured; results at
another density than ISA sea level say so, in every analysis; with a reference density
(thrust scaled by rho / rho_ref) or at sea level they do not."""

from __future__ import annotations

import pytest
import yaml

from tests.conftest import SHIPPED_CASE
from tuflexperf.analysis.endurance import solve_endurance
from tuflexperf.analysis.oei import solve_oei
from tuflexperf.analysis.performance import solve_performance
from tuflexperf.analysis.takeoff import solve_takeoff
from tuflexperf.analysis.trim import solve_trim
from tuflexperf.io.case import load_case


def _case(tmp_path, altitude_m: float, keep_reference: bool):
    raw = yaml.safe_load(SHIPPED_CASE.read_text())
    for key in ("aircraft", "battery"):
        raw[key] = str((SHIPPED_CASE.parent / raw[key]).resolve())
    propulsion = yaml.safe_load((SHIPPED_CASE.parent / raw["propulsion"]).read_text())
    if not keep_reference:
        propulsion.pop("reference_density_kg_m3", None)
    (tmp_path / "propulsion.yaml").write_text(yaml.safe_dump(propulsion))
    raw["propulsion"] = "propulsion.yaml"
    raw["atmosphere"] = {"altitude_m": altitude_m, "temperature_offset_k": 0}
    path = tmp_path / "case.yaml"
    path.write_text(yaml.safe_dump(raw))
    return load_case(path)


@pytest.mark.parametrize(
    ("altitude", "keep", "warned"),
    [(800.0, False, True), (0.0, False, False), (800.0, True, False)],
)
def test_every_analysis_says_thrust_is_not_lapsed(tmp_path, altitude, keep, warned):
    case = _case(tmp_path, altitude, keep)
    results = {
        "takeoff": solve_takeoff(case).warnings,
        "trim": solve_trim(case).warnings,
        "oei": solve_oei(case).warnings,
        "endurance": solve_endurance(case, 0.6).warnings,
        "performance": solve_performance(case).warnings,
    }
    for name, warnings in results.items():
        said = any("reference_density_kg_m3" in w and "not scaled" in w for w in warnings)
        assert said == warned, name
