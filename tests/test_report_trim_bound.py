"""The trim page draws the reading its verdict also reads: trim on the thrust beyond the
tested airspeeds at its 90 % bound, where it flies and where it does not (issue 47 item 1: a
failing or unproven requirement has a marked point on its own figure)."""

from __future__ import annotations

import numpy as np

from tuflexperf.analysis.requirements import check_case
from tuflexperf.analysis.study import Study
from tuflexperf.io.case import load_case


def test_the_trim_page_draws_the_bound_where_the_verdict_reads_it() -> None:
    from tuflexperf.report import figures as fg
    from tuflexperf.report import flight_figures as ff
    from tuflexperf.report.data import run_analyses

    fg.use_agg()
    case = load_case(None)
    analyses = run_analyses(Study(case))
    bound = analyses.trim_bound
    verdict = {v.name: v for v in check_case(case)}["trim_throttle_max"]
    assert verdict.verdict == "UNPROVEN" and verdict.readings[1].value is None
    throttle = np.asarray(bound.throttle, dtype=float)
    lost = np.asarray(bound.airspeed_m_s)[~np.isfinite(throttle) | (throttle > 1.0)]
    assert lost.size and lost.max() == 45.0  # the envelope's top is where it cannot trim
    # the bound's throttle is above the fitted one beyond 30 m/s, equal inside
    fitted = np.asarray(analyses.trim.throttle, dtype=float)
    inside = np.asarray(bound.airspeed_m_s) <= 30.0
    assert np.allclose(throttle[inside], fitted[inside], rtol=1e-12)
    beyond = ~inside & np.isfinite(throttle)
    assert np.all(throttle[beyond] > fitted[beyond])
    fig = ff.trim_oei_throttle(case, analyses)
    labels = [" ".join(line.get_label().split()) for line in fig.axes[0].get_lines()]
    said = f"not attainable at {lost.min():.1f}-{lost.max():.1f} m/s"
    assert any("90 % lower bound" in label and said in label for label in labels), labels
    assert any(label.endswith("(as fitted)") for label in labels)
