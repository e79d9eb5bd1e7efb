"""FMI 2.0 co-simulation FMU of the thrust model, built from the exported C (no Python inside).

The FMU ``tfp_thrust.fmu`` (a zip, FMI 2.0 section 2.3) holds ``modelDescription.xml``, the
C sources (``sources/``: the model's ``tfp_thrust.c``/``.h``, the FMI wrapper ``fmu.c`` and the
Modelica Association's FMI 2.0 headers, 2-clause BSD) and the binary for this platform
(``binaries/<platform>/tfp_thrust.so``), compiled here with the C compiler.

Variables: inputs ``throttle_<i>`` (fraction per engine), ``airspeed_m_s`` (true airspeed),
``density_kg_m3``; outputs ``thrust_<i>_n`` and ``total_thrust_n``; parameter
``sample_time_s`` (the internal fixed step, default 1 ms). Each ``fmi2DoStep`` runs the C
``tfp_step`` for every sample of the grid ``start + k sample_time_s`` that falls due by its
end (any communication step size; the outputs hold between samples): the dead time
``delay_s`` (ring buffer; the input held from the communication point is its first sample, so
a step at ``t`` reaches the thrust at ``t + round(delay_s / sample_time_s) sample_time_s``, as
the C code's ``T_k = f(x_(k-N))``) and the spool lag ``lag_s`` (exact discretisation), so the
outputs are the model's dynamic thrust. Initialisation starts every engine in steady state
at its initial inputs. Inputs that the model refuses (negative or absurd airspeed,
density <= 0) make the step fail with the reason in the log.

References
----------
Modelica Association, *Functional Mock-up Interface for Model Exchange and Co-Simulation*,
version 2.0.1 (2019), sections 2.2 (modelDescription.xml), 2.3 (FMU archive), 4 (co-simulation).
"""

from __future__ import annotations

import hashlib
import io
import os
import platform
import shutil
import zipfile
from pathlib import Path
from xml.sax.saxutils import escape, quoteattr

from tuflexperf.errors import InputError
from tuflexperf.export.c_code import HEADER_NAME, SOURCE_NAME, header_text, source_text
from tuflexperf.export.cbuild import find_compiler, run_compiler
from tuflexperf.export.model import (
    EXTRAPOLATION_WARNING,
    ExportModel,
    model_notes,
    xml_comment,
)
from tuflexperf.io import swap

MODEL_IDENTIFIER = "tfp_thrust"
DEFAULT_SAMPLE_TIME_S = 0.001
FMI_HEADERS = ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h")


def platform_folder() -> str:
    """FMI 2.0 binaries folder name of this machine (``linux64``, ``darwin64``, ``win64``).

    References
    ----------
    FMI 2.0.1 standard, section 2.3 (FMU distribution, ``binaries/<platform>``).
    """
    system = {"Linux": "linux", "Darwin": "darwin", "Windows": "win"}.get(platform.system())
    if system is None:
        raise InputError(f"--format fmu: unsupported platform {platform.system()!r}")
    bits = "64" if platform.architecture()[0] == "64bit" else "32"
    return system + bits


def _guid(model: ExportModel) -> str:
    from tuflexperf import __version__ as version

    digest = hashlib.sha256(f"{model.propulsion_sha256}:{version}".encode()).hexdigest()
    return "{" + "-".join((digest[:8], digest[8:12], digest[12:16], digest[16:20],
                           digest[20:32])) + "}"


def value_references(n_engines: int) -> dict[str, int]:
    """Name -> value reference of every FMU variable, in the order the wrapper stores them.

    Parameters
    ----------
    n_engines : int
        Number of engines (one throttle input and one thrust output each).

    Returns
    -------
    dict
        Variable name (units in the name: ``_m_s``, ``_kg_m3``, ``_n``, ``_s``) -> reference.

    References
    ----------
    FMI 2.0.1 standard, section 2.2.7 (ScalarVariable, valueReference).
    """
    names = [f"throttle_{i + 1}" for i in range(n_engines)]
    names += ["airspeed_m_s", "density_kg_m3"]
    names += [f"thrust_{i + 1}_n" for i in range(n_engines)]
    names += ["total_thrust_n", "sample_time_s"]
    return {name: index for index, name in enumerate(names)}


