"""One basis for every thrust figure (issue 47 item 3): the measured forces are carried onto
the propulsion file's reference density, the model's own basis, by one factor rho_ref/rho.

The shipped campaign was measured at 1.225 kg/m^3 and the shipped model states 1.204: the
thrust surfaces scaled the model up to the campaign's density while the band page drew the
campaign's points as measured against the model at its own, so the same points were 1.7 %
apart on two pages.
"""

from __future__ import annotations

import numpy as np
import pytest

from tuflexperf.io.case import load_case
from tuflexperf.models.thrust import engine_thrust_n, reference_basis_scale


@pytest.fixture(scope="module")
def shipped():
    from tuflexperf.report.data import load_measured

    case = load_case(None)
    return case, load_measured(case, None)


def test_the_factor_is_rho_ref_over_rho_and_one_without_a_density():
    prop = load_case(None).propulsion
    assert reference_basis_scale(prop, 1.225) == pytest.approx(1.204 / 1.225)
    assert reference_basis_scale(prop, None) == 1.0
    from dataclasses import replace

    assert reference_basis_scale(replace(prop, reference_density_kg_m3=None), 1.225) == 1.0


def test_every_measured_force_is_on_the_reference_density(shipped):
    case, measured = shipped
    scale = case.propulsion.reference_density_kg_m3 / measured.density_kg_m3
    assert measured.basis_scale == pytest.approx(scale)
    assert scale != pytest.approx(1.0, abs=1e-3)  # the two densities differ: the test can fail
    raw = np.array([row["thrust_n"] for row in measured.fit_summary["points"]])
    np.testing.assert_allclose(measured.points.thrust_n, scale * raw)
    run = measured.processed
    means = np.array([mean for _, _, mean in run.segments])
    cleaned = np.array([run.force_clean_n[a:b].mean() for a, b, _ in run.segments])
    np.testing.assert_allclose(means, cleaned, atol=0.05 * scale)  # segments scaled alike
    assert run.reference_density_kg_m3 == case.propulsion.reference_density_kg_m3


def test_the_model_is_compared_unscaled_with_the_scaled_points(shipped):
    """On one basis the residuals are what the surface and the band both show."""
    case, measured = shipped
    for engine in case.propulsion.engines:
        x, v, t = measured.points.select(engine.name)
        residual = t - np.asarray(engine_thrust_n(engine, x, v), dtype=float)
        raw = t / measured.basis_scale
        # the same residual as the model scaled to the test's density, times the factor
        scaled = raw - np.asarray(engine_thrust_n(engine, x, v, 1 / measured.basis_scale))
        np.testing.assert_allclose(residual, measured.basis_scale * scaled, atol=1e-9)


def test_the_balance_model_subtracts_the_drag_scaled_onto_the_basis(shipped):
    from tuflexperf.report.data import balance_model_n

    case, measured = shipped
    run = measured.comparisons[-1]
    engine = next(e for e in case.propulsion.engines if e.name == run.engine)
    force = balance_model_n(case, measured, run.engine, run.time_s, run.throttle,
                            run.airspeed_m_s, 0.0, 0.0)
    c1, c2 = measured.drag_c1_c2
    v = run.airspeed_m_s
    thrust = np.asarray(engine_thrust_n(engine, run.throttle, v), dtype=float)
    np.testing.assert_allclose(force, thrust - measured.basis_scale * (c1 * v + c2 * v * v))


def test_the_dynamic_model_is_fitted_on_the_sweeps_and_on_the_steps_alike(shipped):
    """Both fits against the synthetic campaign's truth (truth.yaml), reported side by side."""
    import yaml

    from tuflexperf.report.data import CAMPAIGN_BESIDE_PROPULSION

    case, measured = shipped
    truth_file = case.propulsion_path.parent / CAMPAIGN_BESIDE_PROPULSION.parent / "truth.yaml"
    truth = yaml.safe_load(truth_file.read_text())
    fits = measured.fit_summary["dynamics_fits"]
    for which in ("sine_sweep", "throttle_steps"):
        fit = fits[which]
        assert fit["n_runs"] >= 2
        assert fit["delay_s"] == pytest.approx(truth["delay_s"], abs=0.005)
        assert fit["lag_s"] == pytest.approx(truth["spool_lag_s"], abs=0.01)
    # one step run per engine, each at its highest airspeed
    engines = {str(r["engine"]) for r in fits["throttle_steps"]["runs"]}
    assert fits["throttle_steps"]["n_runs"] == len(engines) == 2


def test_the_sweep_page_says_which_dynamic_model_misses_the_amplitude(shipped):
    """The shipped 50 ms pure delay over-predicts the 5 Hz amplitude about 3x (issue 47);
    the fitted delay and lag reproduce it within 20 %."""
    from tuflexperf.report.measured_figures import AMPLITUDE_TOLERANCE, amplitude_verdicts

    _, measured = shipped
    verdicts = {label: (ok, text) for label, ok, text in amplitude_verdicts(measured)}
    assert set(verdicts) == {"propulsion file", "sine-sweep fit", "throttle-step fit"}
    ok, text = verdicts["propulsion file"]
    assert not ok and "does NOT reproduce" in text
    error = measured.sweep_amplitude.error
    labels = [label for label, _, _ in measured.sweep_amplitude_labels]
    shipped_error = error[labels.index("propulsion file")]
    assert np.nanmax(shipped_error) > 1.0  # more than twice the measured amplitude
    for label in ("sine-sweep fit", "throttle-step fit"):
        assert verdicts[label][0]
        assert np.nanmax(np.abs(error[labels.index(label)])) <= AMPLITUDE_TOLERANCE
