"""`tuflexperf flightlog` on real PX4 and ArduPilot logs (tests/data/flightlogs/README.md).

Every expected value is reduced here independently: pyulog's or pandas' own reading of the
log and a few lines of numpy, never the module's code. Traps a real log does not hold are
derived from a real log in a temporary folder (the change stated in each test).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from tuflexperf.cli import app

pyulog = pytest.importorskip("pyulog")
pytest.importorskip("pymavlink")

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data" / "flightlogs"
SMALL = DATA / "sample_log_small.ulg"  # CubeOrange VTOL hop: two packs, land detector
EVENTS = DATA / "sample_px4_events.ulg"  # PX4 SITL take-off and landing, current -1
ARDUPLANE = DATA / "arduplane_test.BIN"  # ArduPlane 3.8 on the ground, BAT/BARO/CTUN/STAT

runner = CliRunner()


def run(*args: str) -> tuple[int, dict | str, str]:
    result = runner.invoke(app, ["flightlog", *args])
    out = result.stdout
    if "--json" in args and result.exit_code in (0, 1):
        return result.exit_code, json.loads(out), result.stderr
    return result.exit_code, out, result.stderr


# ---- an independent reduction, straight off pyulog ------------------------------------------


def topic(path: Path, name: str, instance: int = 0) -> pd.DataFrame:
    ulog = pyulog.ULog(str(path), [name])
    data = next(d for d in ulog.data_list if d.name == name and d.multi_id == instance)
    frame = pd.DataFrame(data.data)
    frame["t"] = frame["timestamp"] * 1e-6
    return frame


def land_window(path: Path) -> tuple[float, float]:
    land = topic(path, "vehicle_land_detected")
    airborne = land.index[land["landed"] == 0]
    after = land[(land.index > airborne[-1]) & (land["landed"] == 1)]
    return float(land["t"][airborne[0]]), float(after["t"].iloc[0])


def pack_energy_j(frame: pd.DataFrame, start: float, end: float) -> float:
    inside = frame[(frame["t"] >= start) & (frame["t"] <= end)]
    return float(np.trapezoid(inside["voltage_v"] * inside["current_a"], inside["t"]))


# ---- real logs ------------------------------------------------------------------------------


def test_two_packs_of_a_real_hop_add_up_as_pyulog_reads_them() -> None:
    """sample_log_small: two battery instances (6S and 12S), both with current, counters
    that start at 1.6 and 0.5 mAh, a temperature column NaN throughout."""
    start, end = land_window(SMALL)
    packs = [topic(SMALL, "battery_status", i) for i in (0, 1)]
    assert packs[0]["temperature"].isna().all() and packs[0]["discharged_mah"].iloc[0] > 1
    energy_j = sum(pack_energy_j(p, start, end) for p in packs)
    code, data, _ = run(str(SMALL), "--json")
    assert code == 0
    assert data["airborne_start_s"] == pytest.approx(start)
    assert data["airborne_s"] == pytest.approx(end - start)
    assert "land detector" in data["airborne_rule"]
    assert data["energy_wh"] == pytest.approx(energy_j / 3600, rel=1e-6)
    assert data["sources"]["batteries"] == ["battery_status[0]", "battery_status[1]"]
    flown = [p["discharged_mah"][(p["t"] >= start) & (p["t"] <= end)].to_numpy() for p in packs]
    counter = sum(float(mah[-1] - mah[0]) for mah in flown)
    assert data["charge_mah"] == pytest.approx(counter, rel=1e-6)
    # mean power: each pack's energy over its own sampled time, summed
    mean = sum(pack_energy_j(p, start, end) / np.ptp(p["t"][(p["t"] >= start) & (p["t"] <= end)])
               for p in packs)
    assert data["mean_power_w"] == pytest.approx(mean, rel=1e-6)
    assert data["bins"] == []  # a 1 s hop holds no 10 s bin: said, not invented
    assert any("10 s" in n for n in data["notes"])


def test_current_minus_one_is_no_sensor_and_the_window_is_the_land_detectors() -> None:
    """sample_px4_events (SITL): current -1 throughout, no airspeed topic."""
    bat = topic(EVENTS, "battery_status")
    assert (bat["current_a"] == -1).all()
    start, end = land_window(EVENTS)
    code, data, _ = run(str(EVENTS), "--json")
    assert code == 0
    assert data["airborne_s"] == pytest.approx(end - start)
    assert data["energy_wh"] is None and data["mean_power_w"] is None
    assert any("-1 (no sensor)" in n for n in data["notes"])
    assert data["airspeed_kind"] == "ground speed"
    assert any("ground speed" in n for n in data["notes"])


def test_ulog2csv_folder_reads_as_the_ulog(tmp_path: Path) -> None:
    from pyulog.ulog2csv import convert_ulog2csv

    convert_ulog2csv(str(SMALL), "battery_status,vehicle_land_detected,airspeed_validated,"
                     "vehicle_air_data,vehicle_local_position", str(tmp_path), ",", None, None)
    assert (tmp_path / "sample_log_small_battery_status_1.csv").is_file()
    _, from_csv, _ = run(str(tmp_path), "--json")
    _, from_ulog, _ = run(str(SMALL), "--json")
    assert from_csv["format"] == "ulog-csv"
    for key in ("airborne_s", "energy_wh", "charge_mah", "mean_power_w"):
        assert from_csv[key] == pytest.approx(from_ulog[key], rel=1e-6), key


def test_dataflash_reads_and_a_ground_log_is_refused() -> None:
    """The ArduPlane log never leaves the ground (STAT.isFlying 0, GPS speed 0.2 m/s)."""
    from tuflexperf.io.flightlog import read_flight_log

    log = read_flight_log(ARDUPLANE)
    assert log.kind == "dataflash" and log.batteries[0].source == "BAT[0]"
    assert log.batteries[0].column("voltage_v")[0] == pytest.approx(12.3957, abs=1e-4)
    assert log.baro is not None and log.throttle is not None and log.landed is not None
    code, _, err = run(str(ARDUPLANE))
    assert code == 2
    assert err.count("\n") == 1 and "no airborne window" in err and "arduplane_test.BIN" in err


def test_subprocess_run_writes_csv_and_plot(tmp_path: Path) -> None:
    csv, png = tmp_path / "series.csv", tmp_path / "power.png"
    args = [sys.executable, "-m", "tuflexperf", "flightlog", str(SMALL), "--csv", str(csv),
            "--plot", str(png)]
    done = subprocess.run(args, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "energy:" in done.stdout and f"wrote {csv}" in done.stdout
    series = pd.read_csv(csv)
    speed = topic(SMALL, "airspeed_validated")
    assert len(series) == len(speed)
    np.testing.assert_allclose(series["airspeed_m_s"], speed["indicated_airspeed_m_s"],
                               rtol=1e-6)
    assert png.read_bytes().startswith(b"\x89PNG")
    again = subprocess.run(args, capture_output=True, text=True, timeout=120)  # its own outputs
    assert again.returncode == 0, again.stderr


# ---- traps derived from a real log ----------------------------------------------------------


@pytest.fixture()
def small_csv(tmp_path: Path) -> Path:
    """sample_log_small through ulog2csv: the real data, editable."""
    from pyulog.ulog2csv import convert_ulog2csv

    folder = tmp_path / "csv"
    folder.mkdir()
    convert_ulog2csv(str(SMALL), "battery_status,vehicle_land_detected,airspeed_validated,"
                     "vehicle_air_data,vehicle_local_position", str(folder), ",", None, None)
    return folder


def battery_file(folder: Path, instance: int) -> Path:
    return folder / f"sample_log_small_battery_status_{instance}.csv"


def test_one_pack_on_two_instances_counts_once(small_csv: Path) -> None:
    """Derived: instance 1 made a copy of instance 0's voltage with current -1 (no sensor)."""
    zero = pd.read_csv(battery_file(small_csv, 0))
    one = zero.copy()
    one["current_a"] = -1.0
    one.to_csv(battery_file(small_csv, 1), index=False)
    start, end = land_window(SMALL)
    zero["t"] = zero["timestamp"] * 1e-6
    code, data, _ = run(str(small_csv), "--json")
    assert code == 0
    assert data["energy_wh"] == pytest.approx(pack_energy_j(zero, start, end) / 3600, rel=1e-6)
    assert any("battery_status[1]" in n and "no sensor" in n for n in data["notes"])


