"""Run-file, thrust-table and campaign-manifest readers: good files and broken ones."""

from __future__ import annotations

import gzip
from pathlib import Path

import numpy as np
import pytest
import scipy.io
import yaml

from tuflexperf.errors import InputError
from tuflexperf.io.campaign import load_campaign
from tuflexperf.io.runs import read_run, read_thrust_table

N = 400


def columns(n: int = N, fs: float = 250.0) -> dict[str, np.ndarray]:
    t = np.arange(n) / fs
    return {
        "time_s": t,
        "force_n": 10 + np.sin(t),
        "airspeed_m_s": np.full(n, 15.0),
        "throttle": np.where(t < 0.5, 0.0, 0.6),
    }


def write_csv(path: Path, data: dict[str, np.ndarray], gz: bool = False) -> Path:
    lines = [",".join(data)]
    lines += [",".join(repr(float(v)) for v in row) for row in zip(*data.values(), strict=True)]
    text = "\n".join(lines).replace("nan", "NaN") + "\n"
    if gz:
        path.write_bytes(gzip.compress(text.encode()))
    else:
        path.write_text(text)
    return path


def test_csv_mat_and_gzip_read_alike(tmp_path: Path) -> None:
    data = columns()
    runs = [
        read_run(write_csv(tmp_path / "a.csv", data)),
        read_run(write_csv(tmp_path / "a.csv.gz", data, gz=True)),
    ]
    scipy.io.savemat(tmp_path / "a.mat", data, do_compression=True)  # row vectors (1 x n)
    runs.append(read_run(tmp_path / "a.mat"))
    scipy.io.savemat(tmp_path / "b.mat", {"run": data}, oned_as="column")  # one struct
    runs.append(read_run(tmp_path / "b.mat"))
    for run in runs:
        assert run.sample_rate_hz == pytest.approx(250.0)
        np.testing.assert_allclose(run["force_n"], data["force_n"])
        np.testing.assert_allclose(run.time_s, data["time_s"])
        assert run.nan_samples == {}


def test_few_nans_repaired_and_reported(tmp_path: Path) -> None:
    data = columns()
    data["force_n"][[50, 51, 200]] = np.nan
    data["time_s"] = data["time_s"].copy()
    data["time_s"][300] = np.nan
    run = read_run(write_csv(tmp_path / "n.csv", data))
    assert run.nan_samples == {"time_s": 1, "force_n": 3}
    assert run.n_samples == N - 1
    assert np.isfinite(run["force_n"]).all()
    expected = 10 + np.sin(50 / 250.0)
    assert run["force_n"][50] == pytest.approx(expected, abs=1e-3)  # interpolated in time
    assert any("NaN" in w for w in run.warnings)


@pytest.mark.parametrize(
    ("mutate", "message"),
    [
        (lambda d: d.pop("throttle"), "missing column 'throttle'"),
        (lambda d: d["force_n"].__setitem__(slice(0, 40), np.nan), "force_n: 40 of 400"),
        (lambda d: d["time_s"].__setitem__(100, d["time_s"][99]), "not strictly increasing"),
        (lambda d: d["throttle"].__setitem__(slice(None), 60.0), "percent"),
    ],
)
def test_broken_csv_is_input_error(tmp_path: Path, mutate, message: str) -> None:
    data = columns()
    mutate(data)
    with pytest.raises(InputError, match=message) as err:
        read_run(write_csv(tmp_path / "bad.csv", data))
    assert "bad.csv" in str(err.value)


