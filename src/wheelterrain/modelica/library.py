"""The WheelTerrain Modelica library, generated from the model's CasADi Functions and the one
parameter table (``wheelterrain build --flavor modelica``).

What it writes (a directory-structured library, ``package.mo`` and ``package.order`` at every
level), and where each part comes from:

- ``Functions``: the contact (with the soil's memory, ripple on: the WheelTerrain FMU's) and
  the quasi-static contact (the steady state's), one function per contact form
  (:func:`wheelterrain.model.contact.export_kernels`), each with its derivative function
  (CasADi's forward mode, ``annotation(derivative(zeroDerivative=p))``), a function choosing
  the form as the model's switch does, the two slips (:mod:`wheelterrain.fmu.functions`), and
  ``Index``: the position of each output in the functions' output vectors; every argument a
  ``Modelica.Units.SI`` type (or Real with its unit where SI has none).
  ``Functions.External``: the same functions calling the C CasADi generates from the same
  Functions (:mod:`.external`); ``Functions.Interfaces``: the signatures the
  components' replaceable contact functions are constrained by.
- ``Data``: every preset as a parameter vector in table order (no MSL needed).
- ``Records``: the parameter table as records with ``Modelica.Units.SI`` types, ranges,
  descriptions and sources; every preset a record (rumoca 0.10 cannot flatten a reference to
  a record constant); ``parameterVector``.
- ``Components``: ``QuasiStaticWheel``, ``Wheel``, ``MapWheel`` (on the terrain map),
  ``SoilWheel`` and ``RoverChassis`` (blocks: MSL's RealInput and RealOutput connectors) and
  ``Contact`` on MSL flanges (Rotational hub, Translational axle and vertical), the soil's
  memory a state, each contact function replaceable (generated or external).
- ``Wheels.PlanarWheel`` (a wheel on PlanarMechanics' Frame with a Rotational axle flange,
  the soil's memory its state), ``Terrain`` (the ``inner`` ground: flat, a plane or a
  profile; its soil the terrain map's; replaceable height, slope and soil functions,
  ``Functions.Ground``), ``Types`` (enumerations), ``Components.SoilWheel`` (the Wheel with its
  soil as an input).
- ``Examples``: ``SteadyC2``, ``SlipRamp``, ``Rover``, ``RoverSlope``, ``RoverDescent``,
  ``RoverPullTest``, ``RoverSoftPatch`` and ``RigC1`` ... ``RigC4`` (the paper's
  rig from MSL components), ``PlanarRig`` (the rig with a PlanarWheel, level or tilted) with
  ``Utilities.RigCarriage``, ``PlanarRover`` and ``PlanarRoverSlope`` (the rover from standard
  parts: ``Utilities.PlanarBody``, PlanarMechanics' FixedTranslation axles, four PlanarWheels,
  four ``Utilities.SpeedDrive``; Rover's and RoverSlope's references), with ``experiment``
  annotations at which they reproduce their
  reference results (``Resources/Reference``, MSL's regression layout: each example's CSV and
  ``comparisonSignals.txt``) written by the Python model.
- ``UsersGuide``: conventions, slips, citations, the name map, what was tested in which tool.

The output is deterministic: the same bytes on every run.
"""

from __future__ import annotations

import html
import math
import re
import string
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources
from pathlib import Path

import casadi as ca
import numpy as np

from wheelterrain import __version__, presets
from wheelterrain.model import contact, ground, rover
from wheelterrain.modelica import external, names, reference, translate
from wheelterrain.modelica.translate import Port
from wheelterrain.parameters import (
    NAMES,
    RIG_TABLE,
    SLIP_ANGLE_LIMIT,
    TABLE,
    TURN_SLIP_LIMIT,
    Parameter,
)

LIBRARY = "WheelTerrain"
MSL_VERSION = "4.1.0"
PLANAR_MECHANICS_VERSION = "1.6.0"
FORM_NAMES = {"arc": "Arc", "arc_reversal": "ArcReversal", "patch": "Patch"}
GROUPS = {"wheel": "wheel", "grouser": "grouser", "soil": "soil", "ripple": "ripple",
          "model": "options"}
"""Table group -> the Parameters record's component ('model' is a Modelica keyword)."""
KEYWORDS = frozenset((
    "algorithm", "and", "annotation", "block", "break", "class", "connect", "connector",
    "constant", "constrainedby", "der", "discrete", "each", "else", "elseif", "elsewhen",
    "encapsulated", "end", "enumeration", "equation", "expandable", "extends", "external",
    "false", "final", "flow", "for", "function", "if", "import", "impure", "in", "initial",
    "inner", "input", "loop", "model", "not", "operator", "or", "outer", "output", "package",
    "parameter", "partial", "protected", "public", "pure", "record", "redeclare", "replaceable",
    "return", "stream", "then", "true", "type", "when", "while", "within"))


def modelica_name(table_name: str) -> str:
    """The Records.Parameters component of a table row: 'soil.phi' -> 'soil.phi',
    'model.contact_form' -> 'options.contactForm' (the library's names, :mod:`.names`; a
    keyword gets a trailing underscore)."""
    group, _, field_ = table_name.partition(".")
    field_ = field_ + "_" if field_ in KEYWORDS else names.identifier(field_)
    return f"{GROUPS[group]}.{field_}"


def preset_constant(name: str) -> str:
    """'rashid-patch' -> 'rashidPatch', 'paper-table2-arc' -> 'paperTable2Arc'."""
    words = name.replace("_", "-").split("-")
    return words[0] + "".join(w[:1].upper() + w[1:] for w in words[1:])


def preset_record(name: str) -> str:
    """'rashid-patch' -> 'RashidPatch': the preset's record in Records.Presets."""
    const = preset_constant(name)
    return const[:1].upper() + const[1:]


@dataclass
class Library:
    """The library as files: relative path -> text."""

    files: dict[str, str] = field(default_factory=dict)

    def add(self, path: str, text: str) -> None:
        if path in self.files:
            raise ValueError(f"{path} written twice")
        self.files[path] = text

    def package(self, where: str, name: str, description: str, order: Sequence[str],
                annotation: str = "") -> None:
        """``where/name/package.mo`` and ``package.order`` (``where`` '' for the top)."""
        folder = f"{where}/{name}" if where else name
        within = _within(where)
        ann = f"\n  annotation({annotation});" if annotation else ""
        self.add(f"{folder}/package.mo",
                 f'{within}package {name} "{description}"{ann}\nend {name};\n')
        self.add(f"{folder}/package.order", "".join(f"{n}\n" for n in order))

    def write(self, out: Path) -> list[Path]:
        written = []
        for rel, text in sorted(self.files.items()):
            path = out / rel
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text, encoding="utf-8", newline="\n")
            written.append(path)
        return written


def _within(where: str) -> str:
    return f"within {where.replace('/', '.')};\n" if where else "within ;\n"


def _class_file(lib: Library, where: str, name: str, text: str) -> None:
    lib.add(f"{where}/{name}.mo", _within(where) + text)


def _vector(values: Sequence[float]) -> str:
    return "{" + ", ".join(translate.literal(float(v)) for v in values) + "}"


def _doc(text: str) -> str:
    """A Modelica string literal's content: quotes and backslashes escaped."""
    return text.replace("\\", "\\\\").replace('"', '\\"')


# ---- Functions ----------------------------------------------------------------------------

INPUT_DOC = {
    "sinkage": "sinkage of the contact circle below the undisturbed surface",
    "sinkage_rate": "d(sinkage)/dt",
    "slip": "the model's slip (omega*R_ref - V)/max(omega*R_ref, V): traction driving, skid "
            "braking",
    "wheel_angle": "wheel angle, the grouser ripple's phase",
    "plastic_sinkage": "the deepest the wheel has pressed the soil under it (its memory)",
    "carriage_speed": "the axle's forward speed V",
    "wheel_speed": "the wheel's angular velocity omega",
    "slip_paper": "the paper's slip s = (omega*R_ref - V)/V",
    "slip_angle": "the slip angle between the wheel's heading and its velocity, positive when "
                  "it moves toward its left",
    "turn_slip": "the turn slip, the wheel's yaw rate over its forward speed, positive "
                 "counter-clockwise seen from above",
    "mean_pressure": "the contact's mean pressure at the yield sinkage (contact's output "
                     "mean_pressure at the same state)",
    "p": "the parameters in table order (Data, Records.parameterVector)",
    "r": "the rover's parameters in table order (Data.rover)",
    "x": "the chassis' state (Index.RoverState order)",
    "u": "the chassis' inputs (Index.RoverInput order)",
    "position": "where the point is along the path",
    "g": "the terrain map's parameters in table order (Data.terrain)",
}
INPUT_UNIT = {"sinkage": "m", "sinkage_rate": "m/s", "slip": "1", "wheel_angle": "rad",
              "plastic_sinkage": "m", "carriage_speed": "m/s", "wheel_speed": "rad/s",
              "slip_paper": "1", "slip_angle": "rad", "turn_slip": "rad/m",
              "mean_pressure": "Pa", "position": "m"}
"""The scalar inputs' units (their Modelica.Units.SI types, translate.SI_TYPES); the vectors
(p, r, x, u, g) hold mixed units."""