def test_negative_current_is_flipped_and_said(small_csv: Path) -> None:
    """Derived: both instances' current negated."""
    _, before, _ = run(str(small_csv), "--json")
    for i in (0, 1):
        frame = pd.read_csv(battery_file(small_csv, i))
        frame["current_a"] = -frame["current_a"]
        frame.to_csv(battery_file(small_csv, i), index=False)
    code, after, _ = run(str(small_csv), "--json")
    assert code == 0
    assert after["energy_wh"] == pytest.approx(before["energy_wh"], rel=1e-6)
    assert sum("sign flipped" in n for n in after["notes"]) == 2


def test_backwards_and_repeated_timestamps_are_sorted(small_csv: Path) -> None:
    """Derived: instance 0's rows reversed and three rows repeated."""
    _, before, _ = run(str(small_csv), "--json")
    frame = pd.read_csv(battery_file(small_csv, 0))
    pd.concat([frame.iloc[::-1], frame.iloc[5:8]]).to_csv(battery_file(small_csv, 0),
                                                          index=False)
    code, after, _ = run(str(small_csv), "--json")
    assert code == 0
    assert after["energy_wh"] == pytest.approx(before["energy_wh"], rel=1e-6)
    assert any("backwards" in n and "3 repeated" in n for n in after["notes"])


