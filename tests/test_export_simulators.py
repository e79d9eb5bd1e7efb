"""The JSBSim and FMU exports in the real simulators: the ``jsbsim`` and ``fmpy`` packages.

JSBSim loads a minimal aircraft written here that includes the two exported files the way the
README tells users to; the aircraft is held at fixed true airspeed and altitude (JSBSim's
integrators switched off, so the airspeed stays exactly what the initial conditions say) while
the throttles are held, and the external force JSBSim computes must equal the model evaluated
independently from the propulsion file (poly22 typed here from SPEC 4) to 1e-6 relative.
FMPy validates the FMU and simulates a throttle step with ``simulate_fmu``; the outputs must
equal the model before the step, after the dead time, and follow the spool lag in between.
Skipped only when the package cannot be imported (install ``tuflexperf[sim]``).
"""

from __future__ import annotations

import copy
import math
import os
from pathlib import Path

import numpy as np
import pytest
import yaml

from tests.conftest import MADE_UP_PROPULSION, write_case
from tuflexperf.export import export_model
from tuflexperf.export.cbuild import find_compiler

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ROOT / "data" / "tuflex" / "propulsion.yaml"
LBF_N = 0.45359237 * 9.80665
SLUG_FT3 = LBF_N / 0.3048**4
FT = 0.3048


def _thrust(engine: dict, x: float, v: float, rho: float, rho_ref: float | None) -> float:
    """poly22 typed from SPEC 4, independent of tuflexperf.models."""
    c = engine["coefficients"]
    scale = rho / rho_ref if rho_ref else 1.0
    return scale * (c["p00"] + c["p10"] * x + c["p01"] * v + c["p20"] * x * x
                    + c["p11"] * x * v + c["p02"] * v * v)


AIRCRAFT_XML = """<?xml version="1.0"?>
<fdm_config name="tfptest" version="2.0" release="ALPHA">
  <metrics>
    <wingarea unit="M2"> 1.0 </wingarea> <wingspan unit="M"> 2.0 </wingspan>
    <chord unit="M"> 0.5 </chord>
    <location name="AERORP" unit="M"> <x>0</x> <y>0</y> <z>0</z> </location>
    <location name="EYEPOINT" unit="M"> <x>0</x> <y>0</y> <z>0</z> </location>
    <location name="VRP" unit="M"> <x>0</x> <y>0</y> <z>0</z> </location>
  </metrics>
  <mass_balance>
    <ixx unit="KG*M2"> 5 </ixx> <iyy unit="KG*M2"> 5 </iyy> <izz unit="KG*M2"> 8 </izz>
    <emptywt unit="KG"> 22 </emptywt>
    <location name="CG" unit="M"> <x>0</x> <y>0</y> <z>0</z> </location>
  </mass_balance>
  <ground_reactions>
    <contact type="STRUCTURE" name="NOSE">
      <location unit="M"> <x>-0.5</x> <y>0</y> <z>-0.3</z> </location>
      <static_friction>0.8</static_friction> <dynamic_friction>0.5</dynamic_friction>
      <spring_coeff unit="N/M">20000</spring_coeff>
      <damping_coeff unit="N/M/SEC">2000</damping_coeff>
    </contact>
  </ground_reactions>
  <!-- the README's two lines -->
  <external_reactions file="tfp_thrust_reactions"/>
  <system file="tfp_thrust_system"/>
  <aerodynamics/>
</fdm_config>
"""


def _variants(tmp_path: Path) -> dict[str, tuple[Path, dict]]:
    lagged = copy.deepcopy(MADE_UP_PROPULSION)
    lagged.update(delay_s=0.05, lag_s=0.08, reference_density_kg_m3=1.19)
    path = tmp_path / "lagged.yaml"
    path.write_text(yaml.safe_dump(lagged))
    return {"shipped": (SHIPPED, yaml.safe_load(SHIPPED.read_text())), "lagged": (path, lagged)}


