"""Build the native flavour of WheelTerrain.fmu and SingleWheelRig.fmu: no Python at run time.

For each FMU:
1. the modelDescription.xml is the pythonfmu flavour's, post-processed as in
   :mod:`wheelterrain.fmu.build_pythonfmu` (same names, value references, units, types,
   structure), with the co-simulation flags of a native binary;
2. CasADi generates C for the FMU's Functions (:mod:`wheelterrain.fmu.functions`: the same ones the
   pythonfmu flavour calls);
3. model_vars.h (variable table, GUID) and model_hooks.inc (copying values in and out of those
   Functions) are generated from the variable list the slaves use;
4. fmu_src/native/fmi2_native.c (our FMI 2.0 wrapper) is compiled with them against the FMI 2
   headers shipped in fmpy, into binaries/linux64/<model>.so and, with the MinGW-w64 cross
   compiler, binaries/win64/<model>.dll;
5. the C sources go into sources/ so importers on other platforms can rebuild it.
"""

from __future__ import annotations

import copy
import os
import shutil
import subprocess
import tempfile
import zipfile
from collections.abc import Callable
from pathlib import Path
from xml.etree import ElementTree as ET

import casadi as ca

from wheelterrain import compiled as native
from wheelterrain.files import replacing
from wheelterrain.fmu import build_fmi3 as fmi3
from wheelterrain.fmu import functions as fmu_model
from wheelterrain.fmu.build_pythonfmu import build as build_pythonfmu
from wheelterrain.fmu.description import describe, pretty
from wheelterrain.fmu.toolchain import (
    BuildError,
    c_double,
    c_string,
    cross_compiler,
    fmi_headers,
    source_dir,
)
from wheelterrain.fmu.variables import (
    GROUND,
    SOIL_ROWS,
    VARIABLES,
    continuous_states,
    derivative_variables,
)
from wheelterrain.parameters import INDEX, TABLE

SOURCES = ("fmi2_native.c", "model_vars.h", "model_hooks.inc", "casadi_functions.inc",
           "fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h")
"""sources/ of a native FMU. fmi2_native.c is the one translation unit: it includes the
rest, which is why those do not end in .c, so ``cc -shared -fPIC sources/*.c -lm`` and
``fmpy compile`` build the binary as the FMI standard's source-code FMUs expect."""
CFLAGS = ("-O2", "-fPIC", "-shared", "-fvisibility=hidden", "-s", "-DWHEELTERRAIN_PORTABLE_LIBM")
"""Only the fmi2 functions are exported (the header marks them visible), the binary is
stripped, and libm's functions are bound to versions glibc >= 2.17 has (fmi2_native.c)."""
WIN64_CFLAGS = ("-O2", "-shared", "-s", "-static-libgcc", "-D__USE_MINGW_ANSI_STDIO=1")
"""A DLL that needs only the Windows C runtime (no libgcc DLL), exporting the FMI functions
of its version only (the FMI header declares them dllexport), with C99 printf formats (%zu,
%g as on Linux)."""
PLATFORMS = {"linux64": ".so", "win64": ".dll"}


def _compile(cc: str, flags, src: Path, library: Path, model: str, libs=("-lm",),
             source: str = "fmi2_native.c") -> None:
    try:
        run = subprocess.run([cc, *flags, "-I", str(src), str(src / source),
                              "-o", str(library), *libs],
                             capture_output=True, text=True, check=False)
    except OSError as err:
        raise BuildError(f"cannot run the C compiler {cc!r}: {err}") from err
    if run.returncode != 0:
        raise BuildError(f"compiling the native {model} with {cc} failed:\n{run.stderr[:4000]}")


