"""Terminal tables of many rows: ``margins`` grouped by requirement, ``sweep`` by grid point.

Each numeric column has one number of decimals, so its decimal points line up (``%g``
columns did not). The JSON of both commands is written here too, unchanged.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np
import typer

from tuflexperf.cli.render import emit_json, overall_of, verdict_word

#: how a limit value binds -> the mark after it (explained under the table)
_BINDS_MARK = {"not attainable": "*", "envelope ends": "^", "aircraft refused": "#"}

ORDER_RULE = ("binding parameters first: smallest |limit value - nominal| / |nominal| "
              "(where the nominal is 0, over the searched range's width); 'none' last")


def relative_distance(row: Any) -> float:
    """How far ``row``'s parameter moves from its nominal to where the requirement just holds
    (a fraction of the nominal; of the searched range's width where the nominal is 0);
    inf where it never binds."""
    if row.limit_value is None:
        return math.inf
    change = abs(row.limit_value - row.value)
    if row.value != 0.0:
        return change / abs(row.value)
    low, high = row.search_range
    return change / (high - low) if high > low else math.inf


def margin_groups(rows: list[Any]) -> list[tuple[str, list[Any]]]:
    """``rows`` grouped by requirement (in the order met), each binding parameter first."""
    groups: dict[str, list[Any]] = {}
    for row in rows:
        groups.setdefault(row.requirement, []).append(row)
    # sorted is stable: parameters that never bind keep the analysis' order
    return [(name, sorted(group, key=relative_distance)) for name, group in groups.items()]


def smallest_decimals(values: Iterable[float | None], significant: int = 3) -> int:
    """Decimals (0-6) that give a column's smallest non-zero finite magnitude ``significant``
    digits: every value of the column is then shown with that many."""
    finite = [abs(v) for v in values if v is not None and math.isfinite(v) and v != 0.0]
    if not finite:
        return 0
    return int(min(6, max(0, significant - 1 - math.floor(math.log10(min(finite))))))


def _change_text(row: Any) -> str:
    if row.limit_value is None:
        return ""
    signed = math.copysign(relative_distance(row), row.limit_value - row.value)
    return f"{100 * signed:+.1f} %" + (" w" if row.value == 0.0 else "  ")


def show_margins(case: Any, rows: list[Any], notes: list[str], as_json: bool,
                 verdicts: list[Any] | None = None) -> None:
    """``margins``: per requirement its verdict (as ``check`` gives it), each parameter's
    limit value and sensitivity, binding parameters first."""
    verdicts = verdicts or []
    judged = {v.name: v for v in verdicts}
    if as_json:
        emit_json({"case": case.name, "case_file": str(case.path),
                   **({"verdict": overall_of(verdicts)} if verdicts else {}),
                   "verdicts": [v.to_dict() for v in verdicts],
                   "margins": [{**m.to_dict(), **({"verdict": judged[m.requirement].verdict}
                                                  if m.requirement in judged else {})}
                               for m in rows], "notes": notes})
        return
    typer.echo(f"{case.name}  ({case.path})")
    typer.echo("limit value: the parameter's value (others nominal) where the requirement "
               "just holds, nearest the nominal; sensitivity d(value)/d(parameter) at the nominal")
    typer.echo(f"order: {ORDER_RULE}")
    decimals = smallest_decimals([m.value for m in rows] + [m.limit_value for m in rows])
    texts = [(f"{m.value:.{decimals}f}",
              "none " if m.limit_value is None
              else f"{m.limit_value:.{decimals}f}" + _BINDS_MARK.get(m.binds, " "),
              _change_text(m),
              "n/a" if m.sensitivity is None else f"{m.sensitivity:.3e}") for m in rows]
    shown = dict(zip(((m.requirement, m.parameter) for m in rows), texts, strict=True))
    w_par = max([9, *(len(m.parameter) for m in rows)]) + 2
    w_nom = max([7, *(len(t[0]) for t in texts)]) + 2
    w_lim = max([12, *(len(t[1]) for t in texts)]) + 2
    w_chg = max([8, *(len(t[2]) for t in texts)]) + 2
    w_sen = max([11, *(len(t[3]) for t in texts)]) + 2
    header = (f"  {'parameter':<{w_par}}{'nominal':>{w_nom}}{'limit value ':>{w_lim}}"
              f"{'change  ':>{w_chg}}{'sensitivity':>{w_sen}}")
    for name, group in margin_groups(rows):
        typer.echo("")
        verdict = judged.get(name)
        said = "" if verdict is None else (
            f"  {verdict_word(verdict.verdict)} (value "
            + ("not attainable" if verdict.value is None else f"{verdict.value:.4g}")
            + f", limit {verdict.limit:g})")
        typer.echo(f"{name} [{group[0].unit}]{said}")
        typer.echo(header)
        typer.echo("  " + "-" * (len(header) - 2))
        for m in group:
            nominal, limit, change, slope = shown[(m.requirement, m.parameter)]
            typer.echo(f"  {m.parameter:<{w_par}}{nominal:>{w_nom}}{limit:>{w_lim}}"
                       f"{change:>{w_chg}}{slope:>{w_sen}}")
        if verdict is not None:  # under the table: the readings the verdict and limits rest on
            for r in verdict.readings:
                value = "not attainable" if r.value is None else f"{r.value:.4g}"
                typer.echo(f"reading: {value} on {r.label} ({'met' if r.passed else 'not met'})")
            if verdict.verdict == "UNPROVEN":
                typer.echo(f"UNPROVEN: {verdict.reason}")
                typer.echo(f"to settle: {verdict.settle}")
    typer.echo("")
    typer.echo("change: (limit value - nominal) / |nominal|; w: where the nominal is 0, over the "
               "searched range's width")
    typer.echo("none: never binds in the searched range (0.5x-2x the nominal; altitude "
               "-500..5000 m, temperature offset -50..50 K); *: binds by becoming not attainable")
    if any(m.binds == "aircraft refused" for m in rows):
        typer.echo("#: where check refuses the aircraft as bad input (a lift-off or catapult "
                   "release below stall, a stall beyond the speed of sound, thrust above 10 x "
                   "the weight, cl_ground above cl_max): the search ends there")
    if any(m.binds == "envelope ends" for m in rows):
        typer.echo("^: where the envelope's bounds cross (an equivalent-airspeed bound at that "
                   "density): beyond it the case has no envelope to fly")
    for note in notes:
        typer.echo(f"note: {note}")


def column_decimals(values: np.ndarray, significant: int = 4) -> int:
    """Decimals (0-6) that give a column's largest finite magnitude ``significant`` digits."""
    finite = np.abs(values[np.isfinite(values)])
    top = float(finite.max()) if finite.size else 0.0
    if top == 0.0:
        return significant - 1
    return int(min(6, max(0, significant - 1 - math.floor(math.log10(top)))))


def show_sweep(case: Any, result: Any, notes: list[str], written: Iterable[Path | None],
               as_json: bool) -> None:
    """``sweep``: one row per grid point, each requirement's value and verdict."""
    if as_json:
        emit_json({"case": case.name, "case_file": str(case.path), **result.to_dict(),
                   "notes": notes})
        return
    names = list(result.values)
    # each parameter column as wide as its name and a space (max_airspeed_m_s ran into the next)
    widths = [max(16, len(k.split(".")[-1]) + 2) for k in result.parameters]
    header = "".join(f"{k.split('.')[-1]:>{w}}" for k, w in zip(result.parameters, widths,
                                                                 strict=True)) + "".join(
        f"{n:>30}" for n in names)
    typer.echo(f"{case.name}  ({case.path}): {result.points.shape[0]} grid points")
    typer.echo(header)
    typer.echo("-" * len(header))
    # fixed decimals per column: the decimal points of a column line up
    shown = [column_decimals(result.points[:, k], 5) for k in range(len(widths))]
    decimals = {n: column_decimals(np.asarray(result.values[n], dtype=float)) for n in names}
    verdicts = {n: result.verdicts(n) for n in names}
    for i in range(result.points.shape[0]):
        cells = "".join(f"{v:>{w}.{d}f}" for v, w, d in zip(result.points[i], widths, shown,
                                                             strict=True))
        for n in names:
            value = result.values[n][i]
            text = "not attainable" if not np.isfinite(value) else f"{value:.{decimals[n]}f}"
            # padded as plain text: a colour's escape codes take no column
            word = str(verdicts[n][i])
            cells += f"{text + ' ' + word:>30}"[:-len(word)] + verdict_word(word)
        typer.echo(cells)
    for target in written:
        if target is not None:
            typer.echo(f"wrote {target}")
    for note in notes:
        typer.echo(f"  note: {note}")


