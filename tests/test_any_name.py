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