PARAMETER_INPUTS = ("p", "r", "g")
"""Inputs that are parameter vectors: the table's (p), the rover's (r), the terrain map's (g);
zero derivative in every derivative annotation."""


def _sizes() -> dict[str, int]:
    return {"p": len(NAMES), "r": len(rover.ROVER_NAMES), "x": len(rover.STATES),
            "u": len(rover.INPUTS), "g": len(ground.NAMES)}


def _ports(names: Sequence[str]) -> list[Port]:
    sizes = _sizes()
    return [Port(n, sizes.get(n, 1), description=INPUT_DOC[n], unit=INPUT_UNIT.get(n, ""))
            for n in names]


def _derivative(f: ca.Function, names: Sequence[str]) -> ca.Function:
    """The forward directional derivative of ``f`` (one output) with respect to every input
    but the parameter vectors: inputs (the inputs, then der_<input> for each of those), output
    der_<output>."""
    xs = [ca.SX.sym(n, f.nnz_in(k)) for k, n in enumerate(names)]
    seeds = [ca.SX.sym("der_" + n, f.nnz_in(k)) for k, n in enumerate(names)
             if n not in PARAMETER_INPUTS]
    moving = [x for n, x in zip(names, xs, strict=True) if n not in PARAMETER_INPUTS]
    y = f(*xs)
    dy = ca.jtimes(y, ca.vertcat(*moving), ca.vertcat(*seeds))
    return ca.Function(f.name() + "_der", [*xs, *seeds], [dy], {"cse": True})


@dataclass(frozen=True)
class Exported:
    """One generated function: its Modelica name, the CasADi Function it reproduces, its
    ports and its derivative's CasADi Function (None for an integer-valued one)."""

    name: str
    function: ca.Function
    inputs: tuple[str, ...]
    outputs: tuple[Port, ...]
    description: str
    derivative: ca.Function | None


@lru_cache(maxsize=1)
def exported() -> tuple[Exported, ...]:
    """Every function the library's Functions package reproduces from CasADi, in order."""
    from wheelterrain.fmu import functions as fmu_functions

    out: list[Exported] = []
    for memory, stem, what in ((True, "contact", "the contact with the soil's memory, grouser "
                                "ripple on (the WheelTerrain FMU's)"),
                               (False, "quasiStatic", "the quasi-static contact of the steady "
                                "state (ripple-free, no sinkage rate, no memory)")):
        names = contact.EXPORT_INPUTS[memory]
        case, forms = contact.export_kernels(memory)
        out.append(Exported(f"{stem}Case", case, names, (Port("case", description=(
            "the form that applies: 0 arc, 1 arc with shear reversal, 2 patch")),),
            f"Which contact form applies, {what}", None))
        rows = contact.CONTACT_OUTPUTS + (contact.MEMORY_OUTPUTS if memory else ())
        for form, kernel in zip(contact.FORMS, forms, strict=True):
            out.append(Exported(
                stem + FORM_NAMES[form], kernel, names,
                (Port("y", len(rows), description="the outputs, Index order"),),
                f"{what[0].upper()}{what[1:]} in the {form.replace('_', ' ')} form",
                _derivative(kernel, names)))
    wheel_speed, carriage_speed, p = ca.SX.sym("wheel_speed"), ca.SX.sym(
        "carriage_speed"), ca.SX.sym("p", len(NAMES))
    # the paper's slip is left out: it is NaN with the axle at rest, and Modelica has no NaN
    sigma, _ = fmu_functions.slips(wheel_speed, carriage_speed,
                                      fmu_functions.slip_radius(p))
    f = ca.Function("slipFromSpeeds", [wheel_speed, carriage_speed, p], [sigma], {"cse": True})
    names = ("wheel_speed", "carriage_speed", "p")
    slip = Port("slip", description="the model's slip", unit="1")
    out.append(Exported("slipFromSpeeds", f, names, (slip,),
                        "The model's slip from the wheel's and the axle's speeds: "
                        "(omega*R_ref - V)/max(|omega*R_ref|, |V|, "
                        f"{fmu_functions.SLIP_SPEED_FLOOR:g} m/s), the traction slip driving, "
                        "the skid braking, -1 a locked wheel; regularised through standstill "
                        "(0 at rest)",
                        _derivative(f, names)))
    f = ca.Function("rollingSign", [wheel_speed, carriage_speed, p], [ca.if_else(
        fmu_functions.backward(wheel_speed, carriage_speed, fmu_functions.slip_radius(p)), -1,
        1)], {"cse": True})
    sign = Port("sign", description="the direction of rolling", unit="1")
    out.append(Exported("rollingSign", f, names, (sign,),
                        "-1 for a wheel rolling backward (omega*R_ref + V < 0: both speeds "
                        "<= 0, or near rest the faster of the two backward): the mirror image "
                        "of one rolling forward; else 1",
                        _derivative(f, names)))
    f = ca.Function("turningWeight", [wheel_speed, carriage_speed, p], [
        fmu_functions.turning_weight(wheel_speed, carriage_speed, fmu_functions.slip_radius(p))],
        {"cse": True})
    weight = Port("weight", description="the share of rolling forward", unit="1")
    out.append(Exported("turningWeight", f, names, (weight,),
                        "The share of rolling forward in the contact: 1 forward, 0 backward, "
                        "between them within the slip's speed floor of omega*R_ref + V = 0, "
                        "where the contact is the blend of the two (the FMU's)",
                        _derivative(f, names)))
    s = ca.SX.sym("slip_paper")
    f = ca.Function("slipFromPaper", [s], [ca.if_else(s < 0, s, s / (1 + s))], {"cse": True})
    out.append(Exported("slipFromPaper", f, ("slip_paper",),
                        (Port("slip", description="the model's slip: s/(1 + s) driving, s "
                              "braking", unit="1"),),
                        "The model's slip from the paper's slip", _derivative(f, ("slip_paper",))))
    side = ("lateral force, aligning moment, the force's two parts, turning moment and "
            "overturning moment")
    for name, f, names, what in (
            ("lateral", contact.lateral_export(), contact.LATERAL_INPUTS,
             "The quasi-static lateral contact of a wheel at a slip angle and a turn slip "
             f"(Ishigami et al. 2007's side force, the brush model of turn slip): {side}, 0 at "
             "slip angle and turn slip 0"),
            ("lateralMemory", contact.lateral_memory_export(), contact.LATERAL_MEMORY_INPUTS,
             f"The lateral contact of a wheel at a slip angle and a turn slip on the soil with "
             f"memory: {side} "
             "of lateral at the yield sinkage max(plastic_sinkage, sinkage), scaled by the "
             "longitudinal forces' elastic unloading (mean_pressure: contact's output at the "
             "same state)")):
        out.append(Exported(name, f, names, (Port("y", len(contact.LATERAL_OUTPUTS),
                                                  description="the outputs, Index.Lateral "
                                                  "order"),), what, _derivative(f, names)))
    out += _rover_functions()
    return tuple(out)


def _rover_functions() -> list[Exported]:
    """The RoverChassis FMU's chassis (its model-exchange rates and each wheel's sinkage, sinkage
    rate and axle speed) and the Terrain FMU's soil map."""
    sizes = _sizes()
    x, u, r = (ca.SX.sym(n, sizes[n]) for n in ("x", "u", "r"))
    xs = tuple(x[k] for k in range(sizes["x"]))
    named = rover.named(r)
    inputs = {n: u[k] for k, n in enumerate(rover.INPUTS)}
    rates = ca.Function("roverRates", [x, u, r], [ca.vertcat(*rover.rates(xs, inputs, named))],
                        {"cse": True})
    kinematics = []
    for wheel in rover.WHEELS:
        kinematics += [*rover.wheel_kinematics(xs, named, wheel),
                       rover.axle_speed(xs, named, wheel)]
    wheels = ca.Function("roverWheels", [x, r], [ca.vertcat(*kinematics)], {"cse": True})
    position, g = ca.SX.sym("position"), ca.SX.sym("g", sizes["g"])
    soil = ground.soil_at(position, {n: g[k] for k, n in enumerate(ground.NAMES)})
    soil_at = ca.Function("soilAt", [position, g], [ca.vertcat(*soil)], {"cse": True})
    return [
        Exported("roverRates", rates, ("x", "u", "r"),
                 (Port("dx", sizes["x"], description="d(x)/dt"),),
                 "The chassis' state derivative (the RoverChassis FMU's model exchange)",
                 _derivative(rates, ("x", "u", "r"))),
        Exported("roverWheels", wheels, ("x", "r"),
                 (Port("y", 3 * len(rover.WHEELS), description=(
                     "each wheel's sinkage, sinkage rate and axle speed, Index.RoverWheel "
                     "order")),),
                 "Each wheel's sinkage, sinkage rate and axle speed (the chassis' speed less "
                 "the pitch rate's share) from the chassis' state",
                 _derivative(wheels, ("x", "r"))),
        Exported("soilAt", soil_at, ("position", "g"),
                 (Port("soil", len(ground.SOIL_NAMES), description=(
                     "the soil.* parameters there, table order")),),
                 "The terrain map's soil at a position (the Terrain FMU's)",
                 _derivative(soil_at, ("position", "g"))),
    ]


