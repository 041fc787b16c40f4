"""Build WheelTerrain.fmu and SingleWheelRig.fmu with pythonfmu, then make their
modelDescription.xml what a Modelica-minded FMI importer expects.

pythonfmu 0.7 writes no units, types, ranges or dependencies (upstream issues #33, #193). After its
build, :func:`finish_model_description` rewrites modelDescription.xml inside the FMU from the
same :class:`wheelterrain.fmu.variables.Var` lists the slaves register:

- UnitDefinitions with SI base-unit exponents, display units deg (angles) and mm (sinkage);
- TypeDefinitions: one SimpleType per quantity, named after its Modelica.Units.SI type where
  one exists (``Modelica.Units.SI.Velocity``), else ``wheelterrain.<Quantity>``; each mode
  switch an Integer type of its own (``wheelterrain.model.contact_form``, 0..1; its
  description names the choices: an Enumeration would be set by neither libcosim nor ecos);
- declaredType, unit, min/max and a description on every variable, displayUnit where useful;
- ModelStructure: Outputs with their direct dependencies on inputs, InitialUnknowns;
- a DefaultExperiment (from the slave class);
- version, author, and a GUID derived from the description's content (same model, same GUID).

The wheelterrain package itself is bundled into resources/, so the FMU needs only numpy and
casadi in the host's Python.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import tempfile
import uuid
import zipfile
from pathlib import Path
from xml.dom import minidom
from xml.etree import ElementTree as ET

from wheelterrain import compiled as native
from wheelterrain.fmu import functions as fmu_model
from wheelterrain.fmu import variables

PACKAGE_DIR = Path(__file__).resolve().parents[1]  # the wheelterrain package, bundled whole
REPO_DIR = PACKAGE_DIR.parents[1]
SOURCES = {"WheelTerrain": "wheelterrain_slave_terrain.py",
           "SingleWheelRig": "wheelterrain_slave_rig.py",
           "RoverChassis": "wheelterrain_slave_rover.py",
           "Terrain": "wheelterrain_slave_ground.py"}
VARIABLES = variables.VARIABLES

# unit -> SI base-unit exponents (FMI 2 BaseUnit attributes)
BASE_UNITS: dict[str, dict[str, int]] = {
    "1": {},
    "m": {"m": 1},
    "m/s": {"m": 1, "s": -1},
    "rad": {"rad": 1},
    "rad/s": {"rad": 1, "s": -1},
    "m/s2": {"m": 1, "s": -2},
    "rad/s2": {"rad": 1, "s": -2},
    "kg": {"kg": 1},
    "kg.m2": {"kg": 1, "m": 2},
    "N": {"kg": 1, "m": 1, "s": -2},
    "N.m": {"kg": 1, "m": 2, "s": -2},
    "Pa": {"kg": 1, "m": -1, "s": -2},
    "N/m3": {"kg": 1, "m": -2, "s": -2},
    "Pa/m": {"kg": 1, "m": -2, "s": -2},
    "N.s/m": {"kg": 1, "s": -1},
    "s": {"s": 1},
    "N/s": {"kg": 1, "m": 1, "s": -3},
}
DISPLAY_UNITS = {"rad": {"deg": 57.29577951308232}, "m": {"mm": 1000.0}}
MODELICA_SI = {"Length", "Velocity", "Angle", "AngularVelocity", "Acceleration",
               "AngularAcceleration", "Mass", "MomentOfInertia",
               "Force", "Torque", "Pressure", "TranslationalDampingConstant",
               "DimensionlessRatio", "Time"}
NON_SI_QUANTITY = {"N/m3": "WeightDensity", "N/s": "ForceRate", "Pa/m": "PressurePerDepth"}


class BuildError(RuntimeError):
    """The FMU could not be built; the message says why."""


def source_dir() -> Path:
    """fmu_src/: inside the installed package (wheelterrain/fmu_src), else the checkout's."""
    for path in (PACKAGE_DIR / "fmu_src", REPO_DIR / "fmu_src"):
        if (path / SOURCES["WheelTerrain"]).is_file():
            return path
    raise BuildError(f"slave scripts not found in {PACKAGE_DIR / 'fmu_src'} or "
                     f"{REPO_DIR / 'fmu_src'}: the installation is incomplete (reinstall "
                     "wheelterrain)")


