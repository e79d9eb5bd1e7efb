"""A windmilling drag coefficient far below the thrust model's own throttle-0 drag is said.

Independent figures: the coefficient's drag ``Cd q A_fan`` and the model's ``-T(0, V)``
(poly22 at throttle 0, times the density ratio), both at the highest tested airspeed.
"""

from __future__ import annotations

import pytest

from tests.conftest import copy_shipped_case
from tuflexperf.analysis.oei import solve_oei
from tuflexperf.cli import load_case_with


def test_the_shipped_coefficient_drags_a_seventh_of_the_models_idle_and_says_so(tmp_path):
    case = load_case_with(copy_shipped_case(tmp_path), [])
    prop, rho = case.propulsion, case.density_kg_m3
    notes = [w for w in solve_oei(case).warnings if "windmilling_drag_coefficient" in w]
    assert len(notes) == 2
    v = 30.0
    for engine, note in zip(prop.engines, notes, strict=True):
        c = engine.coefficients
        idle = -(c["p00"] + c["p01"] * v + c["p02"] * v * v) * rho / prop.reference_density_kg_m3
        coefficient = engine.windmilling_drag_coefficient * 0.5 * rho * v * v * prop.fan_area_m2
        assert f"{coefficient:.2f} N" in note and f"{idle:.2f} N" in note, note
        assert idle > 5 * coefficient


@pytest.mark.parametrize(("coefficient", "said"), [(0.12785, True), (1.5, False)])
def test_a_coefficient_near_the_models_idle_is_not_said(tmp_path, coefficient, said):
    case_path = copy_shipped_case(tmp_path)
    prop = tmp_path / "data" / "tuflex" / "propulsion.yaml"
    prop.write_text(prop.read_text().replace("windmilling_drag_coefficient: 0.12785",
                                             f"windmilling_drag_coefficient: {coefficient}"))
    case = load_case_with(case_path, [])
    warned = any("windmilling_drag_coefficient" in w for w in solve_oei(case).warnings)
    assert warned is said
