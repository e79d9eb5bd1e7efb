"""Speed of the `fit` reduction on the shipped campaign, stage by stage, against a naive way.

Prints samples per second for each stage of tuflexperf's reduction over every
run of data/tuflex/campaign, the whole `fit` end to end, and the same cleaning
and change-point search done the naive way (pandas rolling mean/std/median,
then ruptures' PELT with the l2 cost on the full-rate signal) on the first
NAIVE_SECONDS of one run (PELT at full rate grows faster than linearly, so it is
kept bounded), with the ratio.

Run: ``.venv/bin/python bench/bench_fit.py``. Not a test: nothing is asserted.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from tuflexperf.io.campaign import load_campaign
from tuflexperf.io.runs import read_run
from tuflexperf.reduction.campaign_fit import fit_campaign
from tuflexperf.reduction.changepoints import force_changepoints, throttle_plateaus
from tuflexperf.reduction.delay import estimate_delay
from tuflexperf.reduction.filters import filloutliers_movmean, movmedian, window_samples
from tuflexperf.reduction.step_runs import reduce_step_run

ROOT = Path(__file__).resolve().parent.parent
CAMPAIGN = ROOT / "data" / "tuflex" / "campaign" / "campaign.yaml"
NAIVE_RUN = "runs/edf1_v30p0.csv.gz"
NAIVE_SECONDS = 10.0
REPEATS = 3


def best_of(func, repeats: int = REPEATS, clock=time.perf_counter) -> tuple[float, object]:
    """Least time of ``repeats`` calls (s; wall time unless ``clock`` says otherwise) and the
    last result."""
    best, result = float("inf"), None
    for _ in range(repeats):
        start = clock()
        result = func()
        best = min(best, clock() - start)
    return best, result


def line(label: str, samples: int, seconds: float) -> None:
    print(
        f"  {label:<44}{samples:>10,d} samples {seconds * 1e3:9.1f} ms "
        f"{samples / seconds / 1e6:8.2f} M samples/s"
    )


def main() -> None:
    campaign = load_campaign(CAMPAIGN)
    steps = campaign.of_kind("throttle_steps")
    sweeps = campaign.of_kind("sine_sweep")
    print(f"campaign: {CAMPAIGN.relative_to(ROOT)} ({len(campaign.runs)} runs)")

    # warm, best of REPEATS, like the fit below (the first read also imports SciPy's .mat reader)
    read_s, runs = best_of(lambda: [read_run(r.path, vendor=r.vendor) for r in campaign.runs])
    data = dict(zip([r.file for r in campaign.runs], runs, strict=True))
    total = sum(r.n_samples for r in runs)
    step_samples = sum(data[r.file].n_samples for r in steps)
    sweep_samples = sum(data[r.file].n_samples for r in sweeps)
    print("tuflexperf reduction, per stage:")
    line("read (csv, csv.gz, mat)", total, read_s)

    def windows(run):
        fs = run.sample_rate_hz
        return window_samples(2.0, fs), window_samples(0.1, fs)

    t_out, filled = best_of(
        lambda: [
            filloutliers_movmean(data[r.file]["force_n"], windows(data[r.file])[0], 1.5)[0]
            for r in steps
        ]
    )
    line("outliers, 2 s moving mean, 1.5 std", step_samples, t_out)
    t_med, smooth = best_of(
        lambda: [movmedian(f, windows(data[r.file])[1]) for f, r in zip(filled, steps, strict=True)]
    )
    line("moving median 0.1 s", step_samples, t_med)
    t_cp, _ = best_of(
        lambda: [
            force_changepoints(s, data[r.file].sample_rate_hz)
            for s, r in zip(smooth, steps, strict=True)
        ]
    )
    line("change points (20 Hz KernelCPD + refine)", step_samples, t_cp)
    t_pl, _ = best_of(
        lambda: [
            throttle_plateaus(data[r.file]["throttle"], data[r.file].sample_rate_hz) for r in steps
        ]
    )
    line("throttle plateaus", step_samples, t_pl)
    t_seg, _ = best_of(lambda: [reduce_step_run(campaign, r, data[r.file], 0.05) for r in steps])
    line("whole step-run reduction (all of the above)", step_samples, t_seg)
    t_delay, _ = best_of(
        lambda: [
            estimate_delay(
                data[r.file].time_s,
                data[r.file]["throttle"],
                data[r.file]["force_n"],
                data[r.file].sample_rate_hz,
            )
            for r in sweeps
        ],
        repeats=1,
    )
    line("delay + lag fit (sine sweeps)", sweep_samples, t_delay)
    t_all, _ = best_of(lambda: fit_campaign(CAMPAIGN))
    line("fit_campaign end to end (read .. poly22)", total, t_all)
    print(f"  fit / read = {t_all / read_s:.2f}   (issue 9 target <= 1.5)")
    # the same two in CPU time of all threads: the work, whatever cores the machine has free
    # (fit_campaign reads and reduces runs on a thread pool; the read above is one thread)
    cpu_read, _ = best_of(
        lambda: [read_run(r.path, vendor=r.vendor) for r in campaign.runs], clock=time.process_time
    )
    cpu_all, _ = best_of(lambda: fit_campaign(CAMPAIGN), clock=time.process_time)
    print(f"  CPU time: read {cpu_read * 1e3:.1f} ms, fit_campaign {cpu_all * 1e3:.1f} ms "
          f"(all threads), fit / read = {cpu_all / cpu_read:.2f}")
    # The least any reduction that follows the paper (section 4) can add to the read: the
    # stages it names, each as timed above, and nothing else (no transient fit, refiltered
    # steady stretches, segment means, drag, poly22 or electrical fits).
    filters = read_s + t_out + t_med
    named = filters + t_cp + t_delay
    print(f"  read + the paper's two filters (outlier fill, moving median) = "
          f"{filters / read_s:.2f} x read; + its change points and sine-sweep delay = "
          f"{named / read_s:.2f} x read (the floor of any reduction that follows the paper)")

    # --- naive: pandas rolling + ruptures PELT at full rate, on a bounded piece ---------
    import pandas as pd
    import ruptures

    run = data[NAIVE_RUN]
    n = int(NAIVE_SECONDS * run.sample_rate_hz)
    force = run["force_n"][:n]
    k_out, k_med = windows(run)

    def naive() -> list[int]:
        s = pd.Series(force)
        mean = s.rolling(k_out, center=True, min_periods=1).mean()
        std = s.rolling(k_out, center=True, min_periods=1).std().fillna(0.0)
        cleaned = s.where((s - mean).abs() <= 1.5 * std, mean)
        y = cleaned.rolling(k_med, center=True, min_periods=1).median().to_numpy()
        sigma2 = np.var(np.diff(y)) / 2
        algo = ruptures.Pelt(model="l2", min_size=int(0.5 * run.sample_rate_hz), jump=1)
        return algo.fit(y.reshape(-1, 1)).predict(pen=10 * sigma2 * np.log(n))

    def ours() -> list[int]:
        cleaned, _ = filloutliers_movmean(force, k_out, 1.5)
        return force_changepoints(movmedian(cleaned, k_med), run.sample_rate_hz)

    t_naive, _ = best_of(naive, repeats=1)
    t_ours, _ = best_of(ours)
    print(f"naive vs tuflexperf, clean + change points on {NAIVE_SECONDS:g} s of {NAIVE_RUN}:")
    line("naive: pandas rolling + PELT l2 full rate", n, t_naive)
    line("tuflexperf: cumsum filters + decimated CPD", n, t_ours)
    print(f"  speed-up: {t_naive / t_ours:,.0f}x")


if __name__ == "__main__":
    main()