@dataclass(frozen=True)
class Entry:
    """One function of the Functions package as Modelica sees it: its name, the CasADi
    Function it reproduces, its ports, its description and its derivative annotation ('' for
    none). The generated functions and Functions.External both list these."""

    name: str
    function: ca.Function
    inputs: tuple[Port, ...]
    outputs: tuple[Port, ...]
    description: str
    annotation: str


@lru_cache(maxsize=1)
def entries() -> tuple[Entry, ...]:
    """Every exported function and, after each, its derivative function."""
    out = []
    for e in exported():
        inputs = tuple(_ports(e.inputs))
        annotation = ""
        if e.derivative is not None:
            zero = ", ".join(f"zeroDerivative={n}" for n in e.inputs if n in PARAMETER_INPUTS)
            annotation = f"derivative{f'({zero})' if zero else ''}={e.name}Der"
        out.append(Entry(e.name, e.function, inputs, e.outputs, e.description, annotation))
        if e.derivative is not None:
            seeds = tuple(p.rate() for p in inputs if p.name not in PARAMETER_INPUTS)
            outs = tuple(p.rate() for p in e.outputs)
            out.append(Entry(f"{e.name}Der", e.derivative, inputs + seeds, outs,
                             f"Derivative of {e.name} (CasADi's forward mode)", ""))
    return tuple(out)


def _functions(lib: Library) -> None:
    where = f"{LIBRARY}/Functions"
    order: list[str] = []
    internal: list[str] = []
    for e in entries():
        stem = e.name.removesuffix("Der")
        pieces = f"{LIBRARY}.Functions.Internal.{stem[0].upper()}{stem[1:]}"
        pieces += "Der" if e.name != stem else ""
        text, parts = translate.functions(e.function, e.name, e.inputs, e.outputs,
                                          e.description, e.annotation, pieces=pieces)
        _class_file(lib, where, e.name, text)
        order.append(e.name)
        _internal(lib, internal, pieces, parts, e.name)
    for stem, memory in (("contact", True), ("quasiStatic", False)):
        order += _dispatch(lib, where, stem, memory)
    _index(lib, where)
    order.append("Index")
    _class_file(lib, where, "Ground", _template("Ground"))
    order.append("Ground")
    order += _external(lib, where)
    order += _interfaces(lib, where)
    lib.package(f"{LIBRARY}/Functions", "Internal", "Pieces of the long generated functions "
                "(not to be called: each runs a stretch of its function's instructions)",
                internal)
    order.append("Internal")
    lib.package(LIBRARY, "Functions", "The model's functions, generated instruction by "
                "instruction from its CasADi Functions (their arguments Modelica.Units.SI types)",
                order)


def _internal(lib: Library, internal: list[str], pieces: str, parts: list[str],
              owner: str) -> None:
    if not parts:
        return
    name = pieces.rsplit(".", 1)[1]
    text = f'package {name} "The pieces of {owner}, in order"\n'
    text += "".join(parts)
    text += f"end {name};\n"
    _class_file(lib, f"{LIBRARY}/Functions/Internal", name, text)
    internal.append(name)


def _external(lib: Library, where: str) -> list[str]:
    """Functions.External: every function of Functions with the same signature and derivative
    annotation, calling the CasADi-generated C of the same Function (:mod:`.external`), and
    the two dispatchers over them."""
    folder = f"{where}/External"
    order = []
    for e in entries():
        text = translate.external(e.name, e.inputs, e.outputs, e.description + " (C)",
                                  external.call(e.name, e.inputs, e.outputs), e.annotation)
        _class_file(lib, folder, e.name, text)
        order.append(e.name)
    for stem, memory in (("contact", True), ("quasiStatic", False)):
        order += _dispatch(lib, folder, stem, memory)
    lib.package(where, "External", "The same functions calling the C that CasADi generates "
                "from the same Functions (Resources/C-Sources, Resources/Library): for tools "
                "that compile long functions slowly", order)
    return ["External"]


def _dispatch_ports(memory: bool, der: bool) -> tuple[list[Port], Port]:
    """The inputs and the output of ``contact`` (``memory``) or ``quasiStatic``, or of their
    derivatives (``der``)."""
    names = contact.EXPORT_INPUTS[memory]
    rows = len(contact.CONTACT_OUTPUTS) + (len(contact.MEMORY_OUTPUTS) if memory else 0)
    inputs = _ports(names)
    if der:
        inputs += [p.rate() for p in _ports(names) if p.name != "p"]
    return inputs, Port("der_y" if der else "y", rows, description="the outputs, Index order")


def _interfaces(lib: Library, where: str) -> list[str]:
    """Functions.Interfaces: the signatures of ``contact`` and ``quasiStatic``, which the
    components' replaceable contact functions are constrained by (the generated functions or
    Functions.External's)."""
    order = []
    for stem, memory in (("contact", True), ("quasiStatic", False)):
        name = stem[0].upper() + stem[1:]
        inputs, out = _dispatch_ports(memory, False)
        lines = [f'partial function {name} "The signature of Functions.{stem} and '
                 f'Functions.External.{stem}"']
        lines += [p.declaration("input") for p in inputs]
        lines += [out.declaration("output"), f"end {name};"]
        _class_file(lib, f"{where}/Interfaces", name, "\n".join(lines) + "\n")
        order.append(name)
    n_soil = len(ground.SOIL_NAMES)
    for name, what, lines in (
            ("Height", "Terrain.height: the terrain's height at a horizontal position",
             ['  input Modelica.Units.SI.Length x "horizontal position";',
              '  output Modelica.Units.SI.Length h "the terrain\'s height there";']),
            ("Slope", "Terrain.slopeAt: the terrain's inclination at a horizontal position",
             ['  input Modelica.Units.SI.Length x "horizontal position";',
              '  output Modelica.Units.SI.Angle angle "the inclination there, rising toward +x";']),
            ("Soil", "Terrain.soil: the soil at a horizontal position",
             ['  input Modelica.Units.SI.Length position "horizontal position";',
              f'  output Real soil[{n_soil}] "the soil.* parameters there, table order '
              '(Index.Soil)";'])):
        text = "\n".join([f'partial function {name} "The signature of {what}"', *lines,
                          f"end {name};"]) + "\n"
        _class_file(lib, f"{where}/Interfaces", name, text)
        order.append(name)
    lib.package(where, "Interfaces", "The signatures a component's contact function and a "
                "terrain's functions must have", order)
    return ["Interfaces"]


def _dispatch(lib: Library, where: str, stem: str, memory: bool) -> list[str]:
    """``stem`` and ``stemDer``: the form ``stemCase`` picks, as the model's switch does (only
    that form is evaluated)."""
    names = contact.EXPORT_INPUTS[memory]
    args = ", ".join(names)
    moving = [n for n in names if n != "p"]
    written = []
    for der in (False, True):
        name = stem + ("Der" if der else "")
        inputs, out = _dispatch_ports(memory, der)
        call = args + (", " + ", ".join("der_" + n for n in moving) if der else "")
        suffix = "Der" if der else ""
        what = ("Derivative of " + stem) if der else (
            "The contact with the soil's memory (the WheelTerrain FMU's)" if memory
            else "The quasi-static contact (the steady state's)")
        lines = [f'function {name} "{what}: the form {stem}Case picks"']
        lines += [p.declaration("input") for p in inputs]
        lines.append(out.declaration("output"))
        lines += ["protected", f"  Integer form = integer({stem}Case({args}));", "algorithm"]
        branches = [(contact.PATCH, "Patch"), (contact.ARC_REVERSAL, "ArcReversal")]
        keyword = "if"
        for number, form in branches:
            lines.append(f"  {keyword} form == {number} then")
            lines.append(f"    {out.name} := {stem}{form}{suffix}({call});")
            keyword = "elseif"
        lines += ["  else", f"    {out.name} := {stem}Arc{suffix}({call});", "  end if;"]
        ann = "Inline=false" + ("" if der else f", derivative(zeroDerivative=p)={stem}Der")
        lines += [f"  annotation({ann});", f"end {name};"]
        _class_file(lib, where, name, "\n".join(lines) + "\n")
        written.append(name)
    return written


def _index(lib: Library, where: str) -> None:
    lines = ['package Index "Where each output sits in the output vectors of contact, '
             'quasiStatic and their forms (the CasADi outputs\' names)"']
    for k, name in enumerate(contact.CONTACT_OUTPUTS + contact.MEMORY_OUTPUTS):
        scope = "contact only" if name in contact.MEMORY_OUTPUTS else "both"
        lines.append(f'  constant Integer {name} = {k + 1} "({scope})";')
    for package, members, what in (("RoverState", rover.STATES, "roverRates' x and dx"),
                                   ("RoverInput", rover.INPUTS, "roverRates' u"),
                                   ("RoverWheel", [f"{w}.{q}" for w in rover.WHEELS
                                                   for q in ("sinkage", "sinkage_rate",
                                                             "axle_speed")],
                                    "roverWheels' y")):
        lines.append(f'  package {package} "Positions in {what}"')
        for k, name in enumerate(members):
            lines.append(f"    constant Integer {name.replace('.', '_')} = {k + 1};")
        lines.append(f"  end {package};")
    lines.append('  package Lateral "Positions in lateral\'s and lateralMemory\'s y"')
    for k, name in enumerate(contact.LATERAL_OUTPUTS):
        lines.append(f"    constant Integer {name} = {k + 1};")
    lines.append("  end Lateral;")
    lines.append('  package Soil "Positions in soilAt\'s soil"')
    for k, name in enumerate(ground.SOIL_NAMES):
        lines.append(f"    constant Integer {name.split('.', 1)[1]} = {k + 1};")
    lines.append("  end Soil;")
    lines.append("end Index;")
    _class_file(lib, where, "Index", "\n".join(lines) + "\n")


