"""Any name, any length (issue 46): a folder whose name is no UTF-8 (a Latin-1 ``ü`` from an
old archive) under every command, and a message about a 4,000-character path.

Each command ended in a ``UnicodeEncodeError`` traceback where it wrote such a name into a
file (``fit``: the propulsion file's source; ``report``, which fits the campaign); and the
one-line error, cut at 1,000 characters from the end, lost its key and its reason to a long
path.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from tests.conftest import MADE_UP_AIRCRAFT, write_case
from tuflexperf.cli import app, one_line
from tuflexperf.io.inputs import path_text

ROOT = Path(__file__).resolve().parent.parent
runner = CliRunner()
LATIN_1 = os.fsdecode(b"archiv-\xfc")  # 'archiv-ü' as Latin-1: the byte 0xfc, no UTF-8


def _deep(tmp_path: Path, length: int) -> Path:
    """A folder under ``tmp_path`` whose path is about ``length`` characters."""
    folder = tmp_path
    while len(str(folder)) + 201 <= length:
        folder = folder / ("d" * 200)
    folder = folder / ("e" * max(1, length - len(str(folder)) - 20))
    folder.mkdir(parents=True)
    return folder


def test_a_message_about_a_long_path_keeps_the_key_the_value_and_the_reason(tmp_path) -> None:
    folder = _deep(tmp_path, 4000)
    case = write_case(folder, aircraft={**MADE_UP_AIRCRAFT, "mass_kg": -3.0})
    assert len(str(case)) > 3900
    result = runner.invoke(app, ["check", str(case)])
    assert result.exit_code == 2
    message = result.stderr.strip()
    assert message.count("\n") == 0 and len(message) < 1100
    assert "characters)..." in message  # the path was cut...
    assert message.startswith(f"tuflexperf: error: {str(folder)[:100]}")  # ...in its middle
    assert "aircraft.yaml: mass_kg: " in message and "-3" in message  # file, key, value
    assert message.endswith(result.stderr.strip().rpartition("mass_kg: ")[2])


@pytest.mark.parametrize("path_length", [50, 4000])
def test_one_line_cuts_the_longest_word_in_its_middle(path_length: int) -> None:
    path = "/" + "/".join(["p" * 40] * (path_length // 41))
    text = f"{path}/x.csv: thrust_n: 'abc' is no number; give a number in N"
    cut = one_line(text)
    assert cut.endswith("/x.csv: thrust_n: 'abc' is no number; give a number in N")
    assert cut.startswith(path[:20])
    assert len(cut) <= 1000 + 30
    assert (cut == text) == (len(text) <= 1000)


def test_one_line_cuts_a_garbage_quote_keeping_both_ends() -> None:
    junk = "run.csv: line 2: column force_n: " + repr(bytes(range(256)) * 30) + " is no number"
    cut = one_line(junk)
    assert cut.startswith("run.csv: line 2: column force_n: b'") and cut.endswith(" is no number")
    assert len(cut) <= 1030


def test_path_text_escapes_only_the_bytes_that_are_no_utf8() -> None:
    assert path_text(os.fsdecode(b"/a/\xfc/\xc3\xbc.yaml")) == "/a/\\xfc/\u00fc.yaml"
    assert path_text("plain ü") == "plain ü"
    name = os.fsdecode(b"/x\xfc")
    assert one_line(f"{name}: file not found") == "/x\\xfc: file not found"


@pytest.fixture(scope="module")
def latin1_folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The shipped case and data copied under a folder whose name is no UTF-8."""
    folder = tmp_path_factory.mktemp("names") / LATIN_1
    for name in ("requirements", "data"):
        shutil.copytree(ROOT / name, folder / name)
    # the shipped endurance and trim are UNPROVEN (exit 1); limits every reading meets keep
    # each command's exit 0, the subject here being the folder's name
    case = folder / "requirements" / "tuflex.yaml"
    case.write_text(case.read_text().replace("min_flight_time_min: 15", "min_flight_time_min: 12")
                    .replace("max_airspeed_m_s: 45", "max_airspeed_m_s: 40"))
    return folder


