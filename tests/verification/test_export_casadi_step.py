"""The exported CasADi step function (dead time + spool lag) against an independent simulation."""

from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from tests.conftest import MADE_UP_PROPULSION, model_from_propulsion_file
from tuflexperf.export.model import thrust_step_function


def _static(engine: dict, x: float, v: float) -> float:
    c = engine["coefficients"]
    return (c["p00"] + c["p10"] * x + c["p01"] * v + c["p20"] * x**2 + c["p11"] * x * v
            + c["p02"] * v**2)


@pytest.mark.parametrize(("delay_s", "lag_s"), [(0.04, 0.08), (0.0, 0.05), (0.03, 0.0)])
def test_casadi_step_equals_independent_loop(tmp_path: Path, delay_s: float, lag_s: float) -> None:
    data = copy.deepcopy(MADE_UP_PROPULSION)
    data.update(delay_s=delay_s, lag_s=lag_s)
    path = tmp_path / "p.yaml"
    path.write_text(yaml.safe_dump(data))
    dt, v = 0.005, 12.0
    step = thrust_step_function(model_from_propulsion_file(path).propulsion, dt)
    steps = int(math.floor(delay_s / dt + 0.5))
    a = math.exp(-dt / lag_s) if lag_s > 0 else 0.0
    commands = np.random.default_rng(5).uniform(0, 1, (120, 2))
    delay_state = np.zeros((2, max(steps, 1)))
    lag_state = np.array([_static(e, 0.0, v) for e in data["engines"]])
    lines = [[0.0] * steps for _ in range(2)]
    y = lag_state.copy()
    for command in commands:
        thrust, total, delay_state, lag_state = step(delay_state, lag_state, command, v, 1.0)
        for j, engine in enumerate(data["engines"]):
            lines[j].append(float(command[j]))
            u = lines[j].pop(0)
            y[j] = a * y[j] + (1 - a) * _static(engine, u, v)
        np.testing.assert_allclose(np.array(thrust).ravel(), y, rtol=1e-12, atol=1e-12)
        assert float(total) == pytest.approx(y.sum(), rel=1e-12)
