"""Time of `tuflexperf report` on the shipped case, side by side with the version before issue 9.

Prints, measured in this run:
- the whole console command as a user runs it (cold process: imports, CasADi builds,
  campaign reduction, drawing each page once as a vector PDF page and rasterising it into its
  PNG, on every core), for this checkout and for the tagged earlier version
  (``git archive before-study-restructure``, run with the same interpreter), alternated
  so that machine load hits both alike; the ratio is issue 9's figure (target <= 0.5);
- this checkout in-process, step by step (from the report's own step counter);
- ``fit_campaign`` alone: the one reduction the report runs.

Run: .venv/bin/python bench/bench_report.py [--repeats N] [--tag TAG]
"""

from __future__ import annotations

import argparse
import io
import os
import re
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TAG = "before-study-restructure"
TAG_COMMIT = "9bc9fc8"  # what the tag names: a clone without tags still has the commit


def console_run(out: Path, pythonpath: Path | None) -> float:
    env = dict(os.environ)
    if pythonpath is not None:
        env["PYTHONPATH"] = str(pythonpath)
    start = time.perf_counter()
    subprocess.run(
        [sys.executable, "-m", "tuflexperf", "report", "--out", str(out), "--json"],
        check=True, capture_output=True, env=env, cwd=out.parent,
    )
    return time.perf_counter() - start


def export_tag(tag: str, into: Path) -> Path | None:
    """The tagged tree, unpacked (None when this is not a git checkout with that tag)."""
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", tag], capture_output=True)
    if archive.returncode != 0 and tag == TAG:
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", TAG_COMMIT],
                                 capture_output=True)
    if archive.returncode != 0:
        return None
    with tarfile.open(fileobj=io.BytesIO(archive.stdout)) as tar:
        tar.extractall(into, filter="data")
    return into


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--tag", default=TAG)
    args = parser.parse_args()
    from tuflexperf.reduction.pipeline import fit_campaign
    from tuflexperf.report import build_report

    with tempfile.TemporaryDirectory() as tmp:
        tmp_path = Path(tmp)
        before_tree = export_tag(args.tag, tmp_path / "before")
        now, before = [], []
        for k in range(args.repeats):
            now.append(console_run(tmp_path / f"now{k}", None))
            if before_tree is not None:
                before.append(console_run(tmp_path / f"before{k}", before_tree))
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
        f"({result.pages}-page PDF, {sum(sizes) / 1e6:.1f} MB); median of {args.repeats}"
    )
    t_now = statistics.median(now)
    print(f"  console command, this checkout   {t_now:6.2f} s")
    if before:
        t_before = statistics.median(before)
        print(f"  console command, {args.tag} {t_before:6.2f} s")
        ratio = t_now / t_before
        print(f"  ratio now / before               {ratio:6.2f}   (issue 9 target <= 0.5)")
    else:
        print(f"  (no git tag {args.tag}: the earlier version is not timed)")
    print(f"  in-process build_report          {warm:6.2f} s")
    print(f"  of which fit_campaign alone      {fit:6.2f} s")
    print("  steps (time since start, s):")
    previous = 0.0
    for line in stream.getvalue().splitlines():
        # a step is "[k/n]", or "[k]" before the number of steps is known
        match = re.match(r"report \[(\d+)(?:/\d+)?\] (.*) \(([\d.]+) s\)", line)
        if match:
            elapsed = float(match.group(3))
            print(f"    {match.group(2):<52} +{elapsed - previous:5.2f}  ({elapsed:5.2f})")
            previous = elapsed


if __name__ == "__main__":
    main()