def _commands(folder: Path) -> list[tuple[list[str], list[Path]]]:
    """Every command on the copied case, each writing its outputs into ``folder/out``."""
    case = str(folder / "requirements" / "tuflex.yaml")
    data, out = folder / "data" / "tuflex", folder / "out"
    flight = str(data / "missions" / "test_flight.yaml")
    formats = [(["export", "--case", case, "--out", str(out / f"e-{f}"), "--format", f],
                [out / f"e-{f}"]) for f in ("c", "casadi", "json", "jsbsim", "fmu")]
    return [
        (["check", case], []),
        (["takeoff", "--case", case], []),
        (["trim", "--case", case], []),
        (["oei", "--case", case], []),
        (["endurance", "--case", case, "--throttle", "0.6"], []),
        (["performance", "--case", case], []),
        (["mission", flight, "--case", case, "--csv", str(out / "m.csv")], [out / "m.csv"]),
        (["sweep", "--case", case, "--vary", "aircraft.mass_kg=20:30:3", "--csv",
          str(out / "s.csv"), "--plot", str(out / "s.png")], [out / "s.csv", out / "s.png"]),
        (["margins", "--case", case], []),
        (["fit", str(data / "campaign" / "campaign.yaml"), "--out", str(out / "p.yaml"),
          "--table", str(out / "t.csv")], [out / "p.yaml", out / "t.csv"]),
        (["fit", str(out / "t.csv"), "--out", str(out / "p2.yaml")], [out / "p2.yaml"]),
        (["fit", str(data / "battery.yaml"), "--out", str(out / "b.yaml")], [out / "b.yaml"]),
        *formats,
    ]


def test_every_command_runs_under_a_folder_whose_name_is_no_utf8(latin1_folder: Path,
                                                                 capsys) -> None:
    """In-process as the console runs it (stdout strict UTF-8, as in a UTF-8 locale), text
    and --json; the fitted file names its source with the byte escaped (\\xfc) and is
    sealed."""
    from tuflexperf.cli import main
    from tuflexperf.io.files import seal_intact

    for args, outputs in _commands(latin1_folder):
        for json_flag in ([], ["--json"]):
            with pytest.raises(SystemExit) as done:
                main([*args, *json_flag])
            printed = capsys.readouterr()
            assert done.value.code == 0, (args, printed.err[-2000:])
            for output in outputs:
                assert output.exists(), output
            if json_flag:
                text = json.dumps(json.loads(printed.out))
                text.encode("utf-8")
                assert "\\udcfc" not in text, args  # no lone surrogate: any reader takes it
    fitted = (latin1_folder / "out" / "p.yaml").read_bytes()
    assert seal_intact(fitted)
    source = yaml.safe_load(fitted)["source"]["input"]
    assert f"{os.sep}archiv-\\xfc{os.sep}" in source


def test_report_runs_under_a_folder_whose_name_is_no_utf8(latin1_folder: Path) -> None:
    """As a user runs it, with stdout strict UTF-8 (a UTF-8 locale): the page writers, the
    campaign's reduction and the title page all name the folder."""
    out = latin1_folder / "review"
    done = subprocess.run(
        [sys.executable, "-m", "tuflexperf", "report", "--case",
         str(latin1_folder / "requirements" / "tuflex.yaml"), "--out", str(out)],
        capture_output=True, timeout=600,
        env={**os.environ, "PYTHONIOENCODING": "utf-8", "PYTHONWARNINGS": "ignore"})
    assert done.returncode == 0, done.stderr[-3000:]
    assert b"archiv-\\xfc" in done.stdout  # the escaped name, not a lone surrogate's bytes
    assert (out / "review.pdf").stat().st_size > 0
