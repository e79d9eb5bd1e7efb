"""Fit covariance, leave-one-airspeed-out error, the shipped covariance and the thrust band."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from tuflexperf.analysis.thrust_band import Z_95, thrust_band
from tuflexperf.errors import InputError
from tuflexperf.io.case import load_case, load_propulsion
from tuflexperf.models.thrust import POLY22_TERMS, poly22
from tuflexperf.reduction.poly22fit import fit_poly22, poly22_design
from tuflexperf.reduction.uncertainty import (
    design_covariance,
    expected_extrapolation_sd_n,
    leave_one_airspeed_out,
    paper_grid,
    published_grid_uncertainty,
)

KNOWN = {"p00": 0.3, "p10": 12.5, "p01": -0.14, "p20": 41.0, "p11": -0.37, "p02": 0.0009}


def test_fit_covariance_is_s2_inverse_normal_matrix_with_n_minus_6_dof() -> None:
    x, v = paper_grid()
    rng = np.random.default_rng(3)
    y = poly22(x, v, KNOWN) + rng.normal(0.0, 0.4, x.size)
    fit = fit_poly22(x, v, y)
    design = poly22_design(x, v)
    beta, *_ = np.linalg.lstsq(design, y, rcond=None)
    s2 = np.sum((y - design @ beta) ** 2) / (x.size - 6)
    np.testing.assert_allclose(fit.covariance, s2 * np.linalg.inv(design.T @ design), rtol=1e-8,
                               atol=1e-12)
    np.testing.assert_allclose(
        np.sqrt(np.diag(fit.covariance)), [fit.standard_errors[t] for t in POLY22_TERMS]
    )
    assert fit.residual_sd_n == pytest.approx(np.sqrt(s2))


def test_covariance_matches_the_scatter_of_repeated_fits() -> None:
    """Monte Carlo over 4000 noisy campaigns: the coefficients scatter as sigma^2 (X^T X)^-1."""
    x, v = paper_grid()
    rng = np.random.default_rng(11)
    truth = poly22(x, v, KNOWN)
    design = poly22_design(x, v)
    noise = rng.normal(0.0, 0.5, (4000, x.size))
    betas = np.linalg.lstsq(design, (truth + noise).T, rcond=None)[0].T
    empirical = np.cov(betas.T)
    expected = design_covariance(x, v, 0.5)
    sd = np.sqrt(np.diag(expected))
    # correlation and variance within the sampling error of 4000 fits (~2-5 %)
    np.testing.assert_allclose(np.sqrt(np.diag(empirical)), sd, rtol=0.05)
    np.testing.assert_allclose(empirical / np.outer(sd, sd), expected / np.outer(sd, sd),
                               atol=0.05)


def test_leave_one_airspeed_out_is_zero_on_an_exact_surface_and_matches_lstsq() -> None:
    x, v = paper_grid()
    exact = leave_one_airspeed_out(x, v, poly22(x, v, KNOWN))
    assert exact.airspeed_m_s == pytest.approx((0, 15, 20, 22.5, 25, 27.5, 30))
    assert max(e for e in exact.rms_error_n if e is not None) < 1e-8
    # a cubic term the poly22 cannot follow: the error at 30 m/s is an independent refit's
    y = poly22(x, v, KNOWN) + 2e-4 * v**3 * x
    top = v == 30.0
    design = poly22_design(x, v)
    beta, *_ = np.linalg.lstsq(design[~top], y[~top], rcond=None)
    expected = np.sqrt(np.mean((design[top] @ beta - y[top]) ** 2))
    got = leave_one_airspeed_out(x + 0.0, v + np.where(top, 0.03, 0.0), y)  # tunnel scatter
    assert got.extrapolation_sd_n == pytest.approx(expected, rel=0.05)
    assert got.extrapolation_sd_n > 0.1


def test_expected_extrapolation_error_matches_simulated_leave_out() -> None:
    x, v = paper_grid()
    rng = np.random.default_rng(5)
    errors = [
        leave_one_airspeed_out(x, v, poly22(x, v, KNOWN) + rng.normal(0, 0.5, x.size))
        .extrapolation_sd_n
        for _ in range(400)
    ]
    rms = float(np.sqrt(np.mean(np.square(errors))))
    assert rms == pytest.approx(expected_extrapolation_sd_n(x, v, 0.5), rel=0.05)


def test_shipped_propulsion_carries_the_paper_grid_covariance() -> None:
    case = load_case()
    expected = design_covariance(*paper_grid(), 0.5)
    for engine, edge in zip(case.propulsion.engines, (0.73, 0.50), strict=True):
        np.testing.assert_allclose(np.asarray(engine.covariance), expected, rtol=1e-5,
                                   atol=1e-9)
        assert engine.residual_sd_n == 0.5
        assert engine.extrapolation_sd_n == pytest.approx(
            published_grid_uncertainty(0.5, edge).extrapolation_sd_n, rel=1e-3
        )


def test_thrust_band_is_delta_method_and_widens_beyond_the_tested_range() -> None:
    case = load_case()
    engine = case.propulsion.engines[0]
    band = thrust_band(case.propulsion, 0, 1.0, [0.0, 30.0, 45.0])
    g = poly22_design([1.0, 1.0], [0.0, 30.0])
    c = np.asarray(engine.covariance)
    np.testing.assert_allclose(band.sd_n[:2], np.sqrt(np.einsum("ij,jk,ik->i", g, c, g)))
    g45 = poly22_design([1.0], [45.0])[0]
    assert band.sd_n[2] == pytest.approx(np.sqrt(g45 @ c @ g45 + engine.extrapolation_sd_n**2))
    np.testing.assert_allclose(band.high_n - band.thrust_n, Z_95 * band.sd_n)
    assert band.extrapolated.tolist() == [False, False, True]


def test_propulsion_file_refuses_a_covariance_that_is_not_one(tmp_path) -> None:
    text = yaml.safe_load(open(load_case().propulsion_path))
    text["engines"][0]["covariance"] = [[1.0] * 6] * 5
    path = tmp_path / "p.yaml"
    path.write_text(yaml.safe_dump(text))
    with pytest.raises(InputError, match="covariance"):
        load_propulsion(path)
    text["engines"][0]["covariance"] = (-np.eye(6)).tolist()
    path.write_text(yaml.safe_dump(text))
    with pytest.raises(InputError, match="positive semi-definite"):
        load_propulsion(path)


def test_fit_writes_covariance_residual_and_extrapolation_error(tmp_path) -> None:
    from typer.testing import CliRunner

    from tuflexperf.cli import app

    rows = ["engine,throttle,airspeed_m_s,thrust_n"]
    rng = np.random.default_rng(0)
    x, v = paper_grid()
    y = poly22(x, v, KNOWN) + rng.normal(0, 0.3, x.size)
    rows += [f"E1,{float(a)!r},{float(b)!r},{float(c)!r}" for a, b, c in zip(x, v, y, strict=True)]
    table = tmp_path / "table.csv"
    table.write_text("\n".join(rows) + "\n")
    out = tmp_path / "fit.yaml"
    result = CliRunner().invoke(app, ["fit", str(table), "--out", str(out), "--json"])
    assert result.exit_code == 0, result.stderr
    engine = load_propulsion(out).engines[0]
    fit = fit_poly22(x, v, y)
    np.testing.assert_allclose(np.asarray(engine.covariance), fit.covariance, rtol=1e-9)
    assert engine.residual_sd_n == pytest.approx(fit.rmse_n)
    assert engine.extrapolation_sd_n == pytest.approx(
        leave_one_airspeed_out(x, v, y).extrapolation_sd_n
    )


def test_the_leave_out_mean_keeps_the_sign_of_a_fan_that_loses_thrust_at_speed() -> None:
    """A fan whose thrust falls as ``-x (v/30)^3`` beyond the poly22 the rest of the grid
    gives: the mean of measured minus extrapolated at the left-out 30 m/s (throttles >= 0.5),
    per the 2.5 m/s it lies beyond 27.5, is negative by three standard errors; a true poly22
    gives a mean within its standard error's reach, the standard error the noise's
    ``sqrt(g^T C g + s^2 / n)``, checked against the spread of repeated campaigns."""
    x, v = paper_grid()
    rng = np.random.default_rng(11)
    upper = x >= 0.5

    def falling(x, v):
        return poly22(x, v, KNOWN) - 1.5 * x * (v / 30.0) ** 3

    left = leave_one_airspeed_out(x, v, falling(x, v) + rng.normal(0.0, 0.05, x.size))
    top = v == 30.0
    refit = fit_poly22(x[~top], v[~top], falling(x, v)[~top])
    exact = np.mean(falling(x, v)[top & upper] - refit.predict(x[top & upper], v[top & upper]))
    assert left.extrapolation_bias_n_per_m_s == pytest.approx(exact / 2.5, rel=0.1)
    assert left.extrapolation_bias_n_per_m_s < -3 * left.extrapolation_bias_se_n_per_m_s

    means, errors = [], []
    for _ in range(200):
        y = poly22(x, v, KNOWN) + rng.normal(0.0, 0.3, x.size)
        out = leave_one_airspeed_out(x, v, y)
        means.append(out.extrapolation_bias_n_per_m_s)
        errors.append(out.extrapolation_bias_se_n_per_m_s)
    assert abs(np.mean(means)) < 3 * np.std(means) / np.sqrt(len(means))
    assert np.mean(errors) == pytest.approx(np.std(means), rel=0.15)
