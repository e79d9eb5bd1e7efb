"""The rig's systematic errors (issue 44 item 1): ``rig_uncertainty`` in the campaign manifest
and the propulsion file, one schema, stated defaults, bad values refused naming the key."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from tuflexperf.errors import InputError
from tuflexperf.io.schemas import (
    RIG_UNCERTAINTY_DEFAULTS,
    PropulsionSchema,
    RigUncertaintySchema,
)
from tuflexperf.io.yamlio import load_model

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ROOT / "data" / "tuflex" / "propulsion.yaml"


def _propulsion(tmp_path: Path, rig: dict[str, float]) -> Path:
    data = yaml.safe_load(SHIPPED.read_text(encoding="utf-8"))
    data["rig_uncertainty"] = rig
    data["reference_voltage_v"] = 44.4  # the voltage error's quantity
    path = tmp_path / "propulsion.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    return path


def test_left_out_keys_take_the_stated_nonzero_defaults() -> None:
    rig = RigUncertaintySchema(thrust_scale_sd=0.02)
    resolved = rig.resolved()
    assert resolved["thrust_scale_sd"] == 0.02
    assert rig.declared() == ("thrust_scale_sd",)
    for key, value in RIG_UNCERTAINTY_DEFAULTS.items():
        assert value > 0, key  # never zero without saying so
        if key != "thrust_scale_sd":
            assert resolved[key] == value


def test_a_declared_rig_loads_in_the_propulsion_file(tmp_path: Path) -> None:
    rig = {"airspeed_bias_sd_m_s": 0.3, "thrust_scale_sd": 0.02, "balance_zero_sd_n": 0.04,
           "voltage_sd_v": 0.2}
    schema = load_model(_propulsion(tmp_path, rig), PropulsionSchema)
    assert schema.rig_uncertainty is not None
    assert schema.rig_uncertainty.resolved() == rig


@pytest.mark.parametrize(("key", "value", "says"), [
    ("thrust_scale_sd", -0.01, "greater than or equal to 0"),
    ("thrust_scale_sd", 0.6, "less than or equal to 0.25"),
    ("airspeed_bias_sd_m_s", 40.0, "less than or equal to 5"),
    ("voltage_sd_v", float("nan"), "finite"),
    ("balance_zero_sd_n", 90.0, "larger than the quantity"),  # the full thrust is ~55 N
    ("voltage_sd_v", 45.0, "larger than the quantity"),  # the reference voltage is 44.4 V
])
def test_bad_values_are_refused_naming_the_key(tmp_path: Path, key: str, value: float,
                                               says: str) -> None:
    with pytest.raises(InputError) as caught:
        load_model(_propulsion(tmp_path, {key: value}), PropulsionSchema)
    assert f"rig_uncertainty.{key}" in str(caught.value)
    assert says in str(caught.value)


@pytest.mark.parametrize(("matrix", "says"), [
    ([[1, 0], [0, 1]], "4x4"),
    ([[1, 0.5, 0, 0], [0.4, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], "symmetric"),
    ([[1, 0.9, 0.9, 0], [0.9, 1, -0.9, 0], [0.9, -0.9, 1, 0], [0, 0, 0, 1]], "semi-definite"),
    ([[2, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], "within [-1, 1]"),
])
def test_a_correlation_no_errors_can_have_is_refused(tmp_path: Path, matrix, says) -> None:
    with pytest.raises(InputError) as caught:
        load_model(_propulsion(tmp_path, {"correlation": matrix}), PropulsionSchema)
    assert "rig_uncertainty.correlation" in str(caught.value) and says in str(caught.value)


def test_a_valid_correlation_loads() -> None:
    matrix = [[1, 0.5, 0, 0], [0.5, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
    assert RigUncertaintySchema(correlation=matrix).correlation == matrix