@pytest.mark.parametrize("gz", [False, True])
@pytest.mark.parametrize("name", ["throttle", "force_n", "voltage_v"])
def test_a_column_named_twice_is_refused(tmp_path: Path, name: str, gz: bool) -> None:
    """pandas renamed the second ``throttle`` to ``throttle.1`` and the first was fitted,
    silently; which one is the measurement only the user can tell."""
    data = columns()
    data["voltage_v"] = np.full(N, 22.0)
    path = write_csv(tmp_path / ("twice.csv.gz" if gz else "twice.csv"), data, gz=gz)
    text = gzip.decompress(path.read_bytes()).decode() if gz else path.read_text()
    header, *rows = text.splitlines()
    # the repeat with a leading space: stripped, as every header cell is
    header += f", {name}"
    rows = [f"{row},{row.split(',')[list(data).index(name)]}" for row in rows]
    text = "\n".join([header, *rows]) + "\n"
    path.write_bytes(gzip.compress(text.encode())) if gz else path.write_text(text)
    with pytest.raises(InputError, match=f"column '{name}' appears more than once") as err:
        read_run(path)
    assert path.name in str(err.value)
    # a repeated column the run does not read is no ambiguity
    data = columns()
    plain = write_csv(tmp_path / "notes.csv", {**data, "note": np.zeros(N)})
    lines = plain.read_text().splitlines()
    # "note " with its trailing space is a second "note" once stripped (a traceback before)
    plain.write_text("\n".join([lines[0] + ",note ", *[r + ",1" for r in lines[1:]]]) + "\n")
    assert read_run(plain).n_samples == N


def test_empty_and_unreadable_files(tmp_path: Path) -> None:
    (tmp_path / "empty.csv").write_text("")
    (tmp_path / "header.csv").write_text("time_s,force_n,airspeed_m_s,throttle\n")
    (tmp_path / "junk.mat").write_bytes(b"\x00\x01not a mat file" * 20)
    (tmp_path / "text.csv").write_text("time_s,force_n,airspeed_m_s,throttle\n0,abc,1,0\n")
    (tmp_path / "run.txt").write_text("x")
    cases = {
        "empty.csv": "empty file",
        "header.csv": "no data rows",
        "junk.mat": "cannot read as a MATLAB",
        "text.csv": "non-numeric value 'abc'",
        "run.txt": "unsupported run file type",
        "missing.csv": "file not found",
    }
    for name, message in cases.items():
        with pytest.raises(InputError, match=message):
            read_run(tmp_path / name)


def test_mat_with_mismatched_lengths(tmp_path: Path) -> None:
    data = columns()
    data["airspeed_m_s"] = data["airspeed_m_s"][:-3]
    scipy.io.savemat(tmp_path / "m.mat", data)
    with pytest.raises(InputError, match="different lengths"):
        read_run(tmp_path / "m.mat")


def test_thrust_table_reading_and_errors(tmp_path: Path) -> None:
    good = tmp_path / "t.csv"
    good.write_text("engine,throttle,airspeed_m_s,thrust_n,note\nA,0.5,10,12.25,x\nB,1,0,55.1,y\n")
    table = read_thrust_table(good)
    assert table.engines() == ["A", "B"]
    assert table.thrust_n.tolist() == [12.25, 55.1]  # exactly the file's numbers
    bad = {
        "engine,throttle,airspeed_m_s\nA,1,2\n": "missing column 'thrust_n'",
        "engine,throttle,airspeed_m_s,thrust_n\nA,50,2,3\n": "percent",
        "engine,throttle,airspeed_m_s,thrust_n\nA,0.5,x,3\n": "line 2: airspeed_m_s",
        "engine,throttle,airspeed_m_s,thrust_n\nA,0.5,1,nan\n": "not finite",
        "engine,throttle,airspeed_m_s,thrust_n\n": "no data rows",
        "": "empty file",
    }
    for text, message in bad.items():
        path = tmp_path / "bad.csv"
        path.write_text(text)
        with pytest.raises(InputError, match=message):
            read_thrust_table(path)


def manifest(tmp_path: Path, **changes) -> Path:
    write_csv(tmp_path / "r.csv", columns())
    doc = {
        "name": "test",
        "fan_area_m2": 0.0068,
        "tunnel_area_m2": 0.16,
        "runs": [
            {"file": "r.csv", "engine": "E", "kind": "throttle_steps"},
            {"file": "elsewhere/e.csv", "engine": "E", "kind": "endurance"},
        ],
    }
    doc.update(changes)
    path = tmp_path / "campaign.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


