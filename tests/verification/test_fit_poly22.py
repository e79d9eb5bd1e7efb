"""The poly22 least-squares fit: exactness, numpy.linalg.lstsq, MATLAB's goodness of fit."""

from __future__ import annotations

import numpy as np
import pytest

from tuflexperf.errors import InputError
from tuflexperf.models.thrust import POLY22_TERMS, poly22
from tuflexperf.reduction.poly22fit import fit_poly22, poly22_design

KNOWN = {"p00": 0.3, "p10": 12.5, "p01": -0.14, "p20": 41.0, "p11": -0.37, "p02": 0.0009}


def grid():
    x, v = np.meshgrid(np.round(np.arange(0.1, 1.01, 0.1), 1), [0, 15, 20, 22.5, 25, 27.5, 30])
    return x.ravel(), v.ravel()


def test_exact_surface_returns_its_coefficients() -> None:
    x, v = grid()
    fit = fit_poly22(x, v, poly22(x, v, KNOWN))
    for term in POLY22_TERMS:
        assert fit.coefficients[term] == pytest.approx(KNOWN[term], rel=1e-9, abs=1e-11)
    assert fit.r2 == pytest.approx(1.0, abs=1e-12)
    assert fit.rmse_n < 1e-9


def test_matches_numpy_lstsq_and_matlab_statistics() -> None:
    rng = np.random.default_rng(7)
    x = rng.uniform(0, 1, 60)
    v = rng.uniform(0, 30, 60)
    y = poly22(x, v, KNOWN) + rng.normal(0, 0.4, 60) + 0.5 * np.sin(5 * x)
    fit = fit_poly22(x, v, y)
    design = np.column_stack([np.ones(60), x, v, x * x, x * v, v * v])
    beta, *_ = np.linalg.lstsq(design, y, rcond=None)
    got = np.array([fit.coefficients[t] for t in POLY22_TERMS])
    np.testing.assert_allclose(got, beta, rtol=1e-10, atol=1e-12)
    residual = y - design @ beta
    sse = residual @ residual
    assert fit.sse == pytest.approx(sse, rel=1e-10)
    assert fit.r2 == pytest.approx(1 - sse / np.sum((y - y.mean()) ** 2), rel=1e-12)
    assert fit.rmse_n == pytest.approx(np.sqrt(sse / (60 - 6)), rel=1e-12)  # MATLAB: dfe = n - p
    errors = np.sqrt(np.diag(np.linalg.inv(design.T @ design)) * sse / 54)
    got_errors = [fit.standard_errors[t] for t in POLY22_TERMS]
    np.testing.assert_allclose(got_errors, errors, rtol=1e-7)
    np.testing.assert_allclose(fit.residuals_n, residual, atol=1e-10)
    np.testing.assert_allclose(fit.predict(x, v), design @ beta, atol=1e-10)


def test_design_column_order_is_matlab_poly22() -> None:
    row = poly22_design([2.0], [3.0])[0]
    np.testing.assert_array_equal(row, [1, 2, 3, 4, 6, 9])


def test_rank_deficient_table_is_bad_input() -> None:
    x = np.array([0.2, 0.4, 0.6, 0.8, 1.0, 0.5, 0.3])
    v = np.full(7, 20.0)  # one airspeed: v and v^2 are multiples of the constant
    with pytest.raises(InputError, match="1 distinct airspeeds"):
        fit_poly22(x, v, 40 * x * x, label="EDF1")
    with pytest.raises(InputError, match="at least 6"):
        fit_poly22(x[:5], v[:5], x[:5])


def test_six_points_fit_exactly_with_no_rmse() -> None:
    x = np.array([0.0, 1.0, 0.0, 1.0, 0.5, 0.5])
    v = np.array([0.0, 0.0, 30.0, 30.0, 15.0, 0.0])
    fit = fit_poly22(x, v, poly22(x, v, KNOWN))
    assert np.isnan(fit.rmse_n)
    assert fit.coefficients["p20"] == pytest.approx(KNOWN["p20"], rel=1e-9)
