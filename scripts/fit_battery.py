"""Write the fitted pack model into the shipped battery file (data/tuflex/battery.yaml).

The same reduction as `tuflexperf fit data/tuflex/battery.yaml` (which may not overwrite its
own input): the equivalent circuit fitted to the discharge runs, their sha256, the
cross-validation, and the measured power correction against the shipped propulsion file's
power surfaces. Re-run after scripts/generate_discharge.py. Deterministic to rounding: where
the fitted numbers equal the shipped ones to 1e-9 (the least-squares fit's last digits vary
with the machine's BLAS), the shipped text is kept and only the power correction rewritten.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import yaml

from tuflexperf.reduction.battery import fitted_battery_text

BATTERY = Path(__file__).resolve().parent.parent / "data" / "tuflex" / "battery.yaml"
PROPULSION = BATTERY.parent / "propulsion.yaml"
CORRECTION = "  power_correction:\n"


def _close(a: Any, b: Any) -> bool:
    """Equal structures, floats to 1e-9 relative."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_close(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_close(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, float) or isinstance(b, float):
        return math.isclose(float(a), float(b), rel_tol=1e-9, abs_tol=1e-12)
    return bool(a == b)


def _without_correction(text: str) -> str:
    """The file's text with its ``fit.power_correction`` sub-block left out."""
    kept, skipping = [], False
    for line in text.splitlines(keepends=True):
        if line == CORRECTION:
            skipping = True
            continue
        if skipping and line.startswith("    "):
            continue
        skipping = False
        kept.append(line)
    return "".join(kept)


def main() -> None:
    text, block = fitted_battery_text(BATTERY, BATTERY, PROPULSION)
    # the shipped file is an input, as its author wrote it plus the fit block: not fit's
    # output (fit says so on a first line, so that a later fit may replace its own file)
    first, rest = text.split("\n", 1)
    text = rest if "written by `tuflexperf fit`" in first else text
    old = _without_correction(BATTERY.read_text(encoding="utf-8"))
    shipped = (yaml.safe_load(old) or {}).get("fit") or {}
    fresh = {k: v for k, v in block.items() if k != "power_correction"}
    if _close(shipped, fresh):  # the same fit to rounding: its numbers stay as shipped
        dumped = yaml.safe_dump({"power_correction": block["power_correction"]},
                                sort_keys=False, width=100)
        text = old.rstrip("\n") + "\n" + "".join("  " + line + "\n"
                                                 for line in dumped.splitlines())
    BATTERY.write_text(text, encoding="utf-8")
    print(f"wrote {BATTERY}: rms {block['rms_v']:.4f} V over {block['n_points']} points; "
          f"power correction {block['power_correction']['form']}")


if __name__ == "__main__":
    main()