def test_a_gap_is_not_integrated_across(small_csv: Path) -> None:
    """Derived: the land detector's airborne stretch widened to 21.5-24.8 s (landed 0 from
    21.51 s to 23.82 s), and instance 1 loses its samples from 22.8 to 24.3 s (a 1.5 s gap)."""
    land_csv = small_csv / "sample_log_small_vehicle_land_detected_0.csv"
    land = pd.read_csv(land_csv)
    t_land = land["timestamp"] * 1e-6
    land.loc[(t_land > 21.0) & (t_land < 24.0), "landed"] = 0
    land.to_csv(land_csv, index=False)
    start = float(t_land[t_land > 21.0].iloc[0])
    end = float(t_land[t_land > 24.0].iloc[0])
    frames = [pd.read_csv(battery_file(small_csv, i)) for i in (0, 1)]
    t1 = frames[1]["timestamp"] * 1e-6
    kept = frames[1][(t1 < 22.8) | (t1 > 24.3)]
    kept.to_csv(battery_file(small_csv, 1), index=False)
    code, data, _ = run(str(small_csv), "--json")
    assert code == 0
    assert data["airborne_start_s"] == pytest.approx(start)
    assert data["airborne_end_s"] == pytest.approx(end)
    zero = frames[0].assign(t=frames[0]["timestamp"] * 1e-6)
    one = kept.assign(t=kept["timestamp"] * 1e-6)
    inside = one[(one["t"] >= start) & (one["t"] <= end)]
    dt = np.diff(inside["t"])
    assert dt.max() > 1.0
    power = (inside["voltage_v"] * inside["current_a"]).to_numpy()
    bridged = float(np.sum((0.5 * (power[1:] + power[:-1]) * dt)[dt <= 1.0]))
    expected = pack_energy_j(zero, start, end) + bridged
    assert data["energy_wh"] == pytest.approx(expected / 3600, rel=1e-6)
    assert any("battery_status[1]" in n and "gaps longer than 1 s" in n for n in data["notes"])


