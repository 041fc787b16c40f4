"""The FMI 3.0 native FMUs: the FMI 2 native FMU's model in the FMI 3 format.

The modelDescription.xml is a translation of the native FMI 2 one (:mod:`build_native`), so
names, value references, units, types, ranges, starts, nominals and structure cannot drift
apart: Real -> Float64, Integer -> Int32 (the mode switches too: an Int32 type of their own
with min and max), Boolean -> Boolean; a state derivative names its state by value
reference; ModelStructure by value reference; the instantiation token is the FMI 2 GUID (one
model, one token). FMI 3 adds the independent variable ``time`` (value reference: the first
one after the FMI 2 variables, ``TIME_VR`` in fmi3_native.c). sources/buildDescription.xml
says how to compile the binary: one translation unit, fmi3_native.c, which includes the FMI 2
wrapper with its fmi2 functions internal.
"""

from __future__ import annotations

import copy
from xml.etree import ElementTree as ET

PLATFORMS = {"linux64": "x86_64-linux", "win64": "x86_64-windows"}
"""FMI 2 platform folder -> FMI 3 platform tuple (binaries/<tuple>/<modelIdentifier>.so|.dll)."""
SOURCE = "fmi3_native.c"
FMI2_INCLUDED = "fmi2_native.inc"
"""fmi2_native.c as the FMI 3 sources/ ship it: included by fmi3_native.c, so not a .c file."""
HEADERS = ("fmi3Functions.h", "fmi3FunctionTypes.h", "fmi3PlatformTypes.h",
           "fmi2FunctionTypes.h", "fmi2TypesPlatform.h")

_TYPE = {"Real": "Float64", "Integer": "Int32", "Enumeration": "Enumeration",
         "Boolean": "Boolean"}
_VARIABLE_ATTRIBUTES = ("name", "valueReference", "description", "causality", "variability",
                        "initial")
_TYPED_ATTRIBUTES = ("declaredType", "quantity", "unit", "displayUnit", "min", "max", "start",
                     "nominal")


def _copy(source: ET.Element, target: ET.Element, names) -> None:
    for name in names:
        if source.get(name) is not None:
            target.set(name, source.get(name))


def description(fmi2: ET.Element) -> ET.Element:
    """The FMI 3.0 modelDescription of the native FMU described (FMI 2) by ``fmi2``."""
    root = ET.Element("fmiModelDescription", fmiVersion="3.0")
    _copy(fmi2, root, ("modelName", "description", "author", "version", "copyright",
                       "license", "generationTool", "variableNamingConvention"))
    root.set("instantiationToken", fmi2.get("guid"))
    identifier = fmi2.find("CoSimulation").get("modelIdentifier")
    common = {"modelIdentifier": identifier, "needsExecutionTool": "false",
              "canBeInstantiatedOnlyOncePerProcess": "false", "canGetAndSetFMUState": "true",
              "canSerializeFMUState": "true"}
    ET.SubElement(root, "ModelExchange", {**common, "needsCompletedIntegratorStep": "false"})
    ET.SubElement(root, "CoSimulation", {**common,
                                         "canHandleVariableCommunicationStepSize": "true"})
    units = fmi2.find("UnitDefinitions")
    if units is not None:
        root.append(copy.deepcopy(units))  # the same schema in FMI 3
    types = ET.SubElement(root, "TypeDefinitions")
    for simple in fmi2.find("TypeDefinitions"):
        kind = simple[0]
        element = ET.SubElement(types, f"{_TYPE[kind.tag]}Type", name=simple.get("name"))
        _copy(kind, element, ("quantity", "unit", "displayUnit", "min", "max"))
        for item in kind.findall("Item"):
            ET.SubElement(element, "Item", name=item.get("name"), value=item.get("value"))
    for tag in ("LogCategories", "DefaultExperiment"):
        if fmi2.find(tag) is not None:
            root.append(copy.deepcopy(fmi2.find(tag)))

    scalars = list(fmi2.find("ModelVariables"))
    if "time" in {s.get("name") for s in scalars}:  # pragma: no cover - a table guard
        raise ValueError("the FMI 2 description already has a variable named time")
    vr_of_index = {k + 1: sv.get("valueReference") for k, sv in enumerate(scalars)}
    variables = ET.SubElement(root, "ModelVariables")
    ET.SubElement(variables, "Float64", name="time", valueReference=str(len(scalars)),
                  causality="independent", variability="continuous",
                  description="Simulation time", unit="s")
    for sv in scalars:
        typed = sv[0]
        if typed.tag not in ("Real", "Integer", "Boolean"):  # pragma: no cover - a table guard
            raise ValueError(f"{sv.get('name')}: fmi3_native.c serves Float64, Int32 and "
                             f"Boolean variables only, not {_TYPE[typed.tag]}")
        element = ET.SubElement(variables, _TYPE[typed.tag])
        _copy(sv, element, _VARIABLE_ATTRIBUTES)
        _copy(typed, element, _TYPED_ATTRIBUTES)
        if typed.get("derivative") is not None:
            element.set("derivative", vr_of_index[int(typed.get("derivative"))])

    structure = ET.SubElement(root, "ModelStructure")
    old = fmi2.find("ModelStructure")
    for section, tag in (("Outputs", "Output"), ("Derivatives", "ContinuousStateDerivative"),
                         ("InitialUnknowns", "InitialUnknown")):
        for unknown in old.findall(f"{section}/Unknown"):
            element = ET.SubElement(structure, tag,
                                    valueReference=vr_of_index[int(unknown.get("index"))])
            if unknown.get("dependencies") is not None:
                element.set("dependencies", " ".join(
                    vr_of_index[int(k)] for k in unknown.get("dependencies").split()))
                if unknown.get("dependenciesKind"):
                    element.set("dependenciesKind", unknown.get("dependenciesKind"))
    units = root.find("UnitDefinitions")
    if units is not None and not any(u.get("name") == "s" for u in units):
        ET.SubElement(ET.SubElement(units, "Unit", name="s"), "BaseUnit", s="1")
    return root


def build_description(model_identifier: str) -> bytes:
    """sources/buildDescription.xml: compile fmi3_native.c alone (it includes the rest)."""
    root = ET.Element("fmiBuildDescription", fmiVersion="3.0")
    config = ET.SubElement(root, "BuildConfiguration", modelIdentifier=model_identifier)
    files = ET.SubElement(config, "SourceFileSet", language="C99")
    ET.SubElement(files, "SourceFile", name=SOURCE)
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)