def _export(tmp_path: Path, propulsion: Path, formats: tuple[str, ...]) -> Path:
    case = write_case(tmp_path / "case", propulsion=yaml.safe_load(propulsion.read_text()))
    out = tmp_path / "export"
    export_model(case, formats, out)
    return out


def _jsbsim_fdm(root: Path, out: Path):  # noqa: ANN202 - jsbsim type
    jsbsim = pytest.importorskip("jsbsim", reason="jsbsim not installed (pip install jsbsim)")
    folder = root / "aircraft" / "tfptest"
    folder.mkdir(parents=True)
    (folder / "tfptest.xml").write_text(AIRCRAFT_XML)
    for name in ("tfp_thrust_system.xml", "tfp_thrust_reactions.xml"):
        (folder / name).write_text((out / name).read_text())
    fdm = jsbsim.FGFDMExec(str(root))
    fdm.set_debug_level(0)
    assert fdm.load_model("tfptest")
    return fdm


@pytest.mark.parametrize("key", ["shipped", "lagged"])
def test_jsbsim_force_equals_the_model(tmp_path: Path, key: str) -> None:
    pytest.importorskip("jsbsim", reason="jsbsim not installed (pip install jsbsim)")
    propulsion, data = _variants(tmp_path)[key]
    out = _export(tmp_path, propulsion, ("jsbsim",))
    rho_ref = data.get("reference_density_kg_m3")
    compared = 0
    for altitude_ft, airspeed in ((0.0, 0.0), (3000.0, 12.0), (8000.0, 27.5), (1000.0, 40.0)):
        fdm = _jsbsim_fdm(tmp_path / f"jsb_{altitude_ft:.0f}_{airspeed:g}", out)
        fdm["ic/h-sl-ft"] = altitude_ft
        fdm["ic/vt-fps"] = airspeed / FT
        fdm.run_ic()
        for axis in ("rate/translational", "rate/rotational", "position/translational",
                     "position/rotational"):
            fdm["simulation/integrator/" + axis] = 0  # hold airspeed and altitude exactly
        dt = fdm.get_delta_t()
        for throttles in ((0.0, 0.0), (0.35, 0.8), (1.0, 1.0), (0.6, 0.1)):
            for i, x in enumerate(throttles):
                fdm[f"fcs/throttle-cmd-norm[{i}]"] = x
            hold_s = data.get("delay_s", 0.0) + 20 * data.get("lag_s", 0.0) + 0.1
            for _ in range(int(hold_s / dt) + 2):
                fdm.run()
            v = fdm["velocities/vtrue-fps"] * FT
            rho = fdm["atmosphere/rho-slugs_ft3"] * SLUG_FT3
            assert v == pytest.approx(airspeed, abs=1e-9)
            expected = [_thrust(e, x, v, rho, rho_ref) for e, x in zip(data["engines"], throttles,
                                                                         strict=True)]
            for i, value in enumerate(expected):
                got = fdm[f"tfp/engine-{i + 1}/thrust-lbs"] * LBF_N
                assert got == pytest.approx(value, rel=1e-6, abs=1e-9), (i, throttles, v)
            total = fdm["forces/fbx-external-lbs"] * LBF_N  # body x: forward
            assert total == pytest.approx(sum(expected), rel=1e-6, abs=1e-9)
            compared += 1
    assert compared == 16