def model_description(model: ExportModel) -> str:
    """``modelDescription.xml`` (FMI 2.0, co-simulation).

    References
    ----------
    FMI 2.0.1 standard, sections 2.2 (model description) and 4.3 (co-simulation capabilities).
    """
    from tuflexperf import __version__ as version

    prop = model.propulsion
    n = model.n_engines
    refs = value_references(n)
    low, high = prop.tested_airspeed_m_s
    variables: list[str] = []

    def scalar(name: str, causality: str, description: str, real: str, extra: str = "") -> None:
        variables.append(
            f"    <ScalarVariable name={quoteattr(name)} valueReference=\"{refs[name]}\" "
            f"causality=\"{causality}\"{extra} description={quoteattr(description)}>\n"
            f"      <Real{real}/>\n    </ScalarVariable>"
        )

    for i, engine in enumerate(prop.engines):
        scalar(f"throttle_{i + 1}", "input", f"throttle command of {engine.name}, fraction 0..1",
               ' start="0"', ' variability="continuous"')
    scalar("airspeed_m_s", "input", f"true airspeed in m/s (tested {low:g}..{high:g} m/s)",
           ' start="0"', ' variability="continuous"')
    scalar("density_kg_m3", "input", "air density in kg/m^3", f' start="{c_density(model)}"',
           ' variability="continuous"')
    for i, engine in enumerate(prop.engines):
        scalar(f"thrust_{i + 1}_n", "output",
               f"thrust of {engine.name} in N after dead time and spool lag", "",
               ' variability="continuous" initial="calculated"')
    scalar("total_thrust_n", "output", "total thrust in N", "",
           ' variability="continuous" initial="calculated"')
    scalar("sample_time_s", "parameter", "internal fixed step in s (the samples due by each "
           "communication point run; outputs hold between them)",
           f' start="{DEFAULT_SAMPLE_TIME_S!r}"',
           ' variability="fixed" initial="exact"')
    # ModelStructure indices are 1-based positions in ModelVariables
    outputs = [refs[f"thrust_{i + 1}_n"] + 1 for i in range(n)] + [refs["total_thrust_n"] + 1]
    unknowns = "\n".join(f'      <Unknown index="{k}"/>' for k in outputs)
    description = (
        f"poly22 thrust model '{prop.name}' (tuflexperf): dead time {prop.delay_s!r} s, spool "
        f"lag {prop.lag_s!r} s. {EXTRAPOLATION_WARNING} " + " ".join(model_notes(prop))
    )
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        "<!-- Provenance: "
        + escape(xml_comment("; ".join(f"{f.role} {f.label} sha256 {f.sha256}"
                                       for f in model.files)))
        + " -->\n"
        f'<fmiModelDescription fmiVersion="2.0" modelName={quoteattr(prop.name)} '
        f'guid="{_guid(model)}" description={quoteattr(description)} '
        f'generationTool="tuflexperf {version}" variableNamingConvention="flat" '
        'numberOfEventIndicators="0">\n'
        f'  <CoSimulation modelIdentifier="{MODEL_IDENTIFIER}" '
        'canHandleVariableCommunicationStepSize="true" canInterpolateInputs="false" '
        'canBeInstantiatedOnlyOncePerProcess="false" canNotUseMemoryManagementFunctions="true" '
        'canGetAndSetFMUstate="false" canSerializeFMUstate="false">\n'
        f'    <SourceFiles>\n      <File name="{SOURCE_NAME}"/>\n      <File name="fmu.c"/>\n'
        "    </SourceFiles>\n  </CoSimulation>\n"
        f'  <DefaultExperiment startTime="0" stopTime="1" stepSize="{DEFAULT_SAMPLE_TIME_S!r}"/>\n'
        "  <ModelVariables>\n" + "\n".join(variables) + "\n  </ModelVariables>\n"
        "  <ModelStructure>\n    <Outputs>\n" + unknowns + "\n    </Outputs>\n"
        "    <InitialUnknowns>\n" + unknowns + "\n    </InitialUnknowns>\n"
        "  </ModelStructure>\n</fmiModelDescription>\n"
    )


