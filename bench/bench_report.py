"""Time of `tuflexperf report` on the shipped TU-Flex case (target: under 15 s).

Prints, measured in this run:
- the whole console command, as a user runs it (cold process: imports, CasADi builds,
  campaign reduction, rendering, PDF);
- the same in-process, with the time of each step (from the report's own step counter);
- `fit_campaign` alone on the same campaign: the reduction the report re-runs to get
  the measured points, so "report minus fit" is what drawing costs.

Run: .venv/bin/python bench/bench_report.py
"""

from __future__ import annotations

import io
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TARGET_S = 15.0


def console_run(out: Path) -> float:
    exe = Path(sys.executable).with_name("tuflexperf")
    start = time.perf_counter()
    subprocess.run(
        [str(exe), "report", "--out", str(out), "--json"], check=True, capture_output=True
    )
    return time.perf_counter() - start


def main() -> None:
    from tuflexperf.reduction.pipeline import fit_campaign
    from tuflexperf.report import build_report

    with tempfile.TemporaryDirectory() as tmp:
        tmp_path = Path(tmp)
        cold = console_run(tmp_path / "cold")
        stream = io.StringIO()
        start = time.perf_counter()
        result = build_report(None, tmp_path / "warm", progress=True, stream=stream)
        warm = time.perf_counter() - start
        start = time.perf_counter()
        fit_campaign(ROOT / "data" / "tuflex" / "campaign" / "campaign.yaml")
        fit = time.perf_counter() - start
        sizes = [p.stat().st_size for p in result.files]

    print(
        f"tuflexperf report, shipped case: {len(result.files)} files "
        f"({result.pages}-page PDF, {sum(sizes) / 1e6:.1f} MB)"
    )
    print(
        f"  console command (cold process)  {cold:6.2f} s   "
        f"{cold / TARGET_S:.2f} x the {TARGET_S:g} s target"
    )
    print(f"  in-process build_report         {warm:6.2f} s")
    print(f"  of which fit_campaign alone     {fit:6.2f} s   ({fit / warm:.0%} of the build)")
    print("  steps (time since start, s):")
    previous = 0.0
    for line in stream.getvalue().splitlines():
        match = re.match(r"report \[(\d+)/(\d+)\] (.*) \(([\d.]+) s\)", line)
        if match:
            elapsed = float(match.group(4))
            print(f"    {match.group(3):<52} +{elapsed - previous:5.2f}  ({elapsed:5.2f})")
            previous = elapsed


if __name__ == "__main__":
    main()