def test_nan_column_drops_no_rows(small_csv: Path) -> None:
    """Derived: instance 0's remaining column blanked (NaN) throughout; energy unchanged."""
    _, before, _ = run(str(small_csv), "--json")
    frame = pd.read_csv(battery_file(small_csv, 0))
    frame["remaining"] = np.nan
    frame.to_csv(battery_file(small_csv, 0), index=False)
    _, after, _ = run(str(small_csv), "--json")
    assert after["energy_wh"] == before["energy_wh"]


def test_no_battery_topic_and_ground_only_are_one_line_errors(small_csv: Path) -> None:
    for i in (0, 1):
        battery_file(small_csv, i).unlink()
    code, _, err = run(str(small_csv))
    assert code == 2 and err.count("\n") == 1 and "no battery topic" in err


def test_land_detector_landed_throughout_falls_back_to_the_airspeed_rule(small_csv: Path
                                                                         ) -> None:
    """Derived: the land detector says landed throughout (a log flown without arming); the
    hop's airspeed (-3 m/s, a sensor offset) never reaches 8 m/s: no airborne window."""
    land = small_csv / "sample_log_small_vehicle_land_detected_0.csv"
    frame = pd.read_csv(land)
    frame["landed"] = 1
    frame.to_csv(land, index=False)
    code, _, err = run(str(small_csv))
    assert code == 2 and "no airborne window" in err and "never reaches 8 m/s" in err