def test_campaign_manifest_resolves_paths_and_ignores_endurance(tmp_path: Path) -> None:
    campaign = load_campaign(manifest(tmp_path, air_density_kg_m3=1.19))
    assert [r.path for r in campaign.runs] == [(tmp_path / "r.csv").resolve()]
    assert [r.kind for r in campaign.ignored] == ["endurance"]  # its file need not exist
    assert campaign.air_density_kg_m3 == 1.19 and campaign.density_given
    assert load_campaign(manifest(tmp_path)).air_density_kg_m3 == 1.225
    assert campaign.filters.outlier_window_s == 2.0 and campaign.filters.outlier_threshold == 1.5


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"tunnel_area_m2s": 0.16}, "tunnel_area_m2s: unknown key"),
        ({"filters": {"median_window": 0.1}}, "filters.median_window: unknown key"),
        (
            {"runs": [{"file": "nope.csv", "engine": "E", "kind": "throttle_steps"}]},
            r"runs\[0\].file: file not found",
        ),
        ({"runs": [{"file": "r.csv", "kind": "throttle_steps"}]}, "engine: required"),
        ({"runs": [{"file": "r.csv", "engine": "E", "kind": "steps"}]}, r"runs\[0\].kind"),
        ({"runs": [{"file": "r.csv", "kind": "drag_sweep"}]}, "no throttle_steps run"),
        ({"fan_area_m2": 0.5}, "must be smaller than"),
    ],
)
def test_bad_manifest(tmp_path: Path, changes: dict, message: str) -> None:
    with pytest.raises(InputError, match=message) as err:
        load_campaign(manifest(tmp_path, **changes))
    assert "campaign.yaml" in str(err.value)


def test_discharge_runs_are_read_by_the_one_run_reader(tmp_path: Path) -> None:
    """An endurance run reads as any run does: .csv, .csv.gz and .mat alike, a few NaN
    samples repaired (its own reader refused a NaN and could not read .csv.gz)."""
    from tuflexperf.io.discharge import read_discharge_run

    n = 400
    t = np.arange(n) * 0.5
    on = t >= 10.0
    data = {"time_s": t, "force_n": np.where(on, 20.0, 0.0), "airspeed_m_s": np.full(n, 30.0),
            "throttle": np.where(on, 0.5, 0.0), "voltage_v": 50.0 - 0.01 * t,
            "current_a": np.where(on, 25.0, 0.1)}
    plain = read_discharge_run(write_csv(tmp_path / "d.csv", data))
    packed = read_discharge_run(write_csv(tmp_path / "d.csv.gz", data, gz=True))
    scipy.io.savemat(tmp_path / "d.mat", data)
    matlab = read_discharge_run(tmp_path / "d.mat")
    for run in (packed, matlab):
        np.testing.assert_array_equal(run.charge_ah, plain.charge_ah)
    # 25 A for 190 s, trapezoid over the step from 0.1 A
    assert plain.charge_ah[-1] == pytest.approx((25.0 * 189.5 + 0.5 * 0.5 * 25.1
                                                 + 0.1 * 9.5) / 3600.0)
    data["voltage_v"] = data["voltage_v"].copy()
    data["voltage_v"][200] = np.nan
    repaired = read_discharge_run(write_csv(tmp_path / "nan.csv", data))
    assert repaired.voltage_v[200] == pytest.approx(50.0 - 0.01 * t[200])


@pytest.mark.parametrize(("head", "extra"), [
    ("\n{h},throttle", "0.6"),            # a blank first line
    ("{h}, \"throttle\"", "0.6"),         # a space, then the name quoted
    ("\ufeff{h},time_s", "0.0"),          # a BOM before a repeated first column
    ("{h},\"a\nb\",throttle", "1,0.6"),   # a newline quoted in an earlier cell
])
def test_a_repeated_column_is_seen_however_the_header_is_written(tmp_path: Path, head: str,
                                                                 extra: str) -> None:
    """A second reading of the header line missed each of these (outside re-audit): the
    names are the ones pandas read."""
    data = columns()
    lines = write_csv(tmp_path / "plain.csv", data).read_text().splitlines()
    path = tmp_path / "twice.csv"
    path.write_text(head.format(h=lines[0]) + "\n"
                    + "\n".join(f"{row},{extra}" for row in lines[1:]) + "\n")
    with pytest.raises(InputError, match="appears more than once"):
        read_run(path)


