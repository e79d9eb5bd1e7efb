"""Write the fitted pack model into the shipped battery file (data/tuflex/battery.yaml).

The same reduction as `tuflexperf fit data/tuflex/battery.yaml` (which may not overwrite its
own input): the equivalent circuit fitted to the discharge runs, their sha256, the
cross-validation. Re-run after scripts/generate_discharge.py. Deterministic.
"""

from __future__ import annotations

from pathlib import Path

from tuflexperf.reduction.battery import fitted_battery_text

BATTERY = Path(__file__).resolve().parent.parent / "data" / "tuflex" / "battery.yaml"


def main() -> None:
    text, block = fitted_battery_text(BATTERY, BATTERY)
    # the shipped file is an input, as its author wrote it plus the fit block: not fit's
    # output (fit says so on a first line, so that a later fit may replace its own file)
    first, rest = text.split("\n", 1)
    BATTERY.write_text(rest if "written by `tuflexperf fit`" in first else text,
                       encoding="utf-8")
    print(f"wrote {BATTERY}: rms {block['rms_v']:.4f} V over {block['n_points']} points")


if __name__ == "__main__":
    main()