def _model_vars(model: str, root: ET.Element) -> str:
    variables = {v.name: v for v in (*VARIABLES[model](), *derivative_variables(model))}
    scalars = list(root.find("ModelVariables"))
    rows, vr_of = [], {}
    for sv in scalars:
        name, vr = sv.get("name"), int(sv.get("valueReference"))
        if vr != len(rows):
            raise BuildError(f"{model}: value references are not 0..n-1 in order ({name})")
        v = variables[name]
        vr_of[name] = vr
        kind = {"Real": "T_REAL", "Integer": "T_INTEGER", "Boolean": "T_BOOLEAN"}[v.type]
        causality = {"parameter": "C_PARAMETER", "input": "C_INPUT", "output": "C_OUTPUT",
                     "local": "C_LOCAL"}[v.causality]
        start = float(v.start) if v.start is not None else 0.0
        has_range = int(v.min is not None)
        lo = c_double(v.min) if v.min is not None else "0.0"
        hi = c_double(v.max) if v.max is not None else "0.0"
        rows.append(f"    {{{c_string(name)}, {kind}, {causality}, {c_double(start)}, "
                    f"{has_range}, {lo}, {hi}, {c_string(v.unit)}, "
                    f"{c_string(v.description)}}},")
    states = continuous_states(model)
    held = states  # WheelTerrain's states are its continuous ones (wheel angle, plastic sinkage)
    memory = 0
    if model in fmu_model.STATE_MODELS:  # the model's states (the Terrain's rut profile: none
        held = fmu_model.STATE_MODELS[model].states  # continuous), then its step's memory
        memory = fmu_model.STATE_MODELS[model].memory
    n_states = len(held) + memory
    text = "\n".join([
        f"/* Generated by `wheelterrain build --flavor native` for {model}. Do not edit. */",
        f"#define MODEL_NAME {c_string(model)}",
        f"#define MODEL_GUID {c_string(root.get('guid'))}",
        f"#define N_VARS {len(rows)}",
        f"#define N_STATES {n_states}",
        "/* a state model without states (Terrain) has empty lists: C99 has no empty arrays */",
        "#define AT_LEAST_ONE(n) ((n) > 0 ? (n) : 1)",
        "/* CasADi's generated functions share one signature, so some leave parameters unused;",
        "   everything else is compiled with -Wall -Wextra -Werror in tests/test_native_fmus.py.",
        "   CasADi's functions are internal to the binary: hidden, whatever the build flags. */",
        "#pragma GCC diagnostic push",
        '#pragma GCC diagnostic ignored "-Wunused-parameter"',
        "#pragma GCC visibility push(hidden)",
        '#include "casadi_functions.inc"',
        "#pragma GCC visibility pop",
        "#pragma GCC diagnostic pop",
        "static const VarInfo VARS[N_VARS] = {",
        *rows,
        "};",
        "/* model exchange: the continuous states (outputs), their derivatives, nominals */",
        f"#define N_CONTINUOUS {len(states)}",
        "static const int STATE_VRS[AT_LEAST_ONE(N_CONTINUOUS)] = "
        f"{_int_list(vr_of[s] for s in states)};",
        "static const int DER_VRS[AT_LEAST_ONE(N_CONTINUOUS)] = "
        f"{_int_list(vr_of[f'der({s})'] for s in states)};",
        "static const double NOMINALS[AT_LEAST_ONE(N_CONTINUOUS)] = {"
        + (", ".join(c_double(variables[s].nominal) for s in states) or "1.0") + "};",
        f"/* for the model hooks ({HOOKS[model]}) */",
        *_hook_config(model, vr_of),
        "",
    ])
    return text


def _int_list(values) -> str:
    """A C initializer; an empty list is {-1} (the array has AT_LEAST_ONE element, unused)."""
    return "{" + (", ".join(str(int(v)) for v in values) or "-1") + "}"


HOOKS = {"WheelTerrain": "terrain_hooks.c", "SingleWheelRig": "state_hooks.c",
         "RoverChassis": "state_hooks.c", "Terrain": "state_hooks.c"}
"""The model hooks of each FMU: real C in fmu_src/native/, shipped as sources/model_hooks.inc.
What they need that is a list of names comes from model_vars.h (:func:`_hook_config`)."""