def test_jsbsim_applies_the_dead_time(tmp_path: Path) -> None:
    """A throttle step: the force holds its old value for the dead time (JSBSim: whole frames)."""
    pytest.importorskip("jsbsim", reason="jsbsim not installed (pip install jsbsim)")
    propulsion, data = _variants(tmp_path)["shipped"]
    out = _export(tmp_path, propulsion, ("jsbsim",))
    fdm = _jsbsim_fdm(tmp_path / "jsb", out)
    fdm["ic/h-sl-ft"] = 500.0
    fdm["ic/vt-fps"] = 15.0 / FT
    fdm.run_ic()
    for axis in ("rate/translational", "rate/rotational", "position/translational",
                 "position/rotational"):
        fdm["simulation/integrator/" + axis] = 0
    dt = fdm.get_delta_t()
    for _ in range(30):
        fdm.run()
    before = fdm["tfp/engine-1/thrust-lbs"]
    fdm["fcs/throttle-cmd-norm[0]"] = 1.0
    fdm["fcs/throttle-cmd-norm[1]"] = 1.0
    trace = []
    for _ in range(int(3 * data["delay_s"] / dt)):
        fdm.run()
        trace.append(fdm["tfp/engine-1/thrust-lbs"])
    changed = next(k for k, f in enumerate(trace) if f != before)
    # JSBSim's delay buffer holds floor(d / dt) frames and passes a command on that many
    # frames minus one after the frame it was set in (documented in export/jsbsim.py)
    frames = math.floor((data["delay_s"] + 1e-9) / dt) - 1
    assert frames >= 4 and changed == frames
    rho = fdm["atmosphere/rho-slugs_ft3"] * SLUG_FT3
    full = _thrust(data["engines"][0], 1.0, 15.0, rho, data.get("reference_density_kg_m3"))
    assert trace[-1] * LBF_N == pytest.approx(full, rel=1e-6)


@pytest.mark.skipif(find_compiler() is None, reason="no C compiler (gcc) to build the FMU")
@pytest.mark.parametrize("key", ["shipped", "lagged"])
def test_fmpy_validates_and_simulates_a_throttle_step(tmp_path: Path, key: str) -> None:
    fmpy = pytest.importorskip("fmpy", reason="fmpy not installed (pip install fmpy)")
    from fmpy.validation import validate_fmu

    propulsion, data = _variants(tmp_path)[key]
    out = _export(tmp_path, propulsion, ("fmu",))
    fmu = str(out / "tfp_thrust.fmu")
    assert validate_fmu(fmu) == []
    dt, v, rho, t_step = 0.001, 18.0, 1.1, 0.3
    names = ["time", "throttle_1", "throttle_2", "airspeed_m_s", "density_kg_m3"]
    # two rows at t_step: a step, not a ramp
    signal = np.array([(0.0, 0.2, 0.3, v, rho), (t_step, 0.2, 0.3, v, rho),
                       (t_step, 0.9, 0.7, v, rho), (2.0, 0.9, 0.7, v, rho)],
                      dtype=[(n, float) for n in names])
    result = fmpy.simulate_fmu(fmu, stop_time=2.0, step_size=dt, output_interval=dt,
                               input=signal)
    t = result["time"]
    rho_ref = data.get("reference_density_kg_m3")
    delay, lag = data.get("delay_s", 0.0), data.get("lag_s", 0.0)
    for i, (x0, x1) in enumerate(((0.2, 0.9), (0.3, 0.7))):
        y = result[f"thrust_{i + 1}_n"]
        t0 = _thrust(data["engines"][i], x0, v, rho, rho_ref)
        t1 = _thrust(data["engines"][i], x1, v, rho, rho_ref)
        # independent discrete simulation: command held over each step, the output after it
        steps = math.floor(delay / dt + 0.5)
        a = math.exp(-dt / lag) if lag > 0 else 0.0
        expected = np.empty(t.size)
        state = t0
        for k in range(t.size):
            if k == 0:
                expected[k] = t0
                continue
            # the command held from a communication point reaches the thrust N samples later
            # (T_k = f(x_(k-N))); with no whole sample of delay, at the next point
            sent_at = t[k] - dt * max(steps, 1)
            command = x1 if sent_at >= t_step - 1e-9 else x0
            target = _thrust(data["engines"][i], command, v, rho, rho_ref)
            state = a * state + (1 - a) * target
            expected[k] = state
        np.testing.assert_allclose(y, expected, rtol=1e-9, atol=1e-9)
        assert y[t < t_step + delay].max() == pytest.approx(t0, rel=1e-12)  # dead time
        assert y[-1] == pytest.approx(t1, rel=1e-6)  # settled (20+ lag time constants)
    np.testing.assert_allclose(result["total_thrust_n"],
                               result["thrust_1_n"] + result["thrust_2_n"], rtol=1e-12)