def build(out: Path, models: tuple[str, ...] = tuple(SOURCES),
          compiled: bool = True) -> list[Path]:
    """Build the pythonfmu FMUs into ``out``; returns their paths.

    ``compiled``: also generate WheelTerrain's Functions (:mod:`wheelterrain.fmu.functions`) as C,
    compile them and ship the libraries in its bundled package (``_compiled/*.so``), which the
    slave then calls instead of the CasADi VM. Without a C compiler the FMU is built without
    them (same results, slower); a compiler that fails is an error.
    """
    from pythonfmu.builder import FmuBuilder

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    built = []
    for name in models:
        script = source_dir() / SOURCES[name]
        with tempfile.TemporaryDirectory(prefix="wheelterrain_build_") as tmp:
            staged = Path(tmp) / "wheelterrain"
            shutil.copytree(PACKAGE_DIR, staged,
                            ignore=shutil.ignore_patterns("__pycache__", "*.pyc", "_compiled"))
            if compiled and name == "WheelTerrain" and native.compiler() is not None:
                try:
                    for fn in fmu_model.terrain_functions():
                        native.compile_function(fn, staged / "_compiled")
                except native.CompileError as err:
                    raise BuildError(str(err)) from err
            fmu = FmuBuilder.build_FMU(script, dest=tmp, project_files=[staged],
                                       canGetAndSetFMUstate=True, canSerializeFMUstate=True)
            finish_model_description(Path(fmu), name)
            target = out / f"{name}.fmu"
            partial = target.with_suffix(".fmu.part")
            shutil.copyfile(fmu, partial)
            os.replace(partial, target)  # never a half-written FMU under the final name
        built.append(target)
    return built


def _type_name(v: variables.Var) -> str:
    if v.choices:
        return f"wheelterrain.{v.name}"  # an Integer type of its own
    if v.type == "Boolean":
        return "wheelterrain.Switch"
    if v.type == "Integer":
        return "wheelterrain.Count"
    quantity = v.quantity or NON_SI_QUANTITY.get(v.unit) or (
        "DimensionlessRatio" if v.unit == "1" else None)
    if quantity is None:
        raise BuildError(f"variable {v.name}: unit {v.unit!r} has no quantity")
    prefix = "Modelica.Units.SI" if quantity in MODELICA_SI else "wheelterrain"
    return f"{prefix}.{quantity}"


def _fmt(x: float) -> str:
    return repr(float(x))


def _identify(root: ET.Element) -> None:
    """Version, author, and a GUID derived from the description's content: the same model
    built twice gets the same GUID, a changed one (variables, ranges, defaults, version)
    another. The hash is over the canonical XML (C14N, whitespace stripped), so it can be
    recomputed from the shipped file; the build time is left out of it and of the file."""
    from wheelterrain import __version__

    root.set("version", __version__)
    root.set("author", "The wheelterrain project")
    for volatile in ("guid", "generationDateAndTime"):
        root.attrib.pop(volatile, None)
    canonical = ET.canonicalize(ET.tostring(root, encoding="unicode"), strip_text=True)
    digest = hashlib.sha256(canonical.encode("utf-8")).digest()
    root.set("guid", "{" + str(uuid.UUID(bytes=digest[:16], version=5)) + "}")


# pythonfmu 0.7.0's Linux binary releases its interpreter state twice at process exit: a
# static std::shared_ptr<PyState> is destroyed by the C++ exit handlers, then the library's
# __attribute__((destructor)) finalizePythonInterpreter() assigns nullptr to that destroyed
# shared_ptr, which still holds the freed control block: a use after free that decrements
# (and may free again) freed memory. The heap is then corrupted and the host aborts at exit
# ("corrupted double-linked list", "pure virtual method called") in some runs, depending on
# what else freed memory (upstream note in fmu_src/README.md). The static destructor alone
# already destroys the state (on Windows DllMain runs first by the code's order: win64 is left);
# the fix turns the Linux destructor's call into a plain return, in our copy of the binary.
_EXIT_FIX_SYMBOL = b"finalizePythonInterpreter"
_ENDBR64 = bytes.fromhex("f30f1efa")
_EXIT_BUG_CODE = _ENDBR64 + bytes.fromhex("55660fefc0534883ec08488b2d")
"""The start of finalizePythonInterpreter as pythonfmu 0.7.0 ships it (reads the freed
shared_ptr); another start (a fixed pythonfmu) is left alone."""