def _hook_config(model: str, vr: dict[str, int]) -> list[str]:
    """The lines of model_vars.h the hooks read: sizes, value references, status codes and the
    status messages, all from the variables table and :mod:`wheelterrain.fmu.functions`."""
    if model == "WheelTerrain":
        inputs, outputs, params = (fmu_model.TERRAIN_INPUTS, fmu_model.TERRAIN_OUTPUTS,
                                   [p.name for p in TABLE])
        lines = [f"#define N_IN {len(inputs)}"]
        lines += [f"#define VR_{name.upper()} {vr[name]}" for name in
                  ("quasi_static", "warm_start", "wheel_angle", "plastic_sinkage", "sinkage",
                   "wheel_speed", "carriage_speed", "load", "contact_sinkage", "slip_angle",
                   "yaw_rate")]
        # soil_from_inputs: the ground.* inputs replace the soil's entries of p
        lines += [f"#define VR_SOIL_FROM_INPUTS {vr['soil_from_inputs']}",
                  f"#define N_GROUND {len(GROUND)}",
                  f"static const int GROUND_VRS[{len(GROUND)}] = "
                  f"{_int_list(vr[n] for n in GROUND)};",
                  f"static const int GROUND_P[{len(GROUND)}] = "
                  f"{_int_list(INDEX[p.name] for p in SOIL_ROWS)};"]
        lines += [f"#define STATUS_{key} {c_double(getattr(fmu_model, f'STATUS_{key}'))}"
                  for key in ("OK", "SLIP", "LOAD", "UNCONVERGED", "BURIED", "NONFINITE",
                              "ANGLE", "TURN")]
        lines += [f"#define MESSAGE_{key} "
                  f"{c_string(fmu_model.STATUS_MESSAGES[getattr(fmu_model, f'STATUS_{key}')])}"
                  for key in ("SLIP", "LOAD", "UNCONVERGED", "BURIED", "NONFINITE", "ANGLE",
                              "TURN")]
    else:
        m = fmu_model.STATE_MODELS[model]
        inputs, outputs, params = m.inputs, m.outputs, list(m.parameters)
        lines = [f"#define MODEL_PREFIX {m.prefix}", f"#define N_X {len(m.states)}",
                 f"#define N_U {len(inputs)}", f"#define N_MEM {m.memory}",
                 f"#define FINITE_LIMIT {c_double(fmu_model.FINITE_LIMIT)}"]
        if m.depth_state is not None:  # a model without states has no domain to check
            lines += [f"#define DEPTH_LIMIT {c_double(m.depth_limit)}",
                      f"#define X_DEPTH {m.states.index(m.depth_state)}"]
            lines += [f"#define X_NONFINITE_{k} {m.states.index(name)}"
                      for k, name in enumerate(m.nonfinite_states)]
        lines += [f"#define MESSAGE_{key.upper()} {c_string(text)}"
                  for key, text in m.messages.items()]
    lines += [f"#define N_OUT {len(outputs)}", f"#define N_P {len(params)}",
              f"static const int IN_VRS[{len(inputs)}] = {_int_list(vr[n] for n in inputs)};",
              f"static const int OUT_VRS[{len(outputs)}] = "
              f"{_int_list(vr[n] for n in outputs)};",
              f"static const int P_VRS[{len(params)}] = {_int_list(vr[n] for n in params)};"]
    return lines


def _functions(model: str) -> list[ca.Function]:
    if model == "WheelTerrain":
        return list(fmu_model.terrain_functions())
    return list(fmu_model.STATE_MODELS[model].functions())


def _casadi_source(model: str, directory: Path) -> None:
    cg = ca.CodeGenerator("casadi_functions.c", {"with_header": False, "with_export": False})
    for fn in _functions(model):
        cg.add(fn)
    cg.generate(str(directory) + os.sep)
    # included by fmi2_native.c, so not a .c of its own (sources/*.c is one translation unit)
    os.replace(directory / "casadi_functions.c", directory / "casadi_functions.inc")


def _native_description(root: ET.Element, model: str) -> ET.Element:
    """The pythonfmu flavour's description with the native binary's capabilities: both FMI 2
    interfaces (ModelExchange before CoSimulation, as the schema orders them) and, for model
    exchange, a ``der(...)`` variable per continuous state after the co-simulation variables
    (same value references for everything else)."""
    root = copy.deepcopy(root)
    root.set("generationTool", "wheelterrain native (CasADi-generated C, own FMI 2 wrapper)")
    root.set("numberOfEventIndicators", "0")
    cs = root.find("CoSimulation")
    cs.set("needsExecutionTool", "false")
    cs.set("canHandleVariableCommunicationStepSize", "true")
    cs.set("canBeInstantiatedOnlyOncePerProcess", "false")
    cs.set("canGetAndSetFMUstate", "true")
    cs.set("canSerializeFMUstate", "true")
    cs.set("canNotUseMemoryManagementFunctions", "false")
    for old in cs.findall("SourceFiles"):
        cs.remove(old)
    sources = ET.SubElement(cs, "SourceFiles")
    ET.SubElement(sources, "File", name="fmi2_native.c")
    me = ET.Element("ModelExchange", {
        "modelIdentifier": cs.get("modelIdentifier"), "needsExecutionTool": "false",
        "completedIntegratorStepNotNeeded": "true", "canBeInstantiatedOnlyOncePerProcess": "false",
        "canNotUseMemoryManagementFunctions": "false", "canGetAndSetFMUstate": "true",
        "canSerializeFMUstate": "true"})
    ET.SubElement(ET.SubElement(me, "SourceFiles"), "File", name="fmi2_native.c")
    root.insert(list(root).index(cs), me)
    scalars = root.find("ModelVariables")
    index = {sv.get("name"): k + 1 for k, sv in enumerate(scalars)}
    derivatives = derivative_variables(model)
    for der in derivatives:
        sv = ET.SubElement(scalars, "ScalarVariable", name=der.name,
                           valueReference=str(len(scalars)), causality="local",
                           variability="continuous")
        ET.SubElement(sv, "Real", derivative=str(index[der.derivative_of]))
    describe(root, model, [*VARIABLES[model](), *derivatives], continuous_states(model))
    return root


