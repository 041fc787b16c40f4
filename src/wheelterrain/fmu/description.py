"""The FMI 2.0 modelDescription.xml of every FMU, written from the one variable table
(:mod:`wheelterrain.fmu.variables`): what a Modelica-minded importer expects and pythonfmu 0.7
does not write (upstream issues #33, #193).

- UnitDefinitions with SI base-unit exponents, display units deg (angles) and mm (sinkage);
- TypeDefinitions: one SimpleType per quantity, named after its Modelica.Units.SI type where
  one exists (``Modelica.Units.SI.Velocity``), else ``wheelterrain.<Quantity>``; each mode
  switch an Integer type of its own (``wheelterrain.model.contact_form``, 0..1; its
  description names the choices: an Enumeration would be set by neither libcosim nor ecos);
- declaredType, unit, min/max and a description on every variable, displayUnit where useful;
- ModelStructure: Outputs with their direct dependencies on inputs (model exchange: and the
  states), Derivatives, InitialUnknowns;
- version, author, and a GUID derived from the description's content (same model, same GUID).

The pythonfmu build (:mod:`wheelterrain.fmu.build_pythonfmu`) and the native one
(:mod:`wheelterrain.fmu.build_native`) both call :func:`describe`; the FMI 3.0 description is
derived from it (:mod:`wheelterrain.fmu.build_fmi3`).
"""

from __future__ import annotations

import hashlib
import uuid
from xml.dom import minidom
from xml.etree import ElementTree as ET

from wheelterrain.fmu import variables
from wheelterrain.fmu.toolchain import BuildError

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
DISPLAY_UNITS = {"rad": {"deg": 57.29577951308232}, "m": {"mm": 1000.0}, "Pa": {"kPa": 1e-3}}
MODELICA_SI = {"Length", "Velocity", "Angle", "AngularVelocity", "Acceleration",
               "AngularAcceleration", "Mass", "MomentOfInertia",
               "Force", "Torque", "Pressure", "TranslationalDampingConstant",
               "DimensionlessRatio", "Time"}
NON_SI_QUANTITY = {"N/m3": "WeightDensity", "N/s": "ForceRate", "Pa/m": "PressurePerDepth"}


def type_name(v: variables.Var) -> str:
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


def identify(root: ET.Element) -> None:
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
        types.setdefault(type_name(v), v)

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
        typed.set("declaredType", type_name(v))
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
    identify(root)