# ---- Data and Records ---------------------------------------------------------------------

def _preset_vectors() -> dict[str, np.ndarray]:
    return {name: presets.load(name).vector() for name in presets.available()}


def _data(lib: Library) -> None:
    lines = ['package Data "The presets as parameter vectors in table order (no Modelica Standard '
             'Library needed)"']
    for name, values in _preset_vectors().items():
        const = preset_constant(name)
        lines.append(_wrap_call(f"  constant Real {const}[{len(NAMES)}] = {_vector(values)}"))
        lines.append(f'    "The preset {name} (Records.Parameters names the values)";')
    for const, values, doc in (
            ("rover", [rover.defaults()[n] for n in rover.ROVER_NAMES],
             "The rover's parameters at the table's defaults (the rover.* rows, table order)"),
            ("roverStart", reference.rover_start(),
             "The rover at the start of Examples.FMUTwin.Rover: level, wheels at their "
             "reference speed, the chassis 1 mm in the soil"),
            ("terrain", [ground.defaults()[n] for n in ground.NAMES],
             "The terrain map's parameters at the table's defaults (one soil, no patch)")):
        lines.append(_wrap_call(f"  constant Real {const}[{len(values)}] = {_vector(values)}"))
        lines.append(f'    "{doc}";')
    lines.append("end Data;")
    _class_file(lib, LIBRARY, "Data", "\n".join(lines) + "\n")


def _camel(text: str, upper: bool) -> str:
    """'wong-hump' -> 'wongHump' (``upper``: 'WongHump'); 'toward the wheel' -> 'towardTheWheel'."""
    words = [w for w in re.split(r"[^0-9A-Za-z]+", text) if w]
    name = words[0].lower() + "".join(w[:1].upper() + w[1:] for w in words[1:])
    return name[:1].upper() + name[1:] if upper else name


def enumeration(row: Parameter) -> str | None:
    """The Types enumeration of an option row (choices given), 'Types.ContactForm' for
    model.contact_form; None for any other row."""
    if row.kind != "enum" or not row.choices:
        return None
    return f"{LIBRARY}.Types.{_camel(row.name.partition('.')[2], upper=True)}"


def _literals(row: Parameter) -> list[tuple[int, str, str]]:
    """(code, literal, description) of an option row's choices, in code order (0, 1, ...)."""
    codes = sorted(int(k) for k in row.choices)
    if codes != list(range(len(codes))):
        raise ValueError(f"{row.name}: an enumeration needs the codes 0, 1, ... ({codes})")
    return [(k, _camel(row.choices[k], upper=False), row.choices[k]) for k in codes]


def _enumerations() -> str:
    """The Types package's enumerations of the table's options."""
    lines = []
    for row in TABLE:
        kind = enumeration(row)
        if kind is None:
            continue
        items = ",\n".join(f'      {lit} "{_doc(text)}"' for _, lit, text in _literals(row))
        lines.append(f"  type {kind.rsplit('.', 1)[1]} = enumeration(\n{items})\n"
                     f'    "{_doc(row.description)} ({row.name}; the table\'s codes '
                     f'{", ".join(f"{k} {t}" for k, _, t in _literals(row))})";')
    return "\n".join(lines)


def _code(row: Parameter, expression: str) -> str:
    """The table's code of an option record field ``expression`` (rumoca 0.10 cannot convert
    an enumeration with Integer(), so a comparison per literal)."""
    kind = enumeration(row)
    if kind is None:
        return expression
    literals = _literals(row)
    text = " elseif ".join(f"{expression} == {kind}.{lit} then {k}"
                           for k, lit, _ in literals[:-1])
    return f"(if {text} else {literals[-1][0]})"


def _type(row: Parameter) -> str:
    if enumeration(row):
        return enumeration(row)
    if row.kind != "real":
        return "Integer"
    if row.quantity:
        return f"Modelica.Units.SI.{row.quantity}"
    return "Real"


def _modifiers(row: Parameter) -> str:
    mods = []
    if row.kind == "real" and not row.quantity:
        mods.append(f'unit="{row.unit}"')
    for key, value in (("min", row.min), ("max", row.max)):
        if math.isfinite(value) and not enumeration(row):
            mods.append(f"{key}={_number(row, value)}")
    return f"({', '.join(mods)})" if mods else ""


def _number(row: Parameter, value: float) -> str:
    if enumeration(row):
        return f"{enumeration(row)}.{_literals(row)[int(value)][1]}"
    return str(int(value)) if row.kind != "real" else translate.literal(value)


def _row_doc(row: Parameter) -> str:
    text = row.description
    if row.choices:
        text += " (" + ", ".join(f"{k} {v}" for k, v in sorted(row.choices.items())) + ")"
    return _doc(f"{text} [{row.unit}] Source: {row.source}")


def _records(lib: Library) -> None:
    where = f"{LIBRARY}/Records"
    order = []
    groups: dict[str, list[Parameter]] = {}
    for row in TABLE:
        groups.setdefault(row.name.partition(".")[0], []).append(row)
    for group, rows in groups.items():
        record = GROUPS[group].capitalize()
        lines = [f'record {record} "The table\'s {group}.* parameters"']
        for row in rows:
            field_ = modelica_name(row.name).partition(".")[2]
            lines.append(f"  parameter {_type(row)} {field_}{_modifiers(row)} = "
                         f'{_number(row, row.default)}\n    "{_row_doc(row)}";')
        lines.append(f"end {record};")
        _class_file(lib, where, record, "\n".join(lines) + "\n")
        order.append(record)
    lines = ['record Parameters "Every parameter of the wheel-soil model, as the table names '
             'them (UsersGuide.NameMap)"']
    for group in groups:
        lines.append(f'  {GROUPS[group].capitalize()} {GROUPS[group]} "the {group}.* rows";')
    lines.append("end Parameters;")
    _class_file(lib, where, "Parameters", "\n".join(lines) + "\n")
    order.insert(0, "Parameters")

    lines = ['function parameterVector "The parameters in table order, as the functions take '
             'them"', "  input Parameters parameters;",
             f"  output Real p[{len(NAMES)}];", "algorithm"]
    lines.append("  p := {" + ", ".join(_code(TABLE[k], f"parameters.{modelica_name(n)}")
                                      for k, n in enumerate(NAMES)) + "};")
    lines.append("end parameterVector;")
    text = "\n".join(_wrap_call(line) for line in lines) + "\n"
    _class_file(lib, where, "parameterVector", text)
    order.append("parameterVector")

    lines = ['package Presets "Every preset as a record: Parameters with the preset\'s values"']
    for name, values in _preset_vectors().items():
        by_group: dict[str, list[str]] = {}
        for table_name, value in zip(NAMES, values, strict=True):
            group, _, field_ = modelica_name(table_name).partition(".")
            row = TABLE[NAMES.index(table_name)]
            by_group.setdefault(group, []).append(f"{field_}={_number(row, value)}")
        mods = ",\n    ".join(f"{g}({', '.join(v)})" for g, v in by_group.items())
        description = _doc(presets.read(name).get("description", name))
        lines.append(f"  record {preset_record(name)} = Parameters(\n    {mods})\n"
                     f'    "{name}: {description}";')
    lines.append("end Presets;")
    _class_file(lib, where, "Presets", "\n".join(lines) + "\n")
    order.append("Presets")
    lib.package(LIBRARY, "Records", "The parameter table as records (Modelica.Units.SI types, "
                "ranges, sources) and the presets", order)


def _wrap_call(line: str) -> str:
    """A long line broken after commas, continued with four spaces."""
    return "\n".join(translate.wrap(line))


# ---- Components and Examples --------------------------------------------------------------

def _template(name: str, **values) -> str:
    """The Modelica text of templates/<name>.mo with ${...} filled in."""
    text = resources.files("wheelterrain.modelica").joinpath("templates", f"{name}.mo")
    return string.Template(text.read_text(encoding="utf-8")).substitute(
        {"version": __version__, **values})


def _speed_floor() -> str:
    """The FMU's SPEED_FLOOR [m/s] as a literal: below it a wheel and its axle are at rest (the
    turn slip's denominator in the wheels)."""
    from wheelterrain.fmu import functions as fmu_functions

    return translate.literal(fmu_functions.SPEED_FLOOR)


def _slip_speed_floor() -> str:
    """The FMU's SLIP_SPEED_FLOOR [m/s], for the wheels' messages: a wheel turning against its
    axle's motion beyond it is outside the slip's range."""
    from wheelterrain.fmu import functions as fmu_functions

    return f"{fmu_functions.SLIP_SPEED_FLOOR:g}"