def _symbol_offset(elf: bytes, symbol: bytes) -> int | None:
    """File offset of the code of dynamic ``symbol`` in a little-endian ELF64 library."""
    import struct

    if elf[:4] != b"\x7fELF" or elf[4] != 2 or elf[5] != 1:
        return None
    shoff, = struct.unpack_from("<Q", elf, 0x28)
    shentsize, shnum = struct.unpack_from("<HH", elf, 0x3A)
    sections = [struct.unpack_from("<IIQQQQIIQQ", elf, shoff + k * shentsize)
                for k in range(shnum)]
    for _, kind, _, _, offset, size, link, _, _, entsize in sections:
        if kind != 11:  # SHT_DYNSYM
            continue
        names = sections[link][4]
        for entry in range(offset, offset + size, entsize):
            name, _, _, shndx, value, _ = struct.unpack_from("<IBBHQQ", elf, entry)
            end = elf.index(b"\0", names + name)
            if elf[names + name:end] == symbol and 0 < shndx < len(sections):
                addr, file_offset = sections[shndx][3], sections[shndx][4]
                return value - addr + file_offset
    return None


def fix_exit_crash(binary: bytes) -> bytes:
    """``binary`` (pythonfmu's Linux library) with the double release at exit removed: the
    destructor's call returns at once. Unchanged if the code is not the known-bad one."""
    at = _symbol_offset(binary, _EXIT_FIX_SYMBOL)
    if at is None or binary[at:at + len(_EXIT_BUG_CODE)] != _EXIT_BUG_CODE:
        return binary
    ret = at + len(_ENDBR64)
    return binary[:ret] + b"\xc3" + binary[ret + 1:]


def finish_model_description(fmu: Path, model: str) -> None:
    """Rewrite modelDescription.xml inside ``fmu`` (see the module docstring)."""
    with zipfile.ZipFile(fmu) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
        members = {info.filename: z.read(info.filename) for info in z.infolist()}
    describe(root, model, VARIABLES[model]())
    members["modelDescription.xml"] = pretty(root)
    for name in members:
        if name.startswith("binaries/linux64/") and name.endswith(".so"):
            members[name] = fix_exit_crash(members[name])
    _install_guard(members, model, root)
    partial = fmu.with_suffix(".rewrite")
    with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data in members.items():
            z.writestr(name, data)
    os.replace(partial, fmu)


def _install_guard(members: dict[str, bytes], model: str, root: ET.Element) -> None:
    """Put the guard library (:mod:`wheelterrain.fmu.build_guard`) in front of pythonfmu's
    linux64 library: the guard becomes ``<model>.so``, pythonfmu's ``<model>_pythonfmu.so``.
    Without a C compiler the FMU keeps pythonfmu's library alone."""
    from wheelterrain.fmu import build_guard

    binary = f"binaries/linux64/{model}.so"
    guard = build_guard.guard_binary(model, root) if binary in members else None
    if guard is not None:
        members[f"binaries/linux64/{model}{build_guard.REAL_SUFFIX}.so"] = members[binary]
        members[binary] = guard


def pretty(root: ET.Element) -> bytes:
    text = minidom.parseString(ET.tostring(root, encoding="unicode")).toprettyxml(indent="  ")
    return "\n".join(line for line in text.splitlines() if line.strip()).encode("utf-8")


