"""The lack-of-fit F-test of `fit` (issue 43 item 4): the textbook split on replicates checked by
hand, the within-hold basis against noise of known size, and a thrust table with repeats."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy import stats
from typer.testing import CliRunner

from tuflexperf.cli import app
from tuflexperf.models.thrust import poly22
from tuflexperf.reduction.lack_of_fit import (
    batch_mean_variance,
    engine_lack_of_fit,
    polynomial_design,
    polynomial_terms,
    replicate_test,
    within_hold_test,
)
from tuflexperf.reduction.poly22fit import poly22_design

COEFFICIENTS = {"p00": 0.2, "p10": 30.0, "p01": -0.12, "p20": 22.0, "p11": -0.4, "p02": 0.0007}


def test_the_textbook_split_on_replicates_by_hand() -> None:
    # a straight line through three conditions, each measured twice:
    # means 1, 5, 3; SS_PE = 6 on 3 dof; the line 2 + x; SSE = 18; SS_LOF = 12 on 1 dof
    x = np.array([0.0, 0.0, 1.0, 1.0, 2.0, 2.0])
    y = np.array([0.0, 2.0, 4.0, 6.0, 2.0, 4.0])
    design = np.column_stack([np.ones_like(x), x])
    lof = replicate_test(design, y, x, x, np.zeros_like(x), form="line")
    assert (lof.dof_lack_of_fit, lof.dof_pure_error) == (1, 3)
    assert lof.f_statistic == pytest.approx((12.0 / 1) / (6.0 / 3))  # 6
    assert lof.p_value == pytest.approx(stats.f.sf(6.0, 1, 3))
    assert lof.p_value == pytest.approx(0.0917, abs=5e-4)  # a t of sqrt(6) on 3 dof, two-sided
    assert lof.pure_error_rms_n == pytest.approx(math.sqrt(2.0))
    # E[SS_LOF] = (m - p) sigma^2 + sum n_i bias_i^2: (12 - 1 x 2) / 6 points
    assert lof.model_form_rms_n == pytest.approx(math.sqrt(10.0 / 6.0))
    # the condition means minus the line: -1, +2, -1
    assert (lof.worst_throttle, lof.worst_residual_n) == (1.0, pytest.approx(2.0))
    assert lof.basis == "replicate_holds" and lof.fits


def test_polynomial_terms_are_matlabs() -> None:
    assert polynomial_terms(2, 2) == [(0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2)]
    assert len(polynomial_terms(3, 2)) == 9 and (0, 3) not in polynomial_terms(3, 2)
    assert len(polynomial_terms(3, 3)) == 10
    x, v = np.array([0.3, 0.7]), np.array([10.0, 25.0])
    assert np.array_equal(polynomial_design(x, v, polynomial_terms(2, 2)), poly22_design(x, v))


def test_batch_means_see_the_autocorrelation_the_iid_formula_misses() -> None:
    # AR(1) with phi 0.95: the mean's variance is (1 + phi) / (1 - phi) = 39x the iid one
    rng = np.random.default_rng(3)
    phi, n, holds = 0.95, 4000, 400
    shocks = rng.normal(size=(holds, n))
    series = np.empty_like(shocks)
    series[:, 0] = shocks[:, 0] / math.sqrt(1 - phi**2)
    for i in range(1, n):  # the test's own AR(1) generator, not the code under test
        series[:, i] = phi * series[:, i - 1] + shocks[:, i]
    true = float(series.mean(axis=1).var())
    estimated = np.mean([batch_mean_variance(s, 1000)[0] for s in series])
    iid = float(np.mean(series.var(axis=1, ddof=1) / n))
    assert estimated == pytest.approx(true, rel=0.2)
    assert iid < true / 10
    assert batch_mean_variance(series[0], 1000)[1] == 3
    assert batch_mean_variance(series[0, :1500], 1000)[1] == 1  # halved


def _grid(law, sd: float, seed: int):
    rng = np.random.default_rng(seed)
    x, v = (a.ravel() for a in np.meshgrid(np.round(np.arange(0, 1.01, 0.1), 1),
                                           [0.0, 15.0, 20.0, 22.5, 25.0, 27.5, 30.0]))
    variance = np.full(x.size, sd**2)
    return x, v, law(x, v) + rng.normal(0, sd, x.size), variance


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_true_poly22_is_not_flagged_and_a_bent_one_is(seed: int) -> None:
    def law(x, v):
        return poly22(x, v, COEFFICIENTS)
    x, v, y, var = _grid(law, 0.015, seed)
    fine = engine_lack_of_fit(x, v, y, v, var, 150)
    assert fine is not None and fine.poly22.fits and fine.best_alternative is None
    assert fine.poly22.basis == "within_hold"
    assert fine.poly22.pure_error_rms_n == pytest.approx(0.015)

    def bent(x, v):  # the ESC's rpm as x^0.8: no poly22 follows it
        return poly22(x**0.8, v, COEFFICIENTS)
    x, v, y, var = _grid(bent, 0.015, seed)
    result = engine_lack_of_fit(x, v, y, v, var, 150)
    assert result is not None and not result.poly22.fits and result.poly22.p_value < 1e-6
    assert result.poly22.model_form_rms_n > 5 * result.poly22.pure_error_rms_n
    best = result.best_alternative
    assert best is not None and best.form in {"poly32", "poly23", "poly33"}
    assert best.model_form_rms_n < result.poly22.model_form_rms_n


def test_within_hold_f_is_sse_over_its_expectation() -> None:
    x, v, y, var = _grid(lambda x, v: poly22(x, v, COEFFICIENTS) + 0.05 * x**3, 0.01, 5)
    design = poly22_design(x, v)
    hat = np.diag(design @ np.linalg.pinv(design))
    residual = y - design @ np.linalg.lstsq(design, y, rcond=None)[0]
    lof = within_hold_test(design, y, var, 150, x, v)
    assert lof.f_statistic == pytest.approx(residual @ residual / np.sum((1 - hat) * var))
    assert lof.dof_lack_of_fit == x.size - 6


def _table(path: Path, repeats: int, bend: float) -> Path:
    rng = np.random.default_rng(4)
    rows = ["engine,throttle,airspeed_m_s,thrust_n"]
    for _ in range(repeats):
        for v in (0.0, 10.0, 20.0, 30.0):
            for x in np.round(np.arange(0.1, 1.01, 0.1), 1):
                t = poly22(x**bend, v, COEFFICIENTS) + rng.normal(0, 0.02)
                rows.append(f"E1,{x},{v},{t:.5f}")
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return path


def test_a_table_with_repeated_rows_is_tested_on_them(tmp_path: Path) -> None:
    out = tmp_path / "p.yaml"
    runner = CliRunner()
    result = runner.invoke(app, ["fit", str(_table(tmp_path / "t.csv", 2, 0.75)), "--out",
                                 str(out), "--json"])
    assert result.exit_code == 0, result.output
    lof = json.loads(result.stdout)["engines"][0]["lack_of_fit"]
    assert lof["pure_error_basis"] == "replicate_holds"
    assert lof["dof_pure_error"] == 40 and lof["dof_lack_of_fit"] == 34
    assert lof["p_value"] < 0.01 and lof["best_alternative"]["form"].startswith("poly")
    assert any("does not fit its data" in w for w in json.loads(result.stdout)["warnings"])
    assert "lack_of_fit:" in out.read_text(encoding="utf-8")
    # the residual surface, per set point (40, two holds each), read back by the sampler
    assert len(lof["residuals"]) == 40 and {r[3] for r in lof["residuals"]} == {2}
    from tuflexperf.io.case import load_propulsion

    engine = load_propulsion(out).engines[0]
    assert engine.model_form_residuals is not None and len(engine.model_form_residuals) == 40
    # one row per condition: nothing to test against, said in the table
    single = runner.invoke(app, ["fit", str(_table(tmp_path / "s.csv", 1, 0.75)), "--out",
                                 str(tmp_path / "s.yaml")])
    assert single.exit_code == 0, single.output
    assert "lack of fit E1: not tested" in single.output
    assert "lack_of_fit" not in (tmp_path / "s.yaml").read_text(encoding="utf-8")


@pytest.mark.parametrize("seed", [6, 7, 8])
def test_near_replicates_are_tested_net_of_the_surfaces_slope_between_them(seed: int) -> None:
    # a tunnel's repeat: the same set points, the airspeed 0.05 m/s (sd) off the first run's;
    # the thrust's slope over that gap (~0.4 N per m/s) is no scatter of the repeats
    rng = np.random.default_rng(seed)
    x, v = (np.tile(a.ravel(), 2) for a in np.meshgrid(np.round(np.arange(0, 1.01, 0.1), 1),
                                                       [0.0, 15.0, 20.0, 25.0, 30.0]))
    measured = v + rng.normal(0, 0.05, v.size) * (v > 0)
    y = poly22(x, measured, COEFFICIENTS) + rng.normal(0, 0.01, x.size)
    result = engine_lack_of_fit(x, measured, y, v)
    assert result is not None and result.poly22.basis == "replicate_holds"
    assert result.poly22.fits and result.poly22.f_statistic > 0.3  # not the degenerate 0
    assert result.poly22.pure_error_rms_n == pytest.approx(0.01, rel=0.3)
    bent = poly22(x**0.8, measured, COEFFICIENTS) + rng.normal(0, 0.01, x.size)
    assert not engine_lack_of_fit(x, measured, bent, v).poly22.fits


def test_holds_without_scatter_show_nothing_and_are_not_flagged() -> None:
    x, v, y, var = _grid(lambda x, v: poly22(x**0.8, v, COEFFICIENTS), 0.0, 1)
    result = engine_lack_of_fit(x, v, y, v, np.zeros_like(var), 150)
    assert result is not None and math.isnan(result.poly22.p_value)
    assert result.poly22.fits and result.best_alternative is None


def test_the_model_form_shares_follow_where_the_residuals_are_large(seed: int = 3) -> None:
    """A misfit cubic in throttle (``P3(u)``, small at mid-throttle, large at its ends) puts
    its share on the throttle slope, whose square has that profile, and none on airspeed; a
    surface that fits gets none (no structure to place)."""
    from tuflexperf.reduction.lack_of_fit import MODEL_FORM_TERMS

    def cubic_throttle(x, v):
        u = 2 * x - 1
        return poly22(x, v, COEFFICIENTS) + 0.5 * (5 * u**3 - 3 * u) / 2

    x, v, y, var = _grid(cubic_throttle, 0.015, seed)
    result = engine_lack_of_fit(x, v, y, v, var, 150)
    shares = dict(zip(MODEL_FORM_TERMS, result.poly22.model_form_shares, strict=True))
    assert sum(shares.values()) == pytest.approx(1.0, abs=1e-3)
    # the drawn variance at the throttle's ends against mid-throttle: P3's squares average
    # 1 at the grid's ends, 0.12 over its inner throttles
    ends = shares["offset"] + 3 * shares["throttle"]
    assert ends > 2.5 * shares["offset"] and shares["throttle"] > 0.3, shares
    assert shares["airspeed"] + shares["airspeed_squared"] + shares["throttle_airspeed"] \
        < 0.05, shares

    x, v, y, var = _grid(lambda x, v: poly22(x, v, COEFFICIENTS), 0.015, seed)
    fine = engine_lack_of_fit(x, v, y, v, var, 150)
    assert fine.poly22.model_form_shares is None
    assert "model_form_shares" not in fine.as_dict()


def test_the_residual_surface_is_written_where_the_test_finds_structure(seed: int = 2) -> None:
    """Per set point its throttle, airspeed, mean residual (measured minus the least-squares
    poly22) and count: the bent law's residuals, none for a true poly22."""
    def bent(x, v):
        return poly22(x**0.8, v, COEFFICIENTS)
    x, v, y, var = _grid(bent, 0.015, seed)
    result = engine_lack_of_fit(x, v, y, v, var, 150)
    assert result is not None and result.poly22.residuals is not None
    rows = np.array(result.poly22.residuals)
    design = poly22_design(x, v)
    residual = y - design @ np.linalg.lstsq(design, y, rcond=None)[0]
    assert rows.shape == (x.size, 4) and np.all(rows[:, 3] == 1)
    expected = np.column_stack([x, v, residual])
    order = np.lexsort((rows[:, 1], rows[:, 0]))  # set points, in the test's order
    np.testing.assert_allclose(rows[order, :3], expected[np.lexsort((v, x))], atol=1e-3)
    assert "residuals" in result.as_dict()

    def law(x, v):
        return poly22(x, v, COEFFICIENTS)
    x, v, y, var = _grid(law, 0.015, seed)
    fine = engine_lack_of_fit(x, v, y, v, var, 150)
    assert fine is not None and fine.poly22.residuals is None
    assert "residuals" not in fine.poly22.as_dict()