def build(out: Path, models: tuple[str, ...] = ("WheelTerrain", "SingleWheelRig",
                                               "RoverChassis", "Terrain"),
          reference_dir: Path | None = None,
          say: Callable[[str], None] = lambda message: None) -> list[Path]:
    """Build the native FMUs into ``out`` (FMI 2.0) and ``out/fmi3`` (FMI 3.0); returns their
    paths, per model the FMI 2 then the FMI 3 one. Each has Linux binaries and, when the
    MinGW-w64 cross compiler is installed, Windows ones, all from the same sources.
    ``reference_dir``: where the pythonfmu FMUs of this build are (their modelDescription is
    the native one's start; built here when not given); ``say(message)``: told as each FMU and
    platform starts."""
    cc = native.compiler()
    if cc is None:
        raise BuildError("the native flavour needs a C compiler (cc/gcc, or $CC) on PATH")
    cross = cross_compiler()
    headers = fmi_headers()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    built = []
    with tempfile.TemporaryDirectory(prefix="wheelterrain_native_") as tmp:
        tmp = Path(tmp)
        given = [Path(reference_dir) / f"{m}.fmu" for m in models] if reference_dir else []
        if given and all(f.is_file() for f in given):
            reference = given
        else:
            say("describing the FMUs (a pythonfmu build of their modelDescription)")
            reference = build_pythonfmu(tmp / "pythonfmu", models, compiled=False)
        for model, fmu in zip(models, reference, strict=True):
            with zipfile.ZipFile(fmu) as z:
                root = _native_description(ET.fromstring(z.read("modelDescription.xml")), model)
            src = tmp / model / "sources"
            src.mkdir(parents=True)
            (src / "model_vars.h").write_text(_model_vars(model, root))
            shutil.copyfile(source_dir() / "native" / HOOKS[model], src / "model_hooks.inc")
            _casadi_source(model, src)
            shutil.copyfile(source_dir() / "native" / "fmi2_native.c", src / "fmi2_native.c")
            for header in ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h"):
                shutil.copyfile(headers / header, src / header)
            libraries = {"linux64": tmp / model / f"{model}.so"}
            say(f"compiling {model} (native, FMI 2, linux64)")
            _compile(cc, CFLAGS, src, libraries["linux64"], model)
            if cross is not None:
                say(f"compiling {model} (native, FMI 2, win64)")
                libraries["win64"] = tmp / model / f"{model}.dll"
                _compile(cross, WIN64_CFLAGS, src, libraries["win64"], model, libs=())
            target = out / f"{model}.fmu"
            with replacing(target) as partial, zipfile.ZipFile(partial, "w",
                                                               zipfile.ZIP_DEFLATED) as z:
                z.writestr("modelDescription.xml", pretty(root))
                for platform, library in libraries.items():
                    z.write(library, f"binaries/{platform}/{model}{PLATFORMS[platform]}")
                for name in SOURCES:
                    z.write(src / name, f"sources/{name}")
            built.append(target)
            say(f"compiling {model} (native, FMI 3, "
                f"{'x86_64-linux and x86_64-windows' if cross else 'x86_64-linux'})")
            built.append(_build_fmi3(model, root, src, tmp / model, out / "fmi3", cc, cross))
    return built


def _build_fmi3(model: str, root: ET.Element, src2: Path, work: Path, out: Path, cc: str,
                cross: str | None) -> Path:
    """The FMI 3.0 FMU of ``model`` from the FMI 2 build's description and sources."""
    src = work / "sources3"
    src.mkdir()
    for name in ("model_vars.h", "model_hooks.inc", "casadi_functions.inc"):
        shutil.copyfile(src2 / name, src / name)
    shutil.copyfile(source_dir() / "native" / fmi3.SOURCE, src / fmi3.SOURCE)
    shutil.copyfile(source_dir() / "native" / "fmi2_native.c", src / fmi3.FMI2_INCLUDED)
    for header in fmi3.HEADERS:
        shutil.copyfile(fmi_headers() / header, src / header)
    (src / "buildDescription.xml").write_bytes(fmi3.build_description(model))
    libraries = {"linux64": work / f"{model}.fmi3.so"}
    _compile(cc, CFLAGS, src, libraries["linux64"], model, source=fmi3.SOURCE)
    if cross is not None:
        libraries["win64"] = work / f"{model}.fmi3.dll"
        _compile(cross, WIN64_CFLAGS, src, libraries["win64"], model, libs=(),
                 source=fmi3.SOURCE)
    out.mkdir(parents=True, exist_ok=True)
    target = out / f"{model}.fmu"
    with replacing(target) as partial, zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("modelDescription.xml", pretty(fmi3.description(root)))
        for platform, library in libraries.items():
            z.write(library, f"binaries/{fmi3.PLATFORMS[platform]}/{model}"
                             f"{PLATFORMS[platform]}")
        for path in sorted(src.iterdir()):
            z.write(path, f"sources/{path.name}")
    return target
