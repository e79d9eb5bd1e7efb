"""The terminal's tables: margins grouped and ordered, columns aligned; the JSON untouched."""

from __future__ import annotations

import json
import math
import re

from typer.testing import CliRunner

from tuflexperf.cli import app

runner = CliRunner()


def _groups(text: str) -> dict[str, list[list[str]]]:
    """margins' text: requirement -> its table rows, split on runs of spaces."""
    groups: dict[str, list[list[str]]] = {}
    current = None
    for line in text.splitlines():
        # the title, then the requirement's verdict as check gives it
        title = re.fullmatch(r"(\w+) \[[^\]]*\](  (PASS|FAIL|UNPROVEN) \(.*\))?", line)
        if title:
            current = title.group(1)
            groups[current] = []
        elif current and line.startswith("  ") and not line.strip().startswith(("-", "param")):
            groups[current].append(line)
        elif not line.strip():
            current = None
    return groups


def test_margins_are_grouped_binding_first_with_aligned_columns() -> None:
    text = runner.invoke(app, ["margins"]).stdout
    data = json.loads(runner.invoke(app, ["margins", "--json"]).stdout)["margins"]
    by_key = {(m["requirement"], m["parameter"]): m for m in data}
    groups = _groups(text)
    assert list(groups) == list(dict.fromkeys(m["requirement"] for m in data))
    for name, lines in groups.items():
        # a blank line before each group's title
        assert f"\n\n{name} [" in text
        distances = []
        for line in lines:
            row = by_key[(name, line.split()[0])]
            limit, nominal = row["limit_value"], row["value"]
            if limit is None:
                distances.append(math.inf)
            else:
                scale = abs(nominal) or (row["search_range"][1] - row["search_range"][0])
                distances.append(abs(limit - nominal) / scale)
        assert len(lines) == sum(1 for m in data if m["requirement"] == name)
        assert distances == sorted(distances), name
        # every number of a column has its decimal point in the same place
        for column in (1, 2):
            points = {line.index(".", _nth_field_start(line, column)) for line in lines
                      if line.split()[column] != "none"}
            assert len(points) == 1, (name, column, points)
    assert runner.invoke(app, ["margins", "--help"]).stdout.count("binding") >= 1


def _nth_field_start(line: str, n: int) -> int:
    return [m.start() for m in re.finditer(r"\S+", line)][n]


def test_margins_json_keeps_the_analysis_order() -> None:
    """The JSON is the analysis' rows as they come: grouping is the text's alone."""
    from tuflexperf.analysis.margins import solve_margins
    from tuflexperf.io.case import load_case

    rows = json.loads(runner.invoke(app, ["margins", "--json"]).stdout)["margins"]
    solved = solve_margins(load_case(None))
    assert [(r["requirement"], r["parameter"]) for r in rows] == [
        (m.requirement, m.parameter) for m in solved]