def describe(root: ET.Element, model: str, rows: list[variables.Var],
             states: tuple[str, ...] = ()) -> None:
    """Write the units, types, attributes, structure and GUID of ``rows`` (every variable of
    ``root``, in order) into ``root``. With ``states`` (model exchange), the outputs' dependencies
    include the states and the state derivatives (``der(...)`` rows) are listed."""
    variables = {v.name: v for v in rows}
    for tag in ("UnitDefinitions", "TypeDefinitions"):
        for old in root.findall(tag):
            root.remove(old)
    model_vars = root.find("ModelVariables")
    scalars = list(model_vars)
    index = {sv.get("name"): k + 1 for k, sv in enumerate(scalars)}
    missing = set(variables) ^ set(index)
    if missing:
        raise BuildError(f"{model}: slave and variable list disagree on {sorted(missing)}")

    # units and types actually used
    units = sorted({v.unit for v in variables.values() if v.type == "Real"})
    types: dict[str, variables.Var] = {}
    for v in variables.values():
        types.setdefault(_type_name(v), v)

    unit_defs = ET.Element("UnitDefinitions")
    for unit in units:
        u = ET.SubElement(unit_defs, "Unit", name=unit)
        ET.SubElement(u, "BaseUnit", {k: str(e) for k, e in BASE_UNITS[unit].items()})
        for display, factor in DISPLAY_UNITS.get(unit, {}).items():
            ET.SubElement(u, "DisplayUnit", name=display, factor=_fmt(factor))
    type_defs = ET.Element("TypeDefinitions")
    for name in sorted(types):
        v = types[name]
        st = ET.SubElement(type_defs, "SimpleType", name=name)
        if v.choices:
            ET.SubElement(st, "Integer", min=str(min(v.choices)), max=str(max(v.choices)))
        elif v.type == "Real":
            ET.SubElement(st, "Real", quantity=name.rsplit(".", 1)[1], unit=v.unit)
        else:
            ET.SubElement(st, v.type)
    # FMI 2 order: ..., UnitDefinitions, TypeDefinitions, LogCategories, DefaultExperiment, ...
    position = list(root).index(root.find("CoSimulation")) + 1
    root.insert(position, unit_defs)
    root.insert(position + 1, type_defs)

    for sv in scalars:
        v = variables[sv.get("name")]
        sv.set("description", v.description)
        typed = sv[0]
        typed.set("declaredType", _type_name(v))
        if v.type == "Real":
            typed.set("unit", v.unit)
            if v.display_unit:
                typed.set("displayUnit", v.display_unit)
        if v.type in ("Real", "Integer") and v.min is not None:
            cast = _fmt if v.type == "Real" else (lambda x: str(int(x)))
            typed.set("min", cast(v.min))
            typed.set("max", cast(v.max))
        if v.nominal is not None:
            typed.set("nominal", _fmt(v.nominal))
        if v.causality in ("parameter", "input") and v.start is not None:
            if v.type == "Boolean":
                typed.set("start", "true" if v.start else "false")
            elif v.type == "Integer":
                typed.set("start", str(int(v.start)))
            else:
                typed.set("start", _fmt(v.start))
        # element order inside a ScalarVariable: the type element first
        sv[:] = [typed, *[c for c in sv if c is not typed]]

    structure = root.find("ModelStructure")
    structure.clear()
    outputs = ET.SubElement(structure, "Outputs")
    derivatives = ET.SubElement(structure, "Derivatives") if states else None
    initial = ET.SubElement(structure, "InitialUnknowns")
    for sv in scalars:
        v = variables[sv.get("name")]
        if v.causality == "output":
            # inputs it depends on directly, then (model exchange) every continuous state: a
            # conservative superset, as FMI allows
            known = [*(v.depends_on or ()), *(s for s in states if s not in (v.depends_on or ()))]
            deps = " ".join(str(index[d]) for d in known)
            attrs = {"index": str(index[v.name]), "dependencies": deps}
            if deps:
                attrs["dependenciesKind"] = " ".join("dependent" for _ in known)
            ET.SubElement(outputs, "Unknown", attrs)
        elif v.derivative_of and derivatives is not None:
            ET.SubElement(derivatives, "Unknown", index=str(index[v.name]))  # depends on all
        else:
            continue
        ET.SubElement(initial, "Unknown", index=str(index[v.name]))
    _identify(root)