@pytest.mark.skipif(find_compiler() is None, reason="no C compiler (gcc) to build the FMU")
def test_fmu_takes_any_communication_step(tmp_path: Path) -> None:
    """The FMU declares canHandleVariableCommunicationStepSize; a step of 2.5 internal
    samples, an input at 0.5005 s and a stop at 1.0005 s each failed with status 3 (outside
    audit). The samples due by each point run, on one grid: at the points both runs share,
    a 2.5 ms communication step gives the 1 ms one's thrust exactly."""
    fmpy = pytest.importorskip("fmpy", reason="fmpy not installed (pip install fmpy)")
    propulsion, data = _variants(tmp_path)["lagged"]
    out = _export(tmp_path, propulsion, ("fmu",))
    names = ["time", "throttle_1", "throttle_2", "airspeed_m_s", "density_kg_m3"]
    t_step, v, rho = 0.5005, 18.0, 1.1
    signal = np.array([(0.0, 0.2, 0.3, v, rho), (t_step, 0.2, 0.3, v, rho),
                       (t_step, 0.9, 0.7, v, rho), (2.0, 0.9, 0.7, v, rho)],
                      dtype=[(n, float) for n in names])
    runs = {h: fmpy.simulate_fmu(str(out / "tfp_thrust.fmu"), stop_time=stop, step_size=h,
                                 output_interval=h, input=signal)
            for h, stop in ((0.001, 2.0), (0.0025, 2.0005))}
    fine, coarse = runs[0.001], runs[0.0025]
    shared = np.round(np.arange(0.0, 2.0, 0.005), 6)
    at = {name: np.searchsorted(np.round(r["time"], 6), shared) for name, r in runs.items()}
    for key in ("thrust_1_n", "thrust_2_n"):
        np.testing.assert_allclose(coarse[key][at[0.0025]], fine[key][at[0.001]], rtol=1e-12)
    t1 = _thrust(data["engines"][0], 0.9, v, rho, data.get("reference_density_kg_m3"))
    assert coarse["thrust_1_n"][-1] == pytest.approx(t1, rel=1e-6)
    changed = coarse["time"][np.argmax(coarse["thrust_1_n"] != coarse["thrust_1_n"][0])]
    assert changed >= t_step - 0.0025 + data["delay_s"] - 1e-9  # the dead time held


@pytest.mark.skipif(find_compiler() is None, reason="no C compiler (gcc) to build the FMU")
def test_fmu_refuses_meaningless_inputs(tmp_path: Path) -> None:
    fmpy = pytest.importorskip("fmpy", reason="fmpy not installed (pip install fmpy)")
    out = _export(tmp_path, SHIPPED, ("fmu",))
    signal = np.array([(0.0, 0.5, 0.5, -5.0)],
                      dtype=[("time", float), ("throttle_1", float), ("throttle_2", float),
                             ("airspeed_m_s", float)])
    with pytest.raises(Exception, match="failed with status"):  # the log says: negative
        fmpy.simulate_fmu(str(out / "tfp_thrust.fmu"), stop_time=0.01, step_size=0.001,
                          input=signal)


@pytest.mark.skipif(find_compiler() is None, reason="no C compiler (gcc) to build the FMU")
def test_fmu_refuses_a_throttle_outside_the_model(tmp_path: Path) -> None:
    """Throttle 1.5 gave 174 N, 60 % above full throttle (outside audit)."""
    fmpy = pytest.importorskip("fmpy", reason="fmpy not installed (pip install fmpy)")
    out = _export(tmp_path, SHIPPED, ("fmu",))
    signal = np.array([(0.0, 1.5, 0.5, 20.0)],
                      dtype=[("time", float), ("throttle_1", float), ("throttle_2", float),
                             ("airspeed_m_s", float)])
    with pytest.raises(Exception, match="failed with status"):  # the log: outside [0, 1]
        fmpy.simulate_fmu(str(out / "tfp_thrust.fmu"), stop_time=0.01, step_size=0.001,
                          input=signal)


