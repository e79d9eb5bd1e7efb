"""Real RCbenchmark 1520 CSVs (tests/data/rcbenchmark/README.md) read as they come, and the
voltage exponent of a 2S/3S pair against an independent log-ratio estimate."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tuflexperf.io.vendor import VendorSettings, read_rcbenchmark
from tuflexperf.reduction.power import fit_voltage_exponent

DATA = Path(__file__).resolve().parent / "data" / "rcbenchmark"
GF_N = 9.80665e-3  # 1 gram-force [N]


def vendor_frame(path: Path) -> pd.DataFrame:
    """pandas' own read: the BOM stripped, the trailing empty column dropped."""
    return pd.read_csv(path, encoding="utf-8-sig").dropna(axis=1, how="all")


@pytest.mark.parametrize("name", ["a1_11", "a1_7", "b1_11", "b1_7"])
def test_real_file_reads_in_si_units(name: str) -> None:
    path = DATA / f"{name}.csv"
    columns, bad = read_rcbenchmark(path, VendorSettings("rcbenchmark", airspeed_m_s=0.0))
    frame = vendor_frame(path)
    assert bad == {}
    np.testing.assert_allclose(columns["force_n"], frame["Thrust (gf)"] * GF_N, rtol=1e-12)
    np.testing.assert_allclose(columns["throttle"],
                               (frame["ESC signal (µs)"] - 1000.0) / 1000.0, rtol=1e-12)
    np.testing.assert_allclose(columns["voltage_v"], frame["Voltage (V)"], rtol=1e-12)
    np.testing.assert_allclose(columns["current_a"], frame["Current (A)"], rtol=1e-12)
    np.testing.assert_allclose(columns["rpm"], frame["Motor Electrical Speed (RPM)"])


def rising(columns: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The steps up to the thrust peak (past it the pack sags)."""
    peak = int(np.argmax(columns["force_n"]))
    return {k: v[: peak + 1] for k, v in columns.items()}


@pytest.mark.parametrize("motor", ["a1", "b1"])
def test_voltage_exponent_of_a_2s_3s_pair(motor: str) -> None:
    settings = VendorSettings("rcbenchmark", airspeed_m_s=0.0)
    high, low = (rising(read_rcbenchmark(DATA / f"{motor}_{s}.csv", settings)[0])
                 for s in ("11", "7"))
    both = {k: np.concatenate([high[k], low[k]]) for k in high}
    fit = fit_voltage_exponent(both["throttle"], both["airspeed_m_s"], both["force_n"],
                               both["voltage_v"], 11.1)
    assert fit.identified, fit.reason
    # independent: ln(T_3S / T_2S) / ln(U_3S / U_2S) at each pulse both runs hold
    common, i, j = np.intersect1d(high["throttle"], low["throttle"], return_indices=True)
    keep = (high["force_n"][i] > 0.2) & (low["force_n"][j] > 0.2)  # above the stand's noise
    ratios = (np.log(high["force_n"][i] / low["force_n"][j])
              / np.log(high["voltage_v"][i] / low["voltage_v"][j]))[keep]
    assert ratios.size >= 5
    assert fit.exponent == pytest.approx(np.median(ratios), abs=0.1)
    assert 1.4 < fit.exponent < 2.2  # thrust ~ rpm^2 with rpm ~ U at a fixed pulse, less losses