def wrapper_source(model: ExportModel) -> str:
    """``fmu.c``: the FMI 2.0 co-simulation functions around ``tfp_step``.

    References
    ----------
    FMI 2.0.1 standard, sections 2.1 (common functions) and 4.2 (co-simulation API).
    """
    n = model.n_engines
    refs = value_references(n)
    listing = ", ".join(f"{name} = {ref}" for name, ref in refs.items())
    return f"""/* FMI 2.0 co-simulation wrapper of the tuflexperf thrust model (generated).
 * Value references: {listing}. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "{HEADER_NAME}"

#define VR_AIRSPEED {refs['airspeed_m_s']}
#define VR_DENSITY {refs['density_kg_m3']}
#define VR_THRUST {refs['thrust_1_n']}
#define VR_TOTAL {refs['total_thrust_n']}
#define VR_SAMPLE_TIME {refs['sample_time_s']}
#define N_VARIABLES {len(refs)}

typedef struct {{
    tfp_state_t state;
    double values[N_VARIABLES];
    double time;
    double start_time;
    long samples_done; /* internal samples run since the start (the sample clock) */
    int initialized;
    fmi2Boolean logging;
    const fmi2CallbackFunctions *callbacks;
    char name[128];
}} instance_t;

static void say(instance_t *self, fmi2Status status, const char *message)
{{
    if (self->callbacks && self->callbacks->logger) {{
        self->callbacks->logger(self->callbacks->componentEnvironment, self->name, status,
                                status == fmi2OK ? "logAll" : "logStatusError", "%s", message);
    }}
}}

static const char *why(int code)
{{
    switch (code) {{
    case TFP_NEGATIVE_AIRSPEED: return "airspeed_m_s is negative";
    case TFP_AIRSPEED_BEYOND_MODEL: return "airspeed_m_s is above TFP_MAX_MODEL_AIRSPEED_M_S";
    case TFP_BAD_DENSITY: return "density_kg_m3 is not > 0";
    case TFP_BAD_THROTTLE: return "a throttle is outside [0, 1]";
    case TFP_CAPACITY_EXCEEDED: return "sample_time_s too small for the delay buffer";
    default: return "bad (non-finite) input or sample_time_s";
    }}
}}

static void static_outputs(instance_t *self)
{{
    double total = 0.0;
    int i;
    (void)tfp_thrust_v(self->values, self->values[VR_AIRSPEED], self->values[VR_DENSITY],
                       self->values + VR_THRUST);
    for (i = 0; i < TFP_N_ENGINES; ++i) {{
        total += self->values[VR_THRUST + i];
    }}
    self->values[VR_TOTAL] = total;
}}

const char *fmi2GetTypesPlatform(void) {{ return fmi2TypesPlatform; }}
const char *fmi2GetVersion(void) {{ return fmi2Version; }}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{{
    (void)nCategories;
    (void)categories;
    ((instance_t *)c)->logging = loggingOn;
    return fmi2OK;
}}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{{
    instance_t *self;
    int i;
    (void)fmuResourceLocation;
    (void)visible;
    if (fmuType != fmi2CoSimulation || !fmuGUID || strcmp(fmuGUID, "{_guid(model)}") != 0) {{
        return NULL;
    }}
    self = (instance_t *)calloc(1, sizeof(instance_t));
    if (!self) {{
        return NULL;
    }}
    self->callbacks = functions;
    self->logging = loggingOn;
    strncpy(self->name, instanceName ? instanceName : "tfp_thrust", sizeof(self->name) - 1);
    for (i = 0; i < N_VARIABLES; ++i) {{
        self->values[i] = 0.0;
    }}
    self->values[VR_DENSITY] = {c_density(model)};
    self->values[VR_SAMPLE_TIME] = {DEFAULT_SAMPLE_TIME_S!r};
    return self;
}}

void fmi2FreeInstance(fmi2Component c) {{ free(c); }}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{{
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    ((instance_t *)c)->time = startTime;
    ((instance_t *)c)->start_time = startTime;
    return fmi2OK;
}}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {{ (void)c; return fmi2OK; }}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{{
    instance_t *self = (instance_t *)c;
    int i;
    const int code = tfp_state_init(&self->state, self->values[VR_SAMPLE_TIME], self->values,
                                    self->values[VR_AIRSPEED], self->values[VR_DENSITY]);
    if (code != TFP_OK) {{
        say(self, fmi2Error, why(code));
        return fmi2Error;
    }}
    /* An input set at a communication point holds from that point on (FMI 2.0, 4.2.3): the
       hold itself is the first sample of the dead time, so the ring holds one less, and a
       throttle step at t reaches the thrust at t + round(delay / sample_time_s) samples, as
       the C code's T_k = f(x_(k-N)) (it arrived one sample late; outside audit). */
    for (i = 0; i < TFP_N_ENGINES; ++i) {{
        if (self->state.delay[i].length > 1) {{
            self->state.delay[i].length -= 1;
        }}
    }}
    static_outputs(self);
    self->samples_done = 0;
    self->initialized = 1;
    return fmi2OK;
}}

fmi2Status fmi2Terminate(fmi2Component c) {{ (void)c; return fmi2OK; }}

fmi2Status fmi2Reset(fmi2Component c)
{{
    instance_t *self = (instance_t *)c;
    self->initialized = 0;
    self->time = 0.0;
    self->start_time = 0.0;
    self->samples_done = 0;
    return fmi2OK;
}}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{{
    instance_t *self = (instance_t *)c;
    size_t i;
    if (!self->initialized) {{
        static_outputs(self); /* initialization mode: the static thrust at the inputs */
    }}
    for (i = 0; i < nvr; ++i) {{
        if (vr[i] >= N_VARIABLES) {{
            return fmi2Error;
        }}
        value[i] = self->values[vr[i]];
    }}
    return fmi2OK;
}}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{{
    instance_t *self = (instance_t *)c;
    size_t i;
    for (i = 0; i < nvr; ++i) {{
        const int input = vr[i] < VR_THRUST;
        const int parameter = vr[i] == VR_SAMPLE_TIME && !self->initialized;
        if (vr[i] >= N_VARIABLES || !(input || parameter)) {{
            say(self, fmi2Error, "only inputs (and sample_time_s before initialization) are set");
            return fmi2Error;
        }}
        self->values[vr[i]] = value[i];
    }}
    return fmi2OK;
}}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{{
    instance_t *self = (instance_t *)c;
    const double dt = self->values[VR_SAMPLE_TIME];
    /* the internal samples that fall due by the step's end (a sample clock from the start
       time: any communication step, the samples on one grid; outputs hold between them) */
    const double due = floor((currentCommunicationPoint + communicationStepSize
                              - self->start_time) / dt * (1.0 + 1e-12) + 1e-9);
    double total;
    int i, code;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!(communicationStepSize >= 0.0) || !isfinite(due) || due > 1e15) {{
        say(self, fmi2Error, "bad communication step");
        return fmi2Error;
    }}
    for (; self->samples_done < (long)due; ++self->samples_done) {{
        code = tfp_step(&self->state, self->values, self->values[VR_AIRSPEED],
                        self->values[VR_DENSITY], self->values + VR_THRUST);
        if (code != TFP_OK) {{
            say(self, fmi2Error, why(code));
            return fmi2Error;
        }}
    }}
    total = 0.0;
    for (i = 0; i < TFP_N_ENGINES; ++i) {{
        total += self->values[VR_THRUST + i];
    }}
    self->values[VR_TOTAL] = total;
    self->time = currentCommunicationPoint + communicationStepSize;
    return fmi2OK;
}}

/* Not provided (declared false or absent in modelDescription.xml). */
fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{{ (void)c; (void)vr; (void)value; return nvr == 0 ? fmi2OK : fmi2Error; }}
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[])
{{ (void)c; (void)vr; (void)value; return nvr == 0 ? fmi2OK : fmi2Error; }}
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[])
{{ (void)c; (void)vr; (void)value; return nvr == 0 ? fmi2OK : fmi2Error; }}
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{{ (void)c; (void)vr; (void)value; return nvr == 0 ? fmi2OK : fmi2Error; }}
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[])
{{ (void)c; (void)vr; (void)value; return nvr == 0 ? fmi2OK : fmi2Error; }}
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[])
{{ (void)c; (void)vr; (void)value; return nvr == 0 ? fmi2OK : fmi2Error; }}
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s)
{{ (void)c; (void)s; return fmi2Error; }}
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s)
{{ (void)c; (void)s; return fmi2Error; }}
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s)
{{ (void)c; (void)s; return fmi2Error; }}
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *size)
{{ (void)c; (void)s; (void)size; return fmi2Error; }}
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t size)
{{ (void)c; (void)s; (void)b; (void)size; return fmi2Error; }}
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t size,
                                   fmi2FMUstate *s)
{{ (void)c; (void)b; (void)size; (void)s; return fmi2Error; }}
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[],
                                        size_t nu, const fmi2ValueReference z[], size_t nz,
                                        const fmi2Real du[], fmi2Real dz[])
{{ (void)c; (void)u; (void)nu; (void)z; (void)nz; (void)du; (void)dz; return fmi2Error; }}
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                       size_t nvr, const fmi2Integer order[],
                                       const fmi2Real value[])
{{ (void)c; (void)vr; (void)nvr; (void)order; (void)value; return fmi2Error; }}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[],
                                        fmi2Real value[])
{{ (void)c; (void)vr; (void)nvr; (void)order; (void)value; return fmi2Error; }}
fmi2Status fmi2CancelStep(fmi2Component c) {{ (void)c; return fmi2Error; }}
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{{ (void)c; (void)s; (void)value; return fmi2Discard; }}
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{{ (void)c; (void)s; (void)value; return fmi2Discard; }}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{{ (void)c; (void)s; (void)value; return fmi2Discard; }}
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{{ (void)c; (void)s; (void)value; return fmi2Discard; }}
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{{ (void)c; (void)s; (void)value; return fmi2Discard; }}
"""