def _soil_rows() -> tuple[list[int], list[int], list[int]]:
    """The soil rows' 0-based positions in the table, and the soil's and the patch's in the
    terrain map's table: each side by side, as MapWheel, SoilWheel and Terrain slice them."""
    soil = [NAMES.index(n) for n in ground.SOIL_NAMES]
    in_map = [ground.NAMES.index(n) for n in ground.SOIL_NAMES]
    patch = [ground.NAMES.index(n) for n in ground.PATCH_NAMES]
    for rows in (soil, in_map, patch):
        if rows != list(range(rows[0], rows[0] + len(rows))):
            raise ValueError("the soil rows must lie side by side in the table, and the map's "
                             "soil and patch rows side by side in the map's")
    return soil, in_map, patch


def _components(lib: Library) -> None:
    where = f"{LIBRARY}/Components"
    rows = len(contact.CONTACT_OUTPUTS)
    lateral_rows = len(contact.LATERAL_OUTPUTS)
    _class_file(lib, where, "QuasiStaticWheel", _connectors(_template(
        "QuasiStaticWheel", N=len(NAMES), QUASI_ROWS=rows, LATERAL_ROWS=lateral_rows,
        TURN_SLIP_LIMIT=f"{TURN_SLIP_LIMIT:g}")))
    _class_file(lib, where, "Contact", _template(
        "Contact", N=len(NAMES), CONTACT_ROWS=rows + len(contact.MEMORY_OUTPUTS)))
    phase = NAMES.index("ripple.phase") + 1
    _class_file(lib, where, "PartialWheel", _connectors(_template(
        "PartialWheel", N=len(NAMES), CONTACT_ROWS=rows + len(contact.MEMORY_OUTPUTS),
        PHASE_BEFORE=phase - 1, PHASE=phase, PHASE_AFTER=phase + 1,
        LATERAL_ROWS=lateral_rows, TURN_SLIP_LIMIT=f"{TURN_SLIP_LIMIT:g}",
        SPEED_FLOOR=_speed_floor(), SLIP_SPEED_FLOOR=_slip_speed_floor())))
    _class_file(lib, where, "Wheel", _template("Wheel", N=len(NAMES)))
    soil, in_map, patch = _soil_rows()
    _class_file(lib, where, "MapWheel", _connectors(_template(
        "MapWheel", N=len(NAMES), G=len(ground.NAMES), SOIL_FIRST=soil[0],
        SOIL_AFTER=soil[-1] + 2, START=ground.NAMES.index("patch.start") + 1,
        END=ground.NAMES.index("patch.end") + 1, PATCH_FIRST=patch[0] + 1,
        PATCH_LAST=patch[-1] + 1, MAP_SOIL_FIRST=in_map[0] + 1, MAP_SOIL_LAST=in_map[-1] + 1)))
    _class_file(lib, where, "SoilWheel", _connectors(_template(
        "SoilWheel", N=len(NAMES), S=len(soil), SOIL_FIRST=soil[0], SOIL_AFTER=soil[-1] + 2)))
    _class_file(lib, where, "RoverChassis", _connectors(_rover_chassis()))
    lib.package(LIBRARY, "Components", "The wheel on the soil as blocks (signals in, signals "
                "out) and the contact on MSL's 1-D flanges",
                ["QuasiStaticWheel", "Contact", "PartialWheel", "Wheel", "MapWheel",
                 "SoilWheel", "RoverChassis"])


def _planar(lib: Library) -> None:
    """The component layer on PlanarMechanics: Types, the inner Terrain, Wheels.PlanarWheel."""
    _class_file(lib, LIBRARY, "Types", _template("Types", ENUMERATIONS=_enumerations()))
    soil, in_map, _ = _soil_rows()
    if in_map[0] != 0:
        raise ValueError("Terrain needs the map's soil rows first in the map's table")
    _class_file(lib, LIBRARY, "Terrain", _template(
        "Terrain", G=len(ground.NAMES), SOIL_FIRST=soil[0] + 1, SOIL_LAST=soil[-1] + 1,
        MAP_AFTER_SOIL=len(in_map) + 1))
    _class_file(lib, f"{LIBRARY}/Wheels", "PlanarWheel", _template(
        "PlanarWheel", N=len(NAMES), SLIP_SPEED_FLOOR=_slip_speed_floor()))
    _class_file(lib, f"{LIBRARY}/Wheels", "HorizontalWheel", _template(
        "HorizontalWheel", N=len(NAMES), SLIP_ANGLE_LIMIT=translate.literal(SLIP_ANGLE_LIMIT),
        SLIP_ANGLE_DEG=f"{math.degrees(SLIP_ANGLE_LIMIT):g}",
        TURN_SLIP_LIMIT=f"{TURN_SLIP_LIMIT:g}", SPEED_FLOOR=_speed_floor(),
        SLIP_SPEED_FLOOR=_slip_speed_floor()))
    lib.package(LIBRARY, "Wheels", "Wheels to connect into a vehicle: PlanarMechanics frames, "
                "Rotational flanges; in the vertical plane of travel on an inner Terrain "
                "(PlanarWheel) or seen from above with the load an input (HorizontalWheel)",
                ["PlanarWheel", "HorizontalWheel"],
                'Icon(graphics={Ellipse(extent={{-80,80},{80,-80}}, lineColor={64,64,64}, '
                'fillColor={160,160,160}, fillPattern=FillPattern.Solid)})')


def _declaration_end(text: str, start: int) -> int:
    """The index of the ';' ending the declaration that begins at ``start`` (strings
    skipped)."""
    k = start
    while text[k] != ";":
        k = _string_end(text, k) if text[k] == '"' else k + 1
    return k


def _connectors(text: str) -> str:
    """A signal block's ``input Real`` and ``output Real`` declarations as MSL's RealInput and
    RealOutput connectors, placed on the icon's left (inputs) and right (outputs) edges (the
    templates keep plain declarations: one place decides the connectors)."""
    found = list(re.finditer(r"^  (input|output) Real ", text, re.M))
    counts = {"input": 0, "output": 0}
    totals = {side: sum(m.group(1) == side for m in found) for side in counts}
    out, last = [], 0
    for m in found:
        side = m.group(1)
        counts[side] += 1
        y = round(80 - 160 * (counts[side] - 0.5) / totals[side])
        x = (-140, -100) if side == "input" else (100, 120)
        half = 20 if side == "input" else 10
        end = _declaration_end(text, m.end())
        kind = "RealInput" if side == "input" else "RealOutput"
        out.append(text[last:m.start()] + f"  Modelica.Blocks.Interfaces.{kind} "
                   + text[m.end():end]
                   + f"\n    annotation(Placement(transformation(extent={{{{{x[0]},{y - half}}},"
                     f"{{{x[1]},{y + half}}}}})))")
        last = end
    return "".join(out) + text[last:]


def _state(name: str) -> str:
    return f"x[{rover.STATES.index(name) + 1}]"


def _rover_chassis() -> str:
    """The RoverChassis FMU's chassis as a block: its state, its rates, each wheel's
    kinematics; inputs and outputs per wheel in rover.WHEELS order."""
    sizes, n = _sizes(), len(rover.WHEELS)
    wheels = ", ".join(rover.WHEELS)
    per_wheel = {"normal_force": "N", "drawbar_pull": "N", "torque": "N.m",
                 "wheel_speed_command": "rad/s", "motor_torque_command": "N.m"}
    u = []
    for name in rover.INPUTS:
        wheel, _, quantity = name.rpartition(".")
        u.append(f"{quantity}[{rover.WHEELS.index(wheel) + 1}]" if wheel else quantity)
    kinematics = []
    for k in range(n):
        kinematics += [f"sinkage[{k + 1}]", f"sinkage_rate[{k + 1}]",
                       f"carriage_speed[{k + 1}]"]
    lines = [
        'block RoverChassis "The RoverChassis FMU\'s chassis (its model exchange): a rigid body '
        'in the plane of travel on four driven wheels"',
        f"  parameter Real r[{sizes['r']}] = {LIBRARY}.Data.rover "
        '"the rover\'s parameters in table order";',
        f"  parameter Real x_start[{sizes['x']}] = {LIBRARY}.Data.roverStart "
        '"the state at the start (Index.RoverState order)";',
        '  input Real slope(unit="rad") "the terrain\'s slope (the rover.* ramp adds to it)";',
        '  input Real towing_force(unit="N") "a force holding the rover back";']
    for name, unit in per_wheel.items():
        lines.append(f'  input Real {name}[{n}](each unit="{unit}") "per wheel: {wheels}";')
    lines += [
        f'  output Real sinkage[{n}](each unit="m") "per wheel";',
        f'  output Real sinkage_rate[{n}](each unit="m/s") "per wheel";',
        f'  output Real carriage_speed[{n}](each unit="m/s") "per wheel: its axle\'s speed '
        'along the terrain";',
        f'  output Real wheel_speed[{n}](each unit="rad/s") "per wheel";',
        '  output Real speed(unit="m/s") "the chassis\' speed along the terrain";',
        '  output Real position(unit="m") "the chassis\' reference point along the path";',
        '  output Real pitch(unit="rad") "nose down positive";',
        f"  Real x[{sizes['x']}](start=x_start, each fixed=true) "
        '"the state, Index.RoverState order";',
        "protected",
        f"  Real u[{sizes['u']}];",
        "equation"]
    lines += translate.wrap(f"  u = {{{', '.join(u)}}};")
    lines.append(f"  der(x) = {LIBRARY}.Functions.roverRates(x, u, r);")
    lines += translate.wrap(f"  {{{', '.join(kinematics)}}} = "
                         f"{LIBRARY}.Functions.roverWheels(x, r);")
    speeds = ", ".join(_state(f"{w}.wheel_speed") for w in rover.WHEELS)
    lines += [f"  wheel_speed = {{{speeds}}};", f"  speed = {_state('speed')};",
              f"  position = {_state('position')};", f"  pitch = {_state('pitch')};",
              "end RoverChassis;"]
    return "\n".join(lines) + "\n"


