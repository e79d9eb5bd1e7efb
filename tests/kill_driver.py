"""SIGKILL a tuflexperf command at many moments; say after each what its outputs are.

Run as ``python tests/kill_driver.py CONFIG.json`` by tests/test_kill_anywhere.py. One warm
interpreter (the commands' modules imported by a first complete run) forks a child per
trial that runs the command in-process (``tuflexperf.cli.main``), as a user's process does
after its imports; the driver kills it with SIGKILL after a random delay, or the child
kills itself at a chosen step of the output swap (``inject``). After each kill every output
is looked at: ``whole`` (a folder holding exactly what its marker lists, each file as
hashed; a file as the tool wrote it: fit's seal, or its sha256 mark), ``missing`` or
``broken``. A last complete run of each variant then says which hidden names remain.

CONFIG: ``{"cwd": ..., "seed": int, "refuse_exchange": bool, "jobs": [{"name": ...,
"variants": [[args...], ...], "outputs": [...], "kills": int, "inject": [[target, call,
"before"|"after"], ...]}]}``. Prints one JSON object.
"""

from __future__ import annotations

import json
import os
import random
import signal
import sys
import time
from pathlib import Path
from typing import Any


def _run_child(args: list[str], log: Path, inject: list[Any] | None,
               refuse_exchange: bool) -> int:
    log.touch()  # there even when the kill lands before the child opens it
    pid = os.fork()
    if pid:
        return pid
    try:  # the child: the command in-process, its streams to the log
        fd = os.open(log, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        os.dup2(fd, 1)
        os.dup2(fd, 2)
        from tuflexperf.io import swap

        if refuse_exchange:
            swap.exchange = lambda a, b: False  # type: ignore[assignment]
        if inject:
            _inject(*inject)
        from tuflexperf.cli import main

        main(args)
    except SystemExit as done:
        os._exit(done.code if isinstance(done.code, int) else 1)
    except BaseException:  # noqa: BLE001
        import traceback

        traceback.print_exc()
        os._exit(99)
    os._exit(0)


def _inject(target: str, call: int, when: str) -> None:
    """SIGKILL this process ``when`` the ``call``-th call of ``target`` (module.function)."""
    import importlib

    module_name, _, name = target.rpartition(".")
    module = importlib.import_module(module_name)
    real = getattr(module, name)
    count = [0]

    def wrapped(*args: Any, **kwargs: Any) -> Any:
        count[0] += 1
        if count[0] == call and when == "before":
            os.kill(os.getpid(), signal.SIGKILL)
        result = real(*args, **kwargs)
        if count[0] == call and when == "after":
            os.kill(os.getpid(), signal.SIGKILL)
        return result

    setattr(module, name, wrapped)


def _warm(args: list[str], log: Path) -> tuple[float, int]:
    """Run the command once here: its modules imported before the children fork; returns
    the seconds it took and its exit status."""
    start, code = time.monotonic(), 0
    saved = os.dup(1), os.dup(2)
    fd = os.open(log, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
    os.dup2(fd, 1)
    os.dup2(fd, 2)
    try:
        from tuflexperf.cli import main

        main(args)
    except SystemExit as done:
        code = done.code if isinstance(done.code, int) else 1
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for signum in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):  # the driver's own
            signal.signal(signum, signal.SIG_DFL)
    return time.monotonic() - start, code


def _state(path: Path) -> str:
    """``whole``, ``missing`` or ``broken: why`` (module docstring)."""
    from tuflexperf.io import artefacts, files

    if not os.path.lexists(path):
        return "missing"
    if path.is_dir():
        marker = files._read_marker_data(path)
        listed = marker.get("sha256")
        if not isinstance(listed, dict):
            return "broken: no marker"
        present = {p.relative_to(path).as_posix() for p in path.rglob("*") if p.is_file()}
        if present - {files.MARKER} != set(listed):
            return f"broken: holds {sorted(present ^ set(listed))}"
        changed = [n for n, h in listed.items() if files.sha256_of(path / n) != h]
        return f"broken: changed {changed}" if changed else "whole"
    data = path.read_bytes()
    if path.suffix in (".yaml", ".yml"):
        return "whole" if files.seal_intact(data) else "broken: seal"
    mark = artefacts.written_mark(path)
    return "whole" if mark == files.sha256_of(path) else f"broken: mark {mark}"


def _hidden(cwd: Path, outputs: list[str]) -> dict[str, str]:
    """Each hidden name beside an output, with its :func:`_state`."""
    prefixes = tuple(f".{Path(o).name}." for o in outputs)
    return {p.name: _state(p) for p in sorted(cwd.iterdir()) if p.name.startswith(prefixes)}


def main() -> None:
    config = json.loads(Path(sys.argv[1]).read_text())
    cwd = Path(config["cwd"])
    os.chdir(cwd)
    rng = random.Random(config["seed"])
    refuse = bool(config.get("refuse_exchange"))
    logs = cwd / "logs"
    logs.mkdir(exist_ok=True)
    report: dict[str, Any] = {"trials": [], "complete": []}

    def complete(job: str, args: list[str]) -> float:
        log = logs / f"{job}-complete-{len(report['complete'])}.txt"
        start = time.monotonic()
        _, status = os.waitpid(_run_child(args, log, None, refuse), 0)
        seconds = time.monotonic() - start
        report["complete"].append({"job": job, "status": os.waitstatus_to_exitcode(status),
                                   "log": log.read_text(errors="replace")})
        return seconds

    for job in config["jobs"]:
        name, variants, outputs = job["name"], job["variants"], job["outputs"]
        # the first variant here (imports and all: its time is an upper bound), the others
        # in children; each leaves the earlier output the next kill must keep
        seconds, code = _warm(variants[0], logs / f"{name}-warm.txt")
        report["complete"].append({"job": name, "status": code,
                                   "log": (logs / f"{name}-warm.txt").read_text()})
        durations = [seconds, *(complete(name, args) for args in variants[1:])]
        # a child's run: the warm one here counted the imports too (an upper bound only)
        spread = max(durations[1:]) if len(durations) > 1 else durations[0]
        trials: list[tuple[str, Any, list[str]]] = [
            ("random", rng.uniform(0.0, 1.1 * spread), variants[k % len(variants)])
            for k in range(job.get("kills", 0))]
        trials += [("inject", point, variants[k % len(variants)])
                   for k, point in enumerate(job.get("inject", []))]
        for kind, when, args in trials:
            log = logs / f"{name}-{len(report['trials'])}.txt"
            pid = _run_child(args, log, when if kind == "inject" else None, refuse)
            if kind == "random":
                time.sleep(when)
                os.kill(pid, signal.SIGKILL)
            _, status = os.waitpid(pid, 0)
            report["trials"].append({
                "job": name, "kind": kind, "when": when, "args": args,
                "killed": os.WIFSIGNALED(status),
                "status": os.waitstatus_to_exitcode(status),
                "states": {o: _state(cwd / o) for o in outputs},
                "hidden": _hidden(cwd, outputs),
            })
        for args in variants:  # the next runs: each completes and cleans what was left
            complete(name, args)
        import tempfile

        scratch = sorted(p.name for p in Path(tempfile.gettempdir()).iterdir()
                         if p.name.startswith("tuflexperf-"))  # killed runs' scratch folders
        report.setdefault("after", {})[name] = {
            "states": {o: _state(cwd / o) for o in outputs}, "hidden": _hidden(cwd, outputs),
            "scratch": scratch}
    print(json.dumps(report))


if __name__ == "__main__":
    main()