def test_jsbsim_holds_throttle_and_airspeed_at_the_models_edges(tmp_path: Path) -> None:
    """A simulation has no error channel: beyond [0, 1] and the model's airspeed limit the
    JSBSim export holds the input at the edge, where it extrapolated on (1.5 gave 77.5 N per
    engine; 100 m/s a rising quadratic), unlike the C code and the FMU (outside audit)."""
    pytest.importorskip("jsbsim", reason="jsbsim not installed (pip install jsbsim)")
    from tuflexperf.io.case import load_propulsion
    from tuflexperf.models.thrust import max_model_airspeed_m_s

    data = yaml.safe_load(SHIPPED.read_text())
    limit = max_model_airspeed_m_s(load_propulsion(SHIPPED))
    out = _export(tmp_path, SHIPPED, ("jsbsim",))
    for airspeed, command, held in ((20.0, 1.5, (1.0, 20.0)), (20.0, -0.3, (0.0, 20.0)),
                                    (limit + 20.0, 0.6, (0.6, limit))):
        fdm = _jsbsim_fdm(tmp_path / f"jsb_{airspeed:g}_{command:g}", out)
        fdm["ic/h-sl-ft"] = 0.0
        fdm["ic/vt-fps"] = airspeed / FT
        fdm.run_ic()
        for axis in ("rate/translational", "rate/rotational", "position/translational",
                     "position/rotational"):
            fdm["simulation/integrator/" + axis] = 0
        for i in range(2):
            fdm[f"fcs/throttle-cmd-norm[{i}]"] = command
        for _ in range(int((data["delay_s"] + 0.1) / fdm.get_delta_t()) + 2):
            fdm.run()
        rho = fdm["atmosphere/rho-slugs_ft3"] * SLUG_FT3
        for i, engine in enumerate(data["engines"]):
            expected = _thrust(engine, *held, rho, data.get("reference_density_kg_m3"))
            got = fdm[f"tfp/engine-{i + 1}/thrust-lbs"] * LBF_N
            assert got == pytest.approx(expected, rel=1e-6), (airspeed, command, i)


def test_jsbsim_lag_filter_follows_the_spool_lag(tmp_path: Path) -> None:
    """Lagged model: one time constant after the dead time JSBSim's force has made 63 % of the
    step (its lag_filter is Tustin's discretisation; 1 % is its error at 120 Hz and more)."""
    pytest.importorskip("jsbsim", reason="jsbsim not installed (pip install jsbsim)")
    propulsion, data = _variants(tmp_path)["lagged"]
    out = _export(tmp_path, propulsion, ("jsbsim",))
    fdm = _jsbsim_fdm(tmp_path / "jsb", out)
    fdm["ic/h-sl-ft"] = 500.0
    fdm["ic/vt-fps"] = 10.0 / FT
    fdm.run_ic()
    for axis in ("rate/translational", "rate/rotational", "position/translational",
                 "position/rotational"):
        fdm["simulation/integrator/" + axis] = 0
    dt = fdm.get_delta_t()
    for _ in range(int(4.0 / dt)):
        fdm.run()  # settle at throttle 0 (50 time constants)
    before = fdm["tfp/engine-1/thrust-lbs"]
    fdm["fcs/throttle-cmd-norm[0]"] = 1.0
    trace = []
    for _ in range(int(2.5 / dt)):
        fdm.run()
        trace.append(fdm["tfp/engine-1/thrust-lbs"])
    after = trace[-1]
    start = math.floor((data["delay_s"] + 1e-9) / dt) - 1  # first frame that sees the step
    assert trace[start - 1] == pytest.approx(before, rel=1e-12)
    at = start - 1 + round(data["lag_s"] / dt)
    share = (trace[at] - before) / (after - before)
    assert share == pytest.approx(1 - math.exp(-1), abs=0.01)
    rho = fdm["atmosphere/rho-slugs_ft3"] * SLUG_FT3
    full = _thrust(data["engines"][0], 1.0, 10.0, rho, data["reference_density_kg_m3"])
    assert after * LBF_N == pytest.approx(full, rel=1e-6)