def _pins(text: str) -> dict[str, tuple[float, float]]:
    """A class file's connectors and where their icons sit in its icon (their placements'
    centres): the ends of the connection lines an example draws to them."""
    found = re.finditer(r"^\s*\S*(?:RealInput|RealOutput|Frame_a|Frame_b|Flange_a|Flange_b|"
                        r"Support)\s+(\w+)[^;]*?annotation\(Placement\(transformation\("
                        r"extent=\{\{(-?[\d.]+),(-?[\d.]+)\},\{(-?[\d.]+),(-?[\d.]+)\}\}",
                        text, re.M)
    return {m.group(1): ((float(m.group(2)) + float(m.group(4))) / 2,
                         (float(m.group(3)) + float(m.group(5))) / 2) for m in found}


MSL_PINS = {"Constant": {"y": (110.0, 0.0)},
            "Add": {"u1": (-120.0, 60.0), "u2": (-120.0, -60.0), "y": (110.0, 0.0)},
            "FixedTranslation": {"frame_a": (-100.0, 0.0), "frame_b": (100.0, 0.0)}}
"""Where MSL's and PlanarMechanics' connectors sit in the icons of the classes the generated
examples place (Blocks.Sources.Constant, Blocks.Math.Add, PlanarMechanics.Parts.
FixedTranslation)."""


def _line(ends: tuple[tuple[float, float], tuple[float, float]], signal: bool) -> str:
    """A connection's line between two connector positions in the diagram: straight where
    they are level, else across at half way."""
    (x1, y1), (x2, y2) = ends
    middle = round((x1 + x2) / 2, 1)
    points = [(x1, y1), (x2, y2)] if y1 == y2 else [(x1, y1), (middle, y1), (middle, y2),
                                                    (x2, y2)]
    text = ",".join(f"{{{x:g},{y:g}}}" for x, y in points)
    return f"Line(points={{{text}}}{', color={0,0,127}' if signal else ''})"


@dataclass
class Diagram:
    """An example's diagram: each component's centre and half size, and its connectors'
    places in its icon; :meth:`connect` writes a connection with its line."""

    places: dict[str, tuple[float, float, float]] = field(default_factory=dict)
    pins: dict[str, dict[str, tuple[float, float]]] = field(default_factory=dict)

    def place(self, name: str, x: float, y: float, pins: dict[str, tuple[float, float]],
              half: float = 20.0, turned: bool = False) -> str:
        """Place ``name`` centred at (x, y), ``half`` its half size (``turned``: rotated by
        180 deg, its connectors on the other side)."""
        self.places[name] = (x, y, half)
        self.pins[name] = {k: (-px, -py) for k, (px, py) in pins.items()} if turned else pins
        corners = f"{{{{{x - half:g},{y - half:g}}},{{{x + half:g},{y + half:g}}}}}"
        return (f"Placement(transformation(extent={corners}"
                f"{', rotation=180' if turned else ''}))")

    def _at(self, reference: str) -> tuple[float, float]:
        component, connector = reference.split(".")
        x, y, half = self.places[component]
        px, py = self.pins[component][re.sub(r"\[\d+\]$", "", connector)]
        return round(x + px * half / 100, 1), round(y + py * half / 100, 1)

    def connect(self, a: str, b: str, signal: bool = True) -> str:
        return f"  connect({a}, {b}) annotation({_line((self._at(a), self._at(b)), signal)});"


def _experiment(name: str, stop: float, interval: float) -> str:
    """The example ``name``'s experiment annotation: its reference result is at these output
    times, and a run at this tolerance reproduces it (reference.tolerance)."""
    return (f"experiment(StartTime=0, StopTime={stop}, Interval={interval}, "
            f"Tolerance={reference.tolerance(name):g})")


def _reference_doc(name: str) -> str:
    """Where the example ``name``'s reference result and compared signals are."""
    folder = f"Resources/Reference/{reference.location(name)}"
    return f"Reference: {folder}/{name}.csv, compared on {folder}/comparisonSignals.txt"


def _rover_example(pins: dict[str, dict[str, tuple[float, float]]], name: str = "Rover") -> str:
    """Examples.FMUTwin.Rover (four Wheels on one soil) or, for an example with a terrain map
    (reference.ROVER_MAPS), four MapWheels on the map at their axles' positions: the blocks
    and MSL's sources joined by connections only, drawn (``pins``: the library's blocks'
    connectors, :func:`_pins`)."""
    stop, interval = reference.rover_run(name)
    mapped = name in reference.ROVER_MAPS
    what = ("on level ground with a patch of looser soil (k_phi' and phi scaled down) on "
            f"[{ground.SOFT_PATCH_START:g}, {ground.SOFT_PATCH_START + ground.SOFT_PATCH_LENGTH:g})"
            " m, under the front axle, then the rear: four MapWheels" if mapped else
            "on level ground at the commanded rim speed: four Wheels")
    drive = rover.ROVER_NAMES.index("rover.drive") + 1
    d = Diagram()
    constant = MSL_PINS["Constant"]
    lines = [
        f'model {name} "The rover {what} on a RoverChassis, the default preset\'s soil"',
        f"  parameter Real p[{len(NAMES)}] = {LIBRARY}.Data.rashidPatch "
        '"every wheel\'s soil and model";',
        f"  parameter Real r[{_sizes()['r']}] = {LIBRARY}.Data.rover "
        '"the rover\'s parameters (its input profile: the rover.ramp_time ... rows)";']
    if mapped:
        g = reference.ROVER_MAPS[name]
        lines.append(f"  parameter Real g[{len(ground.NAMES)}] = "
                     f"{_vector([g[k] for k in ground.NAMES])} "
                     '"the terrain map (Data.terrain with the soft patch)";')
    lines += [f"  {LIBRARY}.Components.RoverChassis chassis(r=r) "
              f"annotation({d.place('chassis', 0, 40, pins['RoverChassis'])});",
              '  Modelica.Blocks.Sources.Constant level(k=0) "the terrain\'s own slope (the '
              f'chassis\' rover.* profile adds to it)" '
              f"annotation({d.place('level', -60, 90, constant, 10)});",
              '  Modelica.Blocks.Sources.Constant free(k=0) "no force holding the rover back" '
              f"annotation({d.place('free', -100, 90, constant, 10)});",
              '  Modelica.Blocks.Sources.Constant noCommand(k=0) "the wheels\' speed and torque '
              f"commands, read where rover.drive (r[{drive}]) is {rover.DRIVE_SPEED} or "
              f"{rover.DRIVE_TORQUE} only: here the chassis' own profile drives\" "
              f"annotation({d.place('noCommand', -100, 40, constant, 10)});",
              '  Modelica.Blocks.Sources.Constant straight(k=0) "the chassis drives straight: no '
              'slip angle, no yaw rate" '
              f"annotation({d.place('straight', -100, -10, constant, 10)});"]
    k, size = NAMES.index("ripple.phase") + 1, len(NAMES)
    for w in rover.WHEELS:  # each wheel's grouser phase added to its ripple.phase
        j = rover.ROVER_NAMES.index(f"rover.grouser_phase.{w}") + 1
        lines += translate.wrap(f"  parameter Real p_{w}[{size}] = cat(1, p[1:{k - 1}], "
                                f"{{p[{k}] + r[{j}]}}, p[{k + 1}:{size}]) "
                                f'"{w}: p with its grouser phase";')
    block = "MapWheel" if mapped else "Wheel"
    for n, w in enumerate(rover.WHEELS):  # front right of the diagram, left above
        where = d.place(w, 60 if w in rover.FRONT else -60, 20 - 60 * (n % 2), pins[block])
        lines.append(f"  {LIBRARY}.Components.{block} {w}(p=p_{w}{', g=g' if mapped else ''}) "
                     f"annotation({where});")
    half = f"r[{rover.ROVER_NAMES.index('rover.wheelbase') + 1}]/2"
    if mapped:  # rover.wheel_position: the axle ahead of or behind the reference point
        add = MSL_PINS["Add"]
        lines += [f'  Modelica.Blocks.Sources.Constant halfWheelbase(k={half}) "the axles\' '
                  f'distance from the chassis\' reference point" '
                  f"annotation({d.place('halfWheelbase', 100, 90, constant, 10)});",
                  '  Modelica.Blocks.Math.Add frontAxle "where the front axle is along the path" '
                  f"annotation({d.place('frontAxle', 60, 80, add, 10)});",
                  '  Modelica.Blocks.Math.Add rearAxle(k2=-1) "where the rear axle is along the '
                  f"path\" annotation({d.place('rearAxle', -60, -90, add, 10)});"]
    lines += ['  Real speed(unit="m/s") = chassis.speed;',
              '  Real position(unit="m") = chassis.position;',
              f'  Real heave(unit="m") = chassis.{_state("heave")};',
              '  Real pitch(unit="rad") = chassis.pitch;', "equation",
              d.connect("level.y", "chassis.slope"), d.connect("free.y", "chassis.towing_force")]
    if mapped:
        for axle in ("frontAxle", "rearAxle"):
            lines += [d.connect("chassis.position", f"{axle}.u1"),
                      d.connect("halfWheelbase.y", f"{axle}.u2")]
    for k, w in enumerate(rover.WHEELS, start=1):
        lines += [d.connect(f"chassis.{q}[{k}]", f"{w}.{q}")
                  for q in ("sinkage", "sinkage_rate", "wheel_speed", "carriage_speed")]
        lines += [d.connect("straight.y", f"{w}.{q}") for q in ("slip_angle", "yaw_rate")]
        if mapped:
            axle = "frontAxle" if w in rover.FRONT else "rearAxle"
            lines.append(d.connect(f"{axle}.y", f"{w}.position"))
        lines += [d.connect(f"{w}.{q}", f"chassis.{q}[{k}]")
                  for q in ("normal_force", "drawbar_pull", "torque")]
        lines += [d.connect("noCommand.y", f"chassis.{q}[{k}]") for q in rover.WHEEL_COMMANDS]
    lines += [f"  annotation({_experiment(name, stop, interval)},",
              f'    Documentation(info="<html><p>{_reference_doc(name)} (the '
              "Python model: the RoverChassis FMU's model-exchange rates on four contacts with "
              'memory). Model exchange records no rut along the track (as the FMUs\' model '
              'exchange): the rear wheels do not meet the front wheels\' rut here.</p></html>"));',
              f"end {name};"]
    return "\n".join(lines) + "\n"