def c_density(model: ExportModel) -> str:
    """Start value of ``density_kg_m3`` [kg/m^3] as a C literal: the test day's, else ISA
    sea level.

    References
    ----------
    ISO 2533:1975 (ISA sea-level density 1.225 kg/m^3).
    """
    return repr(float(model.propulsion.reference_density_kg_m3 or 1.225))


def build_fmu(model: ExportModel, target: Path) -> Path:
    """Generate the sources, compile the binary for this platform and zip ``target`` (.fmu).

    Raises :class:`InputError` (one line) when no C compiler exists (``--format fmu`` needs
    one), or it cannot run or does not compile the generated C.

    References
    ----------
    FMI 2.0.1 standard, section 2.3 (the zip layout: modelDescription.xml, sources/, binaries/).
    """
    wanted = os.environ.get("CC", "").strip()
    if wanted and shutil.which(wanted) is None:  # said, not gcc taken instead
        raise InputError(f"--format fmu: CC={wanted!r} is no compiler on this machine (one "
                         "program, no arguments; unset CC to use gcc)")
    compiler = find_compiler()
    if compiler is None:
        raise InputError("--format fmu: needs a C compiler to build the binary (set CC or "
                         "install gcc); the other formats do not")
    files: dict[str, bytes] = {
        "modelDescription.xml": model_description(model).encode("utf-8"),
        f"sources/{HEADER_NAME}": header_text(model).encode("ascii"),
        f"sources/{SOURCE_NAME}": source_text(model).encode("ascii"),
        "sources/fmu.c": wrapper_source(model).encode("ascii"),
    }
    here = Path(__file__).resolve().parent / "fmi2"
    for name in FMI_HEADERS:
        files[f"sources/{name}"] = (here / name).read_bytes()
    with swap.scratch("export") as tmp:
        build = Path(tmp)
        for name, data in files.items():
            if name.startswith("sources/"):
                (build / name.split("/", 1)[1]).write_bytes(data)
        library = build / f"{MODEL_IDENTIFIER}.so"
        command = [compiler, "-std=c99", "-O2", "-shared", "-fPIC", "-I", str(build),
                   "-o", str(library), str(build / SOURCE_NAME), str(build / "fmu.c"), "-lm"]
        try:
            scratch = build / "tmp"
            scratch.mkdir()
            done = run_compiler(command, scratch)
        except OSError as exc:
            raise InputError(f"--format fmu: cannot run the C compiler {compiler}: "
                             f"{exc.strerror}; set CC to a working one") from None
        if done.returncode != 0:
            # the generated C compiles under -Wall -Wextra (tests): a failure is the compiler's
            # (CC=/bin/false), said in one line
            said = (done.stderr or done.stdout).strip().splitlines()
            raise InputError(f"--format fmu: the C compiler {compiler} failed (exit "
                             f"{done.returncode}): {said[0] if said else 'no message'}; set CC "
                             "to a working one")
        if not library.is_file():  # a "compiler" that exits 0 and writes nothing
            raise InputError(f"--format fmu: the C compiler {compiler} wrote no library; set "
                             "CC to a working one")
        suffix = ".dylib" if platform.system() == "Darwin" else ".so"
        files[f"binaries/{platform_folder()}/{MODEL_IDENTIFIER}{suffix}"] = library.read_bytes()
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
        for name in sorted(files):
            archive.writestr(name, files[name])
    target.write_bytes(buffer.getvalue())
    return target