def test_jsbsim_xml_stays_xml_for_any_engine_name(tmp_path: Path) -> None:
    """An engine named with a double quote wrote `<channel name="tfp-EDF"2">` (outside
    audit); every JSBSim file must parse, whatever the names hold (a double quote, or a
    comma, is now refused in an engine's name: it heads the mission's CSV columns)."""
    import xml.etree.ElementTree as ElementTree

    odd = copy.deepcopy(MADE_UP_PROPULSION)
    odd["engines"][0]["name"] = "EDF'1 <&> --x"
    path = tmp_path / "odd.yaml"
    path.write_text(yaml.safe_dump(odd))
    out = _export(tmp_path, path, ("jsbsim",))
    for name in ("tfp_thrust_system.xml", "tfp_thrust_reactions.xml"):
        ElementTree.parse(out / name)  # raises on anything that is not well-formed
    system = ElementTree.parse(out / "tfp_thrust_system.xml").getroot()
    assert any(c.get("name", "").startswith("tfp-EDF'1 <&>") for c in system.iter("channel"))


def test_a_compiler_that_fails_is_one_line_naming_it(tmp_path: Path) -> None:
    """CC=/bin/false ended the FMU export in a traceback (outside audit)."""
    import subprocess
    import sys

    for compiler, said in (("/bin/false", "the C compiler /bin/false failed"),
                           # gcc was taken instead, unsaid; "cannot write" named --out
                           ("/nonexistent/cc", "CC='/nonexistent/cc' is no compiler"),
                           ("/bin/true", "the C compiler /bin/true wrote no library")):
        done = subprocess.run([sys.executable, "-m", "tuflexperf", "export", "--format", "fmu",
                               "--out", str(tmp_path / "fmu")], capture_output=True, text=True,
                              env={**os.environ, "CC": compiler}, cwd=tmp_path)
        assert done.returncode == 2 and "Traceback" not in done.stderr
        assert said in done.stderr, done.stderr
        assert len(done.stderr.splitlines()) == 1 and not (tmp_path / "fmu").exists()


def test_an_interrupt_while_compiling_leaves_no_compiler_files_or_processes(tmp_path: Path):
    """gcc's assembler files (cc*.s, cc*.o) were left in $TMPDIR and a cc1 zombie behind
    when the export was interrupted while compiling (outside audit): the compiler runs with
    its temporary files in the export's own scratch folder, its process group ended whole."""
    import signal
    import subprocess
    import sys
    import time

    user_tmp = tmp_path / "tmp"
    user_tmp.mkdir()
    marker = tmp_path / "compiler_pid"
    compiler = tmp_path / "slowcc"
    # a compiler that writes its temporary file, starts a child of its own and takes its time
    compiler.write_text("#!/bin/sh\n"
                        f"echo $$ > {marker}\n"
                        ": > \"$TMPDIR/ccTEST.s\"\n"
                        "sleep 60 &\n"
                        "wait\n")
    compiler.chmod(0o755)
    process = subprocess.Popen([sys.executable, "-m", "tuflexperf", "export", "--format", "fmu",
                                "--out", str(tmp_path / "fmu")], cwd=tmp_path,
                               env={**os.environ, "CC": str(compiler), "TMPDIR": str(user_tmp)},
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    for _ in range(600):
        if marker.exists() and marker.read_text().strip():
            break
        time.sleep(0.05)
    pid = int(marker.read_text())
    time.sleep(0.2)
    process.send_signal(signal.SIGTERM)
    _, err = process.communicate(timeout=60)
    assert process.returncode != 0 and "Traceback" not in err
    assert list(user_tmp.iterdir()) == [], list(user_tmp.iterdir())
    assert not (tmp_path / "fmu").exists()

    from tests.test_workers_interrupt import _processes

    def living_in_group() -> list[int]:  # zombies wait for init to reap them: not living
        return [p for p, state, _, group in _processes() if group == pid and state != "Z"]

    for _ in range(100):  # the compiler's group, its child included, is killed
        if not living_in_group():
            break
        time.sleep(0.05)
    assert living_in_group() == []