def _planar_rover(pins: dict[str, dict[str, tuple[float, float]]]) -> str:
    """Examples.PlanarRover: the rover of Examples.FMUTwin.Rover from standard parts (a body,
    PlanarMechanics' FixedTranslation axles, four PlanarWheels, four Utilities.SpeedDrives), its
    rover parameters Data.rover's rows by name."""
    rows = {n.split(".", 1)[1]: rover.ROVER_NAMES.index(n) + 1 for n in rover.ROVER_NAMES
            if n.count(".") == 1}
    phase = NAMES.index("ripple.phase") + 1
    wheels, connections = [], []
    d, drive = Diagram(), pins["SpeedDrive"]
    for axle, y in (("front", 50), ("rear", -20)):  # as the template places them
        d.place(axle, 10, y, MSL_PINS["FixedTranslation"], 10)
    for k, w in enumerate(rover.WHEELS):  # a row each, top to bottom: drive, then wheel
        y = 75 - 45 * k
        j = rover.ROVER_NAMES.index(f"rover.grouser_phase.{w}") + 1
        axle = "front" if w in rover.FRONT else "rear"
        wheels += [f"  {LIBRARY}.Wheels.PlanarWheel {w}(parameters(ripple(phase="
                   f"{LIBRARY}.Data.rashidPatch[{phase}] + r[{j}])))",
                   f'    "{w}: its grouser phase the preset\'s and rover.grouser_phase.{w}"',
                   f"    annotation({d.place(w, 50, y, pins['PlanarWheel'])});",
                   f"  {LIBRARY}.Examples.Utilities.SpeedDrive {w}_drive("
                   f"J=r[{rows['wheel_inertia']}], bandwidth=r[{rows['speed_bandwidth']}],",
                   f"    w_ref=rim_speed/slip_radius, tau_max=r[{rows['motor_torque_limit']}],",
                   "    w_end=rim_speed_end/slip_radius, ramp_start_time=change_start_time, "
                   "ramp_duration=change_duration) "
                   f'"{w}\'s motor and speed loop"',
                   f"    annotation({d.place(w + '_drive', 110, y, drive, 20, True)});"]
        connections += [d.connect(f"{axle}.frame_b", f"{w}.frame_a", signal=False),
                        d.connect(f"{w}_drive.flange_b", f"{w}.flange_a", signal=False),
                        d.connect(f"{w}_drive.support", f"{w}.support", signal=False)]
    return _template(
        "PlanarRover", R=len(rover.ROVER_NAMES),
        heave_start=translate.literal(reference.ROVER_HEAVE_START),
        wheels="\n".join(wheels), connections="\n".join(connections),
        experiment=_experiment("PlanarRover", *reference.rover_run("Rover")),
        reference=_reference_doc("PlanarRover"),
        **{name: rows[name] for name in (
            "mass", "pitch_inertia", "wheelbase", "cg_forward", "cg_height", "gravity",
            "rim_speed", "slip_radius", "ramp_time", "slope_rate", "slope_rate_after",
            "slope_bound")})


def _profiled_rover(name: str, base: str, example: str, what: str, info: str) -> str:
    """Examples.``name``: the rover example ``base`` with the rover parameters of the rover
    example ``example`` (its input profile, reference.ROVER_PROFILES) and its run."""
    r = reference.rover_parameters(example)
    return (f'model {name} "{what}: {reference.ROVER_DESCRIPTIONS[example]}"\n'
            f"  extends {base}(r={_vector([r[n] for n in rover.ROVER_NAMES])});\n"
            f"  annotation({_experiment(name, *reference.rover_run(example))},\n"
            f'    Documentation(info="<html><p>{info}</p></html>"));\n'
            f"end {name};\n")


def _examples(lib: Library) -> None:
    where = f"{LIBRARY}/Examples"
    load = translate.literal(reference.STEADY_LOAD)
    _class_file(lib, where, "SteadyC2", _template(
        "SteadyC2", steady_load=load,
        experiment=_experiment("SteadyC2", reference.STEADY_TIMES[-1], 0.5)))
    _class_file(lib, where, "SlipRamp", _template(
        "SlipRamp", steady_load=load, ramp_start=translate.literal(reference.RAMP[0]),
        ramp_rate=translate.literal(reference.RAMP[1]),
        experiment=_experiment("SlipRamp", reference.RAMP_TIMES[-1], 0.05)))
    rig = {row.name.replace(".", "_"): translate.literal(row.default) for row in RIG_TABLE}
    _class_file(lib, where, "Rig", _template(
        "Rig", sinkage_start=translate.literal(reference.RIG_SINKAGE_START), **rig))
    twins = f"{where}/FMUTwin"
    components = f"{LIBRARY}/Components"
    pins = {name: _pins(lib.files[f"{components}/{name}.mo"]) for name in ("RoverChassis",)}
    pins["Wheel"] = _pins(lib.files[f"{components}/PartialWheel.mo"])
    pins["MapWheel"] = pins["Wheel"] | _pins(lib.files[f"{components}/MapWheel.mo"])
    _class_file(lib, twins, "Rover", _rover_example(pins))
    twin_order = ["Rover"]
    for example in reference.ROVER_MAPS:
        _class_file(lib, twins, example, _rover_example(pins, example))
        twin_order.append(example)
    for example, profile in reference.ROVER_PROFILES.items():
        if example == "Rover":
            continue
        changed = ", ".join(sorted(profile))
        _class_file(lib, twins, example, _profiled_rover(
            example, f"{LIBRARY}.{reference.class_path('Rover')}", example, "The rover",
            f"Data.rover with {changed} changed. {_reference_doc(example)} (the Python model, "
            "as for Rover). <code>wheelterrain rover --scenario slope|descent|pull-test</code> "
            "goes on until the rover stalls or slides."))
        twin_order.append(example)
    assert sorted(twin_order) == sorted(reference.fmu_twins())
    lib.package(where, "FMUTwin", "The rover on the RoverChassis block: the RoverChassis and "
                "WheelTerrain FMUs' model exchange in Modelica, their cross-check (the rover "
                "from standard parts: Examples.PlanarRover)", twin_order)
    order = ["SteadyC2", "SlipRamp", "Rig"]
    _class_file(lib, where, "PlanarRig", _template(
        "PlanarRig", sinkage_start=translate.literal(reference.RIG_SINKAGE_START),
        experiment=_experiment("PlanarRig", reference.RIG_STOP, reference.RIG_INTERVAL),
        **rig))
    utilities = _template("Utilities")
    drive = utilities[utilities.index("model SpeedDrive"):utilities.index("end SpeedDrive")]
    _class_file(lib, where, "PlanarRover", _planar_rover({
        "PlanarWheel": _pins(lib.files[f"{LIBRARY}/Wheels/PlanarWheel.mo"]),
        "SpeedDrive": _pins(drive)}))
    slope = reference.PLANAR_ROVERS["PlanarRoverSlope"]
    _class_file(lib, where, "PlanarRoverSlope", _profiled_rover(
        "PlanarRoverSlope", "PlanarRover", slope, "The rover from standard parts",
        f"PlanarRover with {slope}'s rover parameters. {_reference_doc('PlanarRoverSlope')} "
        f"({slope}'s: the Python model)."))
    _class_file(lib, where, "Utilities", utilities)
    order += ["PlanarRig", "PlanarRover", "PlanarRoverSlope", "FMUTwin", "Utilities"]
    for case, s in reference.RIG_CASES.items():
        name = f"Rig{case}"
        run = _experiment(name, reference.RIG_STOP, reference.RIG_INTERVAL)
        text = (f'model Rig{case} "The rig at the paper\'s {case}: slip s = {s}"\n'
                f"  extends Rig(slip_paper={translate.literal(s)});\n"
                f"  annotation({run},\n"
                f'    Documentation(info="<html><p>{_reference_doc(name)} '
                f'(the Python model\'s rig in continuous time).</p></html>"));\n'
                f"end Rig{case};\n")
        _class_file(lib, where, f"Rig{case}", text)
        order.append(f"Rig{case}")
    first = ["SteadyC2", "SlipRamp", "Rig", *(f"Rig{case}" for case in reference.RIG_CASES)]
    assert sorted(order) == sorted([*first, "PlanarRig", "PlanarRover", "PlanarRoverSlope",
                                    "FMUTwin", "Utilities"])
    order = first + [n for n in order if n not in first]
    lib.package(LIBRARY, "Examples", "Examples with experiment annotations; reference results "
                "in Resources/Reference (MSL's regression layout)", order)