def test_a_compressed_run_that_unpacks_beyond_the_cap_is_refused(tmp_path, monkeypatch) -> None:
    """The 2 GiB cap held for the .gz file only: a 9 MB bomb unpacked to 6 GB of text and
    exhausted the memory (outside audit). Here the cap is lowered so the bomb stays small."""
    import gzip

    from tuflexperf.errors import InputError
    from tuflexperf.io import inputs
    from tuflexperf.io.runs import read_run

    path = tmp_path / "bomb.csv.gz"
    with gzip.open(path, "wb") as handle:
        handle.write(b"time_s,throttle,airspeed_m_s,force_n\n")
        handle.write(b"".join(b"%d,1,1,1\n" % i for i in range(200_000)))
    assert read_run(path).n_samples == 200_000  # within the cap: read as before
    monkeypatch.setattr(inputs, "MAX_RUN_BYTES", 1 << 20)
    with pytest.raises(InputError, match="unpacks to more than"):
        read_run(path)


def test_a_semicolon_separated_run_is_said_as_such(tmp_path) -> None:
    """It said "missing column 'time_s' (found: none)" (outside audit)."""
    from tuflexperf.errors import InputError
    from tuflexperf.io.runs import read_run

    path = tmp_path / "run.csv"
    path.write_text("time_s;throttle;airspeed_m_s;force_n\n0;0;0;0\n0,1;0;0;0\n")
    with pytest.raises(InputError, match="separated by ';'"):
        read_run(path)


@pytest.mark.parametrize("seed", range(8))
def test_random_bytes_are_said_to_be_binary_not_semicolon_separated(tmp_path, seed) -> None:
    """3 kB of random bytes were called "the header's columns are separated by ';'" (outside
    audit). A Latin-1 degree sign in a text header stays a text problem."""
    import numpy as np

    from tuflexperf.errors import InputError
    from tuflexperf.io.runs import read_run

    path = tmp_path / "run.csv"
    path.write_bytes(np.random.default_rng(seed).bytes(3000))
    with pytest.raises(InputError, match="holds binary bytes, not text") as raised:
        read_run(path)
    assert str(path) in str(raised.value)
    path.write_bytes(b"time_s,throttle,airspeed_m_s,force_n,temp_\xb0C\n0,0,0,0,20\n")
    with pytest.raises(InputError) as raised:
        read_run(path)
    assert "binary" not in str(raised.value)


@pytest.mark.parametrize("scale", [1e-300, 1e-9, 1e6, 1e300])
def test_a_time_base_in_no_units_of_a_measurement_is_bad_input(tmp_path: Path, scale) -> None:
    """time_s x 1e-300 overflowed the filters with a message naming no file; x 1e300 was
    fitted, with dozens of 300-digit notes (outside audit)."""
    data = columns()
    data["time_s"] = data["time_s"] * scale
    with pytest.raises(InputError, match=r"a\.csv: column time_s: a sample interval of .* s "
                                         r"is no measurement"):
        read_run(write_csv(tmp_path / "a.csv", data))


@pytest.mark.parametrize("fs", [1e5, 0.01])
def test_fast_and_slow_loggers_are_read(tmp_path: Path, fs: float) -> None:
    run = read_run(write_csv(tmp_path / "a.csv", columns(fs=fs)))
    assert run.sample_rate_hz == pytest.approx(fs)


@pytest.mark.parametrize("offset", [20, 100])
def test_a_gzip_run_with_a_damaged_body_is_bad_input(tmp_path: Path, offset: int) -> None:
    """A flipped byte inside the deflate stream raises zlib.error, which no handler caught:
    a traceback, exit 1 (outside audit). CRC and length damage were already OSError."""
    text = "time_s,throttle,force_n,airspeed_m_s\n" + "".join(
        f"{0.01 * i:.2f},{(i % 50) / 50:.2f},{i % 7}.5,30\n" for i in range(4000))
    path = tmp_path / "run.csv.gz"
    data = bytearray(gzip.compress(text.encode()))
    data[offset] ^= 0x55
    path.write_bytes(bytes(data))
    with pytest.raises(InputError, match=r"run\.csv\.gz: corrupt gzip data"):
        read_run(path)