def test_truncated_ulog_is_read_with_a_warning(tmp_path: Path) -> None:
    cut = tmp_path / "cut.ulg"
    data = SMALL.read_bytes()
    cut.write_bytes(data[: len(data) * 3 // 4 + 7])
    code, out, _ = run(str(cut), "--json")
    assert code == 0
    assert any("truncated" in n for n in out["notes"])
    assert SMALL.read_bytes() == data  # the input is never modified


@pytest.mark.parametrize("content", [b"hello\n", b"ULog\x01\x12\x35\x01", b""])
def test_not_a_log_is_one_line(tmp_path: Path, content: bytes) -> None:
    bad = tmp_path / "bad.ulg"
    bad.write_bytes(content)
    code, _, err = run(str(bad))
    assert code == 2 and err.count("\n") == 1 and "bad.ulg" in err


def test_zero_airspeed_all_flight_gives_no_bins(small_csv: Path) -> None:
    """Derived: airspeed_validated's airspeed columns set to 0 (an unplugged sensor)."""
    speed = small_csv / "sample_log_small_airspeed_validated_0.csv"
    frame = pd.read_csv(speed)
    frame["indicated_airspeed_m_s"] = 0.0
    frame.to_csv(speed, index=False)
    code, data, _ = run(str(small_csv), "--json")
    assert code == 0 and data["bins"] == []
    assert any("below 1 m/s all flight" in n for n in data["notes"])


# ---- bins: no shipped real log holds 10 s in one bin; a made-up series, checked by pandas ----


def test_bins_equal_a_pandas_groupby() -> None:
    from tuflexperf.analysis.flown import AirborneWindow, sample_weights, speed_bins

    rng = np.random.default_rng(3)
    t = np.cumsum(rng.uniform(0.05, 0.15, 4000))
    t[2000:] += 5.0  # a 5 s dropout: its sample stands for nothing
    v = 14 + 4 * np.sin(t / 40) + rng.normal(0, 0.3, t.size)
    p = 80 + 3 * (v - 12) ** 2 + rng.normal(0, 5, t.size)
    thr = 0.3 + 0.02 * v
    window = AirborneWindow(float(t[50]), float(t[-50]), "test")
    w = sample_weights(t, window)
    bins = speed_bins(v, w, p, thr)
    frame = pd.DataFrame({"v": v, "p": p, "dt": np.diff(t, append=np.nan), "t": t})
    frame = frame[(frame["t"] >= t[50]) & (frame["t"] < t[-50]) & (frame["dt"] <= 1.0)]
    frame["bin"] = np.floor(frame["v"] + 0.5)
    frame["pw"] = frame["p"] * frame["dt"]
    grouped = frame.groupby("bin").agg(time=("dt", "sum"), pw=("pw", "sum"))
    grouped = grouped[grouped["time"] >= 10.0]
    assert [b.airspeed_m_s for b in bins] == list(grouped.index)
    for b in bins:
        row = grouped.loc[b.airspeed_m_s]
        assert b.time_s == pytest.approx(row["time"], rel=1e-12)
        assert b.power_w == pytest.approx(row["pw"] / row["time"], rel=1e-12)
        assert b.throttle == pytest.approx(0.3 + 0.02 * b.airspeed_m_s, abs=0.02)


def test_case_comparison_throttle_agrees_with_trim() -> None:
    """Made-up flight (no real fixed-wing log is shipped): 12 s at each of 18, 20, 22 m/s at
    the case's density (no baro) and mass; the model's throttle per bin is `trim`'s at that
    airspeed, and flown/predicted is the flown power over the model's."""
    from tuflexperf.analysis.flown import reduce_flight
    from tuflexperf.analysis.flown_compare import compare_with_case
    from tuflexperf.io.case import load_case
    from tuflexperf.io.flightlog import FlightLog, Stream

    case = load_case(ROOT / "requirements" / "tuflex.yaml")
    trim = json.loads(runner.invoke(app, ["trim", "--json"]).stdout)
    trim_throttle = dict(zip(trim["airspeed_m_s"], trim["throttle"], strict=True))
    t = np.arange(0.0, 48.0, 0.1)
    v = np.repeat([12.0, 18.0, 20.0, 22.0], 120)  # 12 m/s: below the case's stall
    battery = Stream("battery_status[0]", t, {"voltage_v": np.full(t.size, 22.0),
                                              "current_a": v * 2.0,
                                              "discharged_mah": np.zeros(t.size)})
    log = FlightLog(Path("made-up"), "ulog", (battery,), Stream("airspeed", t, {
        "airspeed_m_s": v}), "calibrated", None, None, None,
        Stream("land", np.array([0.0, 48.0]), {"landed": np.array([0.0, 1.0])}), None)
    flown = reduce_flight(log)
    cmp = compare_with_case(case, log, flown, None)
    assert [r["airspeed_m_s"] for r in cmp.bins] == [12.0, 18.0, 20.0, 22.0]
    assert np.isnan(cmp.bins[0]["predicted_power_w"]) and cmp.bins[0]["ratio"] is None
    assert any("below the model's stall speed" in n for n in cmp.notes)
    for row in cmp.bins[1:]:
        assert row["predicted_throttle"] == pytest.approx(trim_throttle[row["airspeed_m_s"]],
                                                          rel=1e-6)
        assert row["flown_power_w"] == pytest.approx(22.0 * 2.0 * row["airspeed_m_s"])
        assert row["ratio"] == pytest.approx(row["flown_power_w"] / row["predicted_power_w"])
    assert cmp.density_kg_m3 == pytest.approx(case.density_kg_m3)
    assert cmp.predicted_endurance_s is not None
    handoff = cmp.handoff
    best = json.loads(runner.invoke(app, ["endurance", "--best", "--json"]).stdout)
    point = best["best"]["best_endurance"]
    assert handoff is not None
    assert handoff["airspeed_true_m_s"] == pytest.approx(point["airspeed_m_s"], rel=1e-9)
    assert handoff["model_power_w"] == pytest.approx(2 * point["electrical_power_w"], rel=1e-9)


def test_without_the_extra_it_is_one_line_naming_the_package(monkeypatch) -> None:
    monkeypatch.setitem(sys.modules, "pyulog", None)  # import pyulog now raises ImportError
    code, _, err = run(str(SMALL))
    assert code == 2 and err.count("\n") == 1
    assert "pyulog" in err and "tuflexperf[flightlog]" in err


def test_the_cli_loads_no_log_reader() -> None:
    """`check` (any command but flightlog) imports neither pyulog nor pymavlink."""
    code = ("import sys, tuflexperf.cli; "
            "print(sorted(m for m in ('pyulog', 'pymavlink') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=60)
    assert done.stdout.strip() == "[]", done.stderr


def test_garbage_after_a_dataflash_header_prints_one_line(tmp_path: Path, capfd) -> None:
    """pymavlink's compiled indexer says "unknown msg type" on C's stderr: kept off it."""
    bad = tmp_path / "garbage.bin"
    bad.write_bytes(b"\xa3\x95" + bytes(range(256)) * 20)
    code, _, err = run(str(bad))
    assert code == 2 and err.count("\n") == 1 and "garbage.bin" in err
    assert capfd.readouterr().err == ""


def test_a_ulog2csv_row_longer_than_its_header_is_refused(small_csv: Path) -> None:
    """Derived: one cell appended to the first data row of instance 0's battery CSV."""
    path = battery_file(small_csv, 0)
    lines = path.read_text().splitlines(keepends=True)
    lines[1] = lines[1].rstrip("\n") + ",7\n"
    path.write_text("".join(lines))
    code, _, err = run(str(small_csv))
    assert code == 2 and err.count("\n") == 1 and "battery_status_0.csv" in err


def test_outputs_never_replace_the_log_nor_a_foreign_file(tmp_path: Path) -> None:
    log = tmp_path / "flight.ulg"
    log.write_bytes(SMALL.read_bytes())
    foreign = tmp_path / "mine.csv"
    foreign.write_text("time_s,x\n1,2\n")
    for flag, target in (("--csv", log), ("--csv", foreign), ("--plot", tmp_path / "p.txt")):
        code, _, err = run(str(log), flag, str(target))
        assert code == 2 and err.count("\n") == 1, err
    assert log.read_bytes() == SMALL.read_bytes()
    assert foreign.read_text() == "time_s,x\n1,2\n"


def test_the_airspeed_rule_on_a_real_log(small_csv: Path) -> None:
    """Derived: land detector landed throughout (a log flown without arming), the airspeed
    offset by +12 m/s, and the baro altitude raised by 5 m from 23.0 to 24.0 s."""
    land = small_csv / "sample_log_small_vehicle_land_detected_0.csv"
    frame = pd.read_csv(land)
    frame["landed"] = 1
    frame.to_csv(land, index=False)
    speed_csv = small_csv / "sample_log_small_airspeed_validated_0.csv"
    speed = pd.read_csv(speed_csv)
    speed["indicated_airspeed_m_s"] += 12.0
    speed.to_csv(speed_csv, index=False)
    baro_csv = small_csv / "sample_log_small_vehicle_air_data_0.csv"
    baro = pd.read_csv(baro_csv)
    tb = baro["timestamp"] * 1e-6
    baro.loc[(tb >= 23.0) & (tb <= 24.0), "baro_alt_meter"] += 5.0
    baro.to_csv(baro_csv, index=False)
    t, v = speed["timestamp"].to_numpy() * 1e-6, speed["indicated_airspeed_m_s"].to_numpy()
    first = t[np.argmax(v >= 8.0)]
    before = (tb >= first - 30) & (tb < first)
    assert not before.any()  # the baro starts after the airspeed: its first 30 s are ground
    ground = np.median(baro["baro_alt_meter"][tb <= tb.iloc[0] + 30])
    ok = (v >= 8.0) & (np.interp(t, tb, baro["baro_alt_meter"]) >= ground + 3.0)
    code, data, _ = run(str(small_csv), "--json")
    assert code == 0
    assert data["airborne_rule"].startswith("airspeed rule")
    assert data["airborne_start_s"] == pytest.approx(t[ok][0])
    assert data["airborne_end_s"] == pytest.approx(t[ok][-1])
    assert any("landed throughout" in n for n in data["notes"])
    assert any("ground is the median of the baro's first 30 s" in n for n in data["notes"])