# ---- the package, the guide, the reference results ----------------------------------------

def _users_guide(lib: Library) -> None:
    rows = "".join(
        f"<tr><td>{html.escape(n)}</td><td>{html.escape(modelica_name(n))}</td>"
        f"<td>{html.escape(TABLE[k].unit)}</td></tr>" for k, n in enumerate(NAMES))
    outputs = "".join(f"<tr><td>{k + 1}</td><td>{html.escape(n)}</td></tr>" for k, n in
                      enumerate(contact.CONTACT_OUTPUTS + contact.MEMORY_OUTPUTS))
    info = string.Template(resources.files("wheelterrain.modelica").joinpath(
        "templates", "UsersGuide.html").read_text(encoding="utf-8")).substitute(
        version=__version__, outputs=outputs, rows=rows, msl=MSL_VERSION,
        SLIP_SPEED_FLOOR=_slip_speed_floor())
    text = (f'package UsersGuide "Conventions, slips, the name map, what was tested"\n'
            f'  annotation(Documentation(info="{_doc(info)}"));\nend UsersGuide;\n')
    _class_file(lib, LIBRARY, "UsersGuide", text)


EXAMPLE_ICON = ('Icon(graphics={Ellipse(extent={{-100,100},{100,-100}}, lineColor={75,138,73}, '
                'fillColor={255,255,255}, fillPattern=FillPattern.Solid), Polygon(points='
                '{{-36,60},{64,0},{-36,-60},{-36,60}}, lineColor={0,0,255}, fillColor={75,138,73}, '
                'fillPattern=FillPattern.Solid)})')
"""MSL's example icon (Modelica.Icons.Example's look, drawn here rather than extended)."""
BLOCK_ICON = ('Icon(graphics={Rectangle(extent={{-100,100},{100,-100}}, lineColor={0,0,127}, '
              'fillColor={255,255,255}, fillPattern=FillPattern.Solid), Ellipse(extent='
              '{{-50,50},{50,-50}}, lineColor={64,64,64}, fillColor={160,160,160}, '
              'fillPattern=FillPattern.Solid), Text(extent={{-150,150},{150,110}}, '
              'textString="%name", textColor={0,0,255})})')
"""The components' icon where their template draws none: a wheel in a block."""


def _revisions() -> str:
    return (f'"<html><ul><li>{__version__}: generated by wheelterrain {__version__}.</li>'
            '</ul></html>"')


def _string_end(text: str, start: int) -> int:
    """The index just past the Modelica string literal opening at ``start``."""
    k = start + 1
    while text[k] != '"':
        k += 2 if text[k] == "\\" else 1
    return k + 1


def _documented(path: str, text: str) -> str:
    """``text`` (one class file) with Documentation info and revisions on its class, where
    missing: info the class's description, revisions the generator's version; an icon on a
    component or an example that has none."""
    parts = path.split("/")
    name = parts[-2] if parts[-1] == "package.mo" else parts[-1][:-3]
    prefixes = "(?:partial |encapsulated |pure |impure )*"
    header = re.search(rf'^{prefixes}\w+ {name} "((?:[^"\\]|\\.)*)"', text, re.M)
    end = text.rfind(f"end {name};")
    if header is None or end < 0:
        raise ValueError(f"{path}: no class {name} with a description")
    own = [m.start() for m in re.finditer(r"^  annotation\(", text, re.M) if m.start() < end]
    at = own[-1] if own else None
    block = text[at:end] if at is not None else ""
    additions = []
    if "Documentation(" not in block:
        info = f'"<html><p>{html.escape(header.group(1), quote=False)}.</p></html>"'
        additions.append(f"Documentation(info={info}, revisions={_revisions()})")
    if "/Components/" in path and "Icon(" not in block and "partial " not in text[:header.end()]:
        additions.append(BLOCK_ICON)
    if "/Examples/" in path and "Icon(" not in block and "/Utilities" not in path:
        additions.append(EXAMPLE_ICON)
    if "revisions=" not in block and "Documentation(" in block:
        info = block.index('info="', block.index("Documentation(")) + len("info=")
        close = _string_end(block, info)
        block = block[:close] + f", revisions={_revisions()}" + block[close:]
        text = text[:at] + block + text[end:]
        end = text.rfind(f"end {name};")
    if not additions:
        return text
    if at is None:
        return text[:end] + f"  annotation({', '.join(additions)});\n" + text[end:]
    opening = at + len("  annotation(")
    return text[:opening] + ", ".join(additions) + ", " + text[opening:]


def _document(lib: Library) -> None:
    """info and revisions on every public class (not the pieces of Functions.Internal)."""
    for path in list(lib.files):
        if path.endswith(".mo") and "/Functions/Internal/" not in path:
            lib.files[path] = _documented(path, lib.files[path])


def _name(lib: Library) -> None:
    """Every class file's own identifiers in MSL's naming convention (:mod:`.names`): written
    with the model's snake_case names, read in lowerCamelCase; the strings' mentions of them
    too (not the table's and the FMUs' names, 'soil.k_phi'). Refused where two of the model's
    names would become one."""
    mo = [path for path in lib.files if path.endswith(".mo")]
    own = set().union(*(names.identifiers(lib.files[path]) for path in mo))
    names.check_distinct(own)
    known = frozenset(n for n in own if names.identifier(n) != n)
    tables = frozenset(n.partition(".")[0] for n in (*NAMES, *(row.name for row in RIG_TABLE),
                                                      *rover.ROVER_NAMES, *ground.NAMES))
    for path in mo:
        lib.files[path] = names.prose(names.code(lib.files[path]), known, tables)


def build_library(named: bool = True) -> Library:
    """The whole library as files (relative path -> text); ``named`` False: its class files
    with the model's names, before :func:`_name` (what the name checks read)."""
    lib = Library()
    lib.package("", LIBRARY, "Rigid-wheel terramechanics for planetary rover wheels with "
                "grousers on loose soil (generated by wheelterrain)",
                ["UsersGuide", "Wheels", "Terrain", "Types", "Functions", "Data", "Records",
                 "Components", "Examples"],
                f'version="{__version__}", uses(Modelica(version="{MSL_VERSION}"), '
                f'PlanarMechanics(version="{PLANAR_MECHANICS_VERSION}"))')
    _users_guide(lib)
    _functions(lib)
    _data(lib)
    _records(lib)
    _components(lib)
    _planar(lib)
    _examples(lib)
    _document(lib)
    if named:
        _name(lib)
    for name, text in reference.files().items():
        lib.add(f"{LIBRARY}/Resources/Reference/{name}", text)
    for name, text in external.sources(entries()).items():
        lib.add(f"{LIBRARY}/Resources/C-Sources/{name}", text)
    return lib


def write(out: Path, notes: list[str] | None = None, say=lambda message: None) -> Path:
    """Write the library to ``out``/WheelTerrain (replacing what is there) and return that
    folder, Functions.External's C compiled into Resources/Library as far as this machine's
    compilers can (``notes`` gets a line per binary that could not be built, ``say`` a line
    before each compile)."""
    import shutil
    import tempfile

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    lib = build_library()
    staging = Path(tempfile.mkdtemp(prefix=".WheelTerrain-", dir=out))
    try:
        lib.write(staging)
        resources_ = staging / LIBRARY / "Resources"
        missing = external.build(resources_ / "C-Sources", resources_ / "Library", say)
        if notes is not None:
            notes += missing
        target = out / LIBRARY
        if target.exists():
            shutil.rmtree(target)
        (staging / LIBRARY).rename(target)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return out / LIBRARY
