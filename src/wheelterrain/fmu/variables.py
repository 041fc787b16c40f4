"""The one table of the FMUs' variables: every input, output and FMU-only parameter of
WheelTerrain.fmu and SingleWheelRig.fmu, with causality, unit, Modelica quantity, display unit,
type, start, range, description and direct dependencies. The soil, wheel and rig parameters come
from the one parameter table (:data:`wheelterrain.parameters.ROWS`).

Every list of FMU variable names in the project is derived from here: the order of the values
in and out of the per-step CasADi Functions (:data:`TERRAIN_INPUTS`, :data:`TERRAIN_OUTPUTS`,
:data:`RIG_INPUTS`, :data:`RIG_OUTPUTS`), what the co-simulation master and the SSP files
connect (:data:`COUPLED_STATES` rig -> terrain, :data:`COUPLED_FORCES` terrain -> rig: the
names the two FMUs share), the pythonfmu registrations and the modelDescription post-processing
(:func:`terrain_variables`, :func:`rig_variables`), the native wrapper's variable table, the
sweep's columns and the units of every result file (:func:`units`).

No CasADi at import (the sweep's workers read the names): the rig's parameter table is loaded
only when a whole variable list is asked for.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace

from wheelterrain.parameters import (
    GROUND_FMU,
    INDEX,
    RIG_FMU,
    ROVER_FMU,
    ROWS,
    SLIP_ANGLE_LIMIT,
    TERRAIN_FMU,
    TURN_SLIP_LIMIT,
    Parameter,
)


@dataclass(frozen=True)
class Var:
    """One FMU variable, as the slave registers it and as modelDescription.xml describes it."""

    name: str
    causality: str  # parameter | input | output | local (a state derivative)
    description: str
    unit: str = "1"
    quantity: str | None = None
    display_unit: str | None = None
    type: str = "Real"  # Real | Integer | Boolean
    start: float | None = None
    min: float | None = None
    max: float | None = None
    depends_on: tuple[str, ...] | None = None  # outputs: the inputs they depend on directly
    integrated: bool = False  # outputs: kept by the wrapper (a state), not a Function output
    choices: Mapping[int, str] | None = None
    """A mode switch: its values and their names. An Integer in the FMU (min and max its
    first and last value; its description names each), not an FMI Enumeration: libcosim
    and ecos set no Enumeration variable, so a switch in an SSP would silently stay at its
    start value there."""
    nominal: float | None = None
    """A continuous state's typical magnitude: a model-exchange host scales its error
    tolerance with it (absolute tolerance = relative tolerance * nominal)."""
    derivative_of: str | None = None
    """For a state derivative (model exchange): the state it is the time derivative of."""


def _outputs(rows: list[Var], inputs: tuple[str, ...]) -> list[Var]:
    """Terrain outputs computed from the inputs: direct feedthrough of all of them."""
    return [replace(v, depends_on=inputs) if v.depends_on is None else v for v in rows]


def ground_name(soil: str) -> str:
    """The ``ground.*`` variable that carries the soil row ``soil`` (``soil.phi`` ->
    ``ground.phi``): a WheelTerrain input and a Terrain output."""
    return "ground." + soil.split(".", 1)[1]


SOIL_ROWS: tuple[Parameter, ...] = tuple(p for p in ROWS if p.name.startswith("soil."))
"""The soil's rows of the parameter table: what a terrain map supplies along a path."""
GROUND: tuple[str, ...] = tuple(ground_name(p.name) for p in SOIL_ROWS)
"""The ground.* variables, in the order of :data:`SOIL_ROWS`."""


def _ground_inputs() -> list[Var]:
    """WheelTerrain's ground.* inputs: a soil row each, with its unit and validity range."""
    return [Var(ground_name(p.name), "input", "Soil under the wheel when soil_from_inputs is "
                f"true (a terrain map's output, else unused): {p.description}", p.unit,
                p.quantity, p.display_unit, start=p.default, min=p.min, max=p.max)
            for p in SOIL_ROWS]


SINKAGE_RANGE = (-1.0, 1.0)
"""m: the terrain's sinkage input and the rig's sinkage output (the rig refuses to step
beyond it), one range for the pair."""

_TERRAIN_INPUT_ROWS = [
    Var("sinkage", "input", "Sinkage of the wheel below the undisturbed soil surface, "
        "measured to the contact circle (dynamic mode)", "m", "Length", "mm", start=0.02,
        min=SINKAGE_RANGE[0], max=SINKAGE_RANGE[1]),
    Var("sinkage_rate", "input", "Rate of sinkage, positive downward (dynamic mode)", "m/s",
        "Velocity", start=0.0, min=-100.0, max=100.0),
    # start: the default preset's rim speed over its radius (terrain_variables)
    Var("wheel_speed", "input", "Wheel angular velocity, positive when driving forward",
        "rad/s", "AngularVelocity", min=-1.0e3, max=1.0e3),
    # start: the rig's default rim speed (terrain_variables)
    Var("carriage_speed", "input", "Forward speed of the wheel axle (carriage)", "m/s",
        "Velocity", min=-100.0, max=100.0),
    Var("load", "input", "Vertical load on the wheel (quasi-static mode)", "N", "Force",
        start=62.0, min=0.0, max=1.0e5),
    Var("rut_met", "input", "Depth of the rut the wheel meets, recorded by a terrain with "
        "memory (a Terrain.fmu query point's rut_met; 0: none): the contact takes the deeper "
        "of it and soil.rut_depth (with model.soil_memory = 1)", "m", "Length", "mm",
        start=0.0, min=0.0, max=1.0),
]
_TERRAIN_INPUTS = tuple(v.name for v in _TERRAIN_INPUT_ROWS)
_SLIP_ANGLE = Var("slip_angle", "input", "Slip angle between the wheel's heading and its "
                  "velocity, positive when the wheel moves toward its left "
                  "(atan(lateral speed / forward speed) of the axle); the slip inputs are then "
                  "the speeds along the heading. 0: a wheel driven straight (no lateral "
                  "force)", "rad", "Angle", "deg", start=0.0, min=-SLIP_ANGLE_LIMIT,
                  max=SLIP_ANGLE_LIMIT)
_RUT_PRESSURE = ROWS[INDEX["soil.rut_pressure"]]
"""The row whose range the rut pressure met and left (WheelTerrain, Terrain) share."""
_RUT_PRESSURE_MET = Var(
    "rut_pressure_met", "input", "Pressure the rut the wheel meets (rut_met) carried when it "
    "was made, recorded with it by a terrain with memory (a Terrain.fmu query point's "
    "rut_pressure_met): where rut_met is deeper than soil.rut_depth, it replaces "
    "soil.rut_pressure. 0: not known (the rut read from its depth with the wheel's own law)",
    "Pa", "Pressure", "kPa", start=0.0, min=_RUT_PRESSURE.min, max=_RUT_PRESSURE.max)
_YAW_RATE = Var("yaw_rate", "input", "Yaw rate of the wheel about the vertical through its "
                "centre, positive counter-clockwise seen from above; with carriage_speed, the "
                "turn slip yaw_rate/carriage_speed (rad/m, the curvature of the wheel's path), "
                f"|turn slip| <= {TURN_SLIP_LIMIT:g} rad/m. 0: a wheel that does not yaw",
                "rad/s", "AngularVelocity", start=0.0, min=-1.0e3, max=1.0e3)

TERRAIN_IO: tuple[Var, ...] = (
    Var("quasi_static", "parameter",
        "true: solve the sinkage that carries the input 'load' (grouser-period mean, ripple "
        "off, as `wheelterrain steady`); false: forces at the input sinkage and sinkage rate "
        "(ripple on, contact damping on)", type="Boolean", start=False),
    Var("warm_start", "parameter",
        "quasi-static mode: true: start the sinkage solve from the last solved sinkage (the "
        "contact_sinkage output; the cold solve where that does not converge), about twice as "
        "fast a step; false: every solve cold, the shallowest equilibrium whatever came "
        "before. They differ only where the static normal force is non-monotone in sinkage "
        "(extreme braking corners), where a warm start stays on the equilibrium it is on",
        type="Boolean", start=True),
    *_TERRAIN_INPUT_ROWS,
    *_outputs([
        Var("normal_force", "output", "Normal (vertical) force of the soil on the wheel, up",
            "N", "Force"),
        Var("drawbar_pull", "output", "Drawbar pull: net forward force of the soil on the "
            "wheel", "N", "Force"),
        Var("torque", "output", "Resistive torque of the soil about the axle (what the motor "
            "must supply)", "N.m", "Torque"),
        Var("gross_thrust", "output", "Gross thrust: forward part of the shear stress", "N",
            "Force"),
        Var("compaction_resistance", "output", "Compaction resistance: backward part of the "
            "normal stress", "N", "Force"),
        Var("contact_sinkage", "output", "Sinkage the forces were evaluated at: the input in "
            "dynamic mode, the solved one in quasi-static mode", "m", "Length", "mm"),
        Var("slip", "output", "The model's slip (omega*R_ref - V)/max(omega*R_ref, V): the "
            "traction slip driving, the skid (the paper's s) braking; -1 a locked wheel, 1 "
            "spinning in place", "1"),
        Var("slip_paper", "output", "Slip in the paper's definition s = (omega*R_ref - V)/V: 0 "
            "with wheel and carriage at rest; undefined (NaN, with a warning) with the "
            "carriage at rest and the wheel turning", "1"),
        Var("entry_angle", "output", "Entry angle theta_f of the contact arc", "rad", "Angle",
            "deg"),
        Var("exit_angle", "output", "Exit angle theta_r of the contact arc (<= 0)", "rad",
            "Angle", "deg"),
        Var("max_stress_angle", "output", "Angle theta_m of the maximum normal stress", "rad",
            "Angle", "deg"),
        Var("contact_length", "output", "Contact length R_c*(sin(theta_f) - sin(theta_r))",
            "m", "Length"),
        Var("mean_pressure", "output", "Mean contact pressure of the ripple-free stress", "Pa",
            "Pressure"),
        Var("ripple_amplitude", "output", "Amplitude A of the grouser stress ripple (0 in "
            "quasi-static mode)", "Pa", "Pressure"),
        Var("rut_left", "output", "Depth of the rut the wheel leaves behind, from the "
            "original surface: the deepest point it pressed the soil to less the elastic "
            "rebound, never shallower than the rut it met (soil.rut_depth); 0 with "
            "model.soil_memory = 0. What a terrain with memory records along the track",
            "m", "Length", "mm"),
    ], (*_TERRAIN_INPUTS, *GROUND, "rut_pressure_met")),
    Var("wheel_angle", "output", "Wheel rotation angle, integrated from wheel_speed (phase of "
        "the grouser ripple)", "rad", "Angle", "deg", depends_on=(), integrated=True,
        nominal=1.0),
    Var("plastic_sinkage", "output", "Plastic sinkage z_p of the soil under the wheel (a "
        "state): the deepest the wheel has pressed it, relaxing toward the wheel's sinkage as "
        "it rolls onto the soil ahead (over about one contact length). Above it the soil "
        "answers elastically (soil.unloading_stiffness); 0 and unused with "
        "model.soil_memory = 0", "m", "Length", "mm", depends_on=(), integrated=True,
        nominal=0.01),
    # after everything else, so that the value references of the variables above stay as they
    # were before a terrain map could feed the soil
    Var("soil_from_inputs", "parameter",
        "false: the soil is the soil.* parameters (one soil for the whole run); true: the soil "
        "under the wheel is the ground.* inputs, connected to a terrain map's query point (e.g. "
        "Terrain.fmu), the soil.* parameters unused", type="Boolean", start=False),
    *_ground_inputs(),
    # a wheel at a slip angle: after everything else, so that the value references above
    # stay as they were (today's connections keep working, the new input at its start, 0)
    _SLIP_ANGLE,
    *_outputs([
        Var("lateral_force", "output", "Lateral force of the soil on the wheel, along its "
            "axle, positive to the wheel's left (Ishigami et al. 2007's side force: lateral "
            "shear on the rim and the side face's bulldozing; grouser-period mean); 0 at "
            "slip_angle and yaw_rate 0", "N", "Force"),
        Var("aligning_moment", "output", "Moment of the lateral force about the vertical "
            "through the wheel's centre, positive counter-clockwise seen from above (the "
            "self-aligning moment); 0 at slip_angle and yaw_rate 0", "N.m", "Torque"),
    ], (*_TERRAIN_INPUTS, *GROUND, "slip_angle", "yaw_rate", "rut_pressure_met")),
    # a wheel that yaws: after the slip angle's variables, for the same reason
    _YAW_RATE,
    *_outputs([
        Var("turning_moment", "output", "The soil's whole moment on the wheel about the "
            "vertical through its centre, positive counter-clockwise seen from above (M_z: "
            "aligning_moment plus the moment of the longitudinal shear across the tread's "
            "width that a yawing wheel meets; grouser-period mean); equal to aligning_moment "
            "at yaw_rate 0, 0 at slip_angle and yaw_rate 0", "N.m", "Torque"),
        Var("overturning_moment", "output", "Moment of the lateral stresses about the wheel's "
            "heading axis (x, forward) through its centre, positive by the right-hand rule "
            "(a lateral force to the left acting below the centre gives a positive moment): "
            "each element's force times its depth below the centre (grouser-period mean); 0 "
            "at slip_angle and yaw_rate 0", "N.m", "Torque"),
    ], (*_TERRAIN_INPUTS, *GROUND, "slip_angle", "yaw_rate", "rut_pressure_met")),
    # the pressure a rut carried: after everything else, for the same reason
    _RUT_PRESSURE_MET,
    *_outputs([
        Var("rut_pressure_left", "output", "Pressure the wheel pressed the soil to at the "
            "deepest point of the rut it leaves (rut_left): the yield pressure that rut keeps, "
            "what a terrain with memory records with it (the next wheel's soil.rut_pressure); "
            "where the wheel only reloaded the rut it met, that rut's own (0 where not "
            "known); 0 with model.soil_memory = 0", "Pa", "Pressure", "kPa"),
    ], (*_TERRAIN_INPUTS, *GROUND, "slip_angle", "yaw_rate", "rut_pressure_met")),
)

RIG_IO: tuple[Var, ...] = (
    # start: the default rig.load, so that unconnected the soil holds the wheel still (with
    # no force the wheel free-falls and the rig refuses to step once it leaves its range)
    Var("normal_force", "input", "Normal force of the soil on the wheel (from WheelTerrain)",
        "N", "Force", start=next(p.default for p in ROWS if p.name == "rig.load"),
        min=-1.0e6, max=1.0e6),
    Var("drawbar_pull", "input", "Drawbar pull of the soil on the wheel (from WheelTerrain)",
        "N", "Force", start=0.0, min=-1.0e6, max=1.0e6),
    Var("torque", "input", "Resistive soil torque about the axle (from WheelTerrain)", "N.m",
        "Torque", start=0.0, min=-1.0e6, max=1.0e6),
    Var("wheel_speed_command", "input", "Speed the wheel's speed loop tracks when rig.drive "
        "= 1 (speed-command)", "rad/s", "AngularVelocity", start=0.0, min=-1.0e3, max=1.0e3),
    Var("motor_torque_command", "input", "Torque the wheel motor applies when rig.drive = 2 "
        "(torque-command)", "N.m", "Torque", start=0.0, min=-1.0e4, max=1.0e4),
    Var("sinkage", "output", "Wheel sinkage (state of the vertical motion), positive down; "
        "a step that takes it outside its range is the rig's last (the next is refused)",
        "m", "Length", "mm", min=SINKAGE_RANGE[0], max=SINKAGE_RANGE[1], depends_on=(),
        nominal=0.01),
    Var("sinkage_rate", "output", "Sinkage rate, positive down", "m/s", "Velocity",
        depends_on=(), nominal=0.01),
    Var("wheel_speed", "output", "Wheel angular velocity (state of the speed loop)", "rad/s",
        "AngularVelocity", depends_on=(), nominal=1.0),
    Var("carriage_speed", "output", "Carriage speed: rim_speed/(1 + s) when kinematic, "
        "the state of the free carriage's motion otherwise", "m/s", "Velocity",
        depends_on=(), nominal=0.01),
    Var("motor_torque", "output", "Torque of the wheel motor (the speed loop's, or the "
        "torque command): over the last step in co-simulation, at the current state and "
        "commands in model exchange", "N.m", "Torque",
        depends_on=("wheel_speed_command", "motor_torque_command")),
    Var("speed_error_integral", "output", "Integral of the speed loop's error (state of "
        "its PI controller)", "rad", "Angle", depends_on=(), nominal=0.001),
    Var("sensor.drawbar_pull", "output", "Drawbar pull the rig's force sensor reads", "N",
        "Force", depends_on=("drawbar_pull",)),
    Var("sensor.normal_force", "output", "Normal force the rig's force sensor reads", "N",
        "Force", depends_on=("normal_force",)),
    Var("sensor.sinkage", "output", "Sinkage the rig's potentiometer reads", "m", "Length",
        "mm", depends_on=()),
    Var("sensor.slip_paper", "output", "Slip in the paper's definition from the measured "
        "wheel and carriage speeds: undefined (NaN, with a warning) with the carriage at rest "
        "and the wheel turning", "1", depends_on=()),
)


# --- RoverChassis: per wheel the rig's wheel variables with the wheel's prefix -----------------
ROVER_WHEELS = ("front_left", "front_right", "rear_left", "rear_right")
"""The rover's wheels, front axle first (the order of wheelterrain.model.rover.WHEELS)."""
_RIG_ROWS = {v.name: v for v in RIG_IO}
_WHEEL_INPUTS = ("normal_force", "drawbar_pull", "torque", "wheel_speed_command",
                 "motor_torque_command")
_WHEEL_OUTPUTS = ("sinkage", "sinkage_rate", "wheel_speed", "carriage_speed", "motor_torque",
                  "speed_error_integral")
_WHEEL_WORDS = {"from WheelTerrain": "from this wheel's WheelTerrain",
                "rig.drive = 1 (speed-command)": "rover.drive = 1 (speed-command)",
                "rig.drive = 2 (torque-command)": "rover.drive = 2 (torque-command)"}


def _static_wheel_loads() -> dict[str, float]:
    """Each wheel's load [N] of the default rover at rest on level ground: the start of its
    normal_force input, so that RoverChassis alone (a checker, `fmpy simulate`, a host that
    runs an FMU with its start values) stands on its wheels instead of falling out of its heave
    range (with 0 it fell, at 0.46 s)."""
    from wheelterrain.model import rover

    return rover.static_axle_loads(rover.defaults())


def _wheel_var(wheel: str, v: Var) -> Var:
    """The rig's variable ``v`` as ``wheel``'s (prefixed name, the rover's words)."""
    text = v.description
    for old, new in _WHEEL_WORDS.items():
        text = text.replace(old, new)
    if v.name == "sinkage":
        text = ("Sinkage of this wheel's axle below the undisturbed surface, from the chassis' "
                "heave and pitch, positive down")
    elif v.name == "carriage_speed":
        text = "Speed of this wheel's axle along the terrain (the chassis' speed)"
    elif v.name == "motor_torque":
        text = ("Torque of this wheel's motor (its speed loop's, or the torque command, within "
                "+-rover.motor_torque_limit): over the last step in co-simulation, at the "
                "current state and commands in model exchange")
    start = _static_wheel_loads()[wheel] if v.name == "normal_force" else v.start
    depends = None if v.depends_on is None else tuple(f"{wheel}.{d}" for d in v.depends_on)
    return replace(v, name=f"{wheel}.{v.name}", description=f"{wheel}: {text}", start=start,
                   min=None if v.name == "sinkage" else v.min,
                   max=None if v.name == "sinkage" else v.max, depends_on=depends)


ROVER_IO: tuple[Var, ...] = (
    Var("slope", "input", "Slope of the terrain along the direction of travel, positive uphill",
        "rad", "Angle", "deg", start=0.0, min=-1.2, max=1.2),
    Var("towing_force", "input", "Force resisting the rover's motion along the terrain (a "
        "towed load); negative pushes", "N", "Force", start=0.0, min=-1.0e5, max=1.0e5),
    *(_wheel_var(w, _RIG_ROWS[n]) for w in ROVER_WHEELS for n in _WHEEL_INPUTS),
    Var("position", "output", "Distance travelled along the terrain by the chassis' reference "
        "point (the axle line below the centre of mass)", "m", "Length", depends_on=(),
        nominal=1.0),
    Var("speed", "output", "Speed of the chassis along the terrain", "m/s", "Velocity",
        depends_on=(), nominal=0.01),
    Var("heave", "output", "Sinkage of the chassis' reference point, positive down; a step "
        "that takes it outside [-1, 1] m is the rover's last (the next is refused)", "m",
        "Length", "mm", min=SINKAGE_RANGE[0], max=SINKAGE_RANGE[1], depends_on=(),
        nominal=0.01),
    Var("heave_rate", "output", "Rate of the heave, positive down", "m/s", "Velocity",
        depends_on=(), nominal=0.01),
    Var("pitch", "output", "Pitch of the chassis, positive nose down", "rad", "Angle", "deg",
        depends_on=(), nominal=0.01),
    Var("pitch_rate", "output", "Pitch rate, positive nose down", "rad/s", "AngularVelocity",
        depends_on=(), nominal=0.01),
    Var("elapsed", "output", "Time since the start (a state: the clock of the input profile, "
        "rover.ramp_time ... rover.towing_rate)", "s", "Time", depends_on=(), nominal=1.0),
    Var("effective_slope", "output", "Slope the chassis feels: the input plus the profile's "
        "ramp", "rad", "Angle", "deg", depends_on=("slope",)),
    Var("effective_towing_force", "output", "Towing force the chassis feels: the input plus "
        "the profile's ramp", "N", "Force", depends_on=("towing_force",)),
    *(_wheel_var(w, _RIG_ROWS[n]) for w in ROVER_WHEELS for n in _WHEEL_OUTPUTS),
    *(Var(f"{w}.position", "output", f"{w}: position of this wheel's axle along the terrain "
          "(where its soil is: a terrain map's query point)", "m", "Length", depends_on=())
      for w in ROVER_WHEELS),
)


# --- Terrain: a terrain map's query point -----------------------------------------------------
QUERY_POINTS = ("q1", "q2")
"""Terrain.fmu's query points: the wheels of one track, the leading one first (the names of
:data:`wheelterrain.model.ground.QUERY`)."""
_QUERY_ROLE = {"q1": "the leading wheel of the track", "q2": "the wheel behind it"}


def query_ground(query: str) -> tuple[str, ...]:
    """Terrain.fmu's ground.* outputs of query point ``query``: q1.ground.phi, ..."""
    return tuple(f"{query}.{name}" for name in GROUND)


GROUND_IO: tuple[Var, ...] = tuple(v for q in QUERY_POINTS for v in (
    Var(f"{q}.position", "input", f"Position along the path of query point {q} "
        f"({_QUERY_ROLE[q]}: RoverChassis' <wheel>.position, its axle)", "m", "Length",
        start=0.0, min=-1.0e6, max=1.0e6),
    Var(f"{q}.rut_left", "input", f"The rut the wheel at {q} leaves (its WheelTerrain's "
        "rut_left): recorded at its position at each step (co-simulation; model exchange "
        "records none), the deepest in each terrain.cell", "m", "Length", "mm", start=0.0,
        min=0.0, max=1.0),
    Var(f"{q}.rut_pressure_left", "input", f"The pressure the wheel at {q} pressed its rut "
        "to (its WheelTerrain's rut_pressure_left): recorded with the rut (the deepest rut's "
        "in each cell; 0: not known)", "Pa", "Pressure", "kPa", start=0.0,
        min=_RUT_PRESSURE.min, max=_RUT_PRESSURE.max),
    *(Var(f"{q}.{ground_name(p.name)}", "output", f"Soil of the map at query point {q} (to "
          f"its WheelTerrain's input ground.*, with soil_from_inputs): {p.description}",
          p.unit, p.quantity, p.display_unit, depends_on=(f"{q}.position",))
      for p in SOIL_ROWS),
    Var(f"{q}.rut_met", "output", f"The rut the wheel at {q} meets (to its WheelTerrain's "
        "input rut_met): its rut profile (each cell's deepest rut at its middle, linear "
        "between cells' middles) averaged over terrain.lookahead/2 to terrain.lookahead ahead "
        "of its position (at most 10 cells), 0 where no wheel has left one (or the profile "
        "has moved on)", "m", "Length",
        "mm", depends_on=(f"{q}.position",)),
    Var(f"{q}.rut_pressure_met", "output", f"The pressure the rut the wheel at {q} meets "
        "(rut_met) carried (to its WheelTerrain's input rut_pressure_met): averaged as the "
        "rut; 0 where no wheel has left one, or where a cell the average reads holds a rut "
        "of no known pressure", "Pa", "Pressure", "kPa",
        depends_on=(f"{q}.position",))))


def _names(rows: tuple[Var, ...], causality: str, computed: bool = False) -> tuple[str, ...]:
    return tuple(v.name for v in rows
                 if v.causality == causality and not (computed and v.integrated))


TERRAIN_INPUTS = (*_TERRAIN_INPUTS, "slip_angle", "yaw_rate", "rut_pressure_met")
"""The order of the terrain Functions' ``u`` (terrain_dynamic, terrain_quasi_static). The
ground.* inputs (:data:`GROUND`) are not in it: with soil_from_inputs they replace the soil's
entries of the Functions' ``p`` (:func:`soil_from_ground`)."""
TERRAIN_OUTPUTS = _names(TERRAIN_IO, "output", computed=True)
"""The order of the terrain Functions' ``y`` (the wrapper keeps wheel_angle itself)."""
RIG_INPUTS = _names(RIG_IO, "input")
"""The order of the rig Functions' ``u`` (equal to wheelterrain.model.rig.INPUTS)."""
RIG_OUTPUTS = _names(RIG_IO, "output")
"""The order of rig_outputs' ``y``."""
COUPLED_STATES = tuple(n for n in TERRAIN_INPUTS if n in RIG_OUTPUTS)
"""What the rig hands the terrain each exchange: the names both FMUs share, rig -> terrain."""
COUPLED_FORCES = tuple(n for n in RIG_INPUTS if n in TERRAIN_OUTPUTS)
"""What the terrain hands the rig: the names both FMUs share, terrain -> rig."""
ROVER_INPUTS = _names(ROVER_IO, "input")
"""The order of the rover Functions' ``u`` (equal to wheelterrain.model.rover.INPUTS)."""
ROVER_OUTPUTS = _names(ROVER_IO, "output")
"""The order of rover_outputs' ``y``."""
GROUND_OUTPUTS = _names(GROUND_IO, "output")
"""The order of ground_outputs' ``y``: :func:`query_ground` of each query point."""


def soil_from_ground(p: list[float], values: Mapping[str, float]) -> list[float]:
    """The terrain Functions' parameter vector ``p`` (table order) with the soil's entries
    replaced by the ground.* ``values`` by name: what both WheelTerrain flavours evaluate when
    soil_from_inputs is true (the native wrapper does the same with GROUND_VRS/GROUND_P)."""
    out = list(p)
    for row, name in zip(SOIL_ROWS, GROUND, strict=True):
        out[INDEX[row.name]] = float(values[name])
    return out


def parameter_var(p: Parameter, start: float) -> Var:
    """A parameter table row as an FMU parameter."""
    kind = "Integer" if p.kind in ("integer", "enum") else "Real"
    return Var(p.name, "parameter", f"{p.description} [{p.source}]", p.unit, p.quantity,
               p.display_unit, kind, start, p.min, p.max,
               choices=p.choices if p.kind == "enum" else None)


def terrain_variables() -> list[Var]:
    """WheelTerrain.fmu's variables in value-reference order: the parameter table (starts from
    the default preset), then :data:`TERRAIN_IO` (wheel and carriage speeds start at the rig's
    default rim speed)."""
    from wheelterrain import presets
    from wheelterrain.model import rig

    start = dict(presets.load(presets.DEFAULT_PRESET))
    rim_speed = rig.defaults()["rig.rim_speed"]
    starts = {"wheel_speed": rim_speed / start["wheel.radius"], "carriage_speed": rim_speed,
              **{ground_name(p.name): start[p.name] for p in SOIL_ROWS}}
    rows = (p for p in ROWS if p.fmu == TERRAIN_FMU)
    return [*(parameter_var(p, start[p.name]) for p in rows),
            *(replace(v, start=starts[v.name]) if v.name in starts else v for v in TERRAIN_IO)]


def rig_variables() -> list[Var]:
    """SingleWheelRig.fmu's variables in value-reference order: the parameter table's rig rows,
    then :data:`RIG_IO`."""
    return [*(parameter_var(p, p.default) for p in ROWS if p.fmu == RIG_FMU), *RIG_IO]


def rover_variables() -> list[Var]:
    """RoverChassis.fmu's variables in value-reference order: the parameter table's rover
    rows, then :data:`ROVER_IO`."""
    return [*(parameter_var(p, p.default) for p in ROWS if p.fmu == ROVER_FMU), *ROVER_IO]


def ground_variables() -> list[Var]:
    """Terrain.fmu's variables in value-reference order: the soil rows (starts from the default
    preset, as WheelTerrain's), the map's own rows (patch.*), then :data:`GROUND_IO`."""
    from wheelterrain import presets

    start = dict(presets.load(presets.DEFAULT_PRESET))
    return [*(parameter_var(p, start[p.name]) for p in SOIL_ROWS),
            *(parameter_var(p, p.default) for p in ROWS if p.fmu == GROUND_FMU), *GROUND_IO]


VARIABLES = {TERRAIN_FMU: terrain_variables, RIG_FMU: rig_variables,
             ROVER_FMU: rover_variables, GROUND_FMU: ground_variables}
"""Each FMU's variable list, by model name."""


_DERIVATIVE_QUANTITY = {"Length": "Velocity", "Velocity": "Acceleration",
                        "Angle": "AngularVelocity", "AngularVelocity": "AngularAcceleration",
                        "Time": None}


def continuous_states(model: str) -> tuple[str, ...]:
    """The continuous states of ``model``'s model-exchange interface, in the order of its state
    vector: the terrain's wheel angle and plastic sinkage; the rig's states
    (:data:`wheelterrain.model.rig.RIG_STATES`, the very states its co-simulation step
    advances). Each is an output of the FMU."""
    if model == TERRAIN_FMU:
        return ("wheel_angle", "plastic_sinkage")
    if model == GROUND_FMU:
        return ()
    if model == ROVER_FMU:
        from wheelterrain.model import rover

        return rover.STATES
    from wheelterrain.model import rig

    return rig.RIG_STATES


def derivative_variables(model: str) -> list[Var]:
    """``der(<state>)`` for each continuous state: the local variables model exchange adds
    after the co-simulation variables (their value references follow)."""
    rows = {v.name: v for v in VARIABLES[model]()}
    out = []
    for name in continuous_states(model):
        state = rows[name]
        unit = state.unit[:-2] + "/s2" if state.unit.endswith("/s") else state.unit + "/s"
        unit = "1" if state.unit == "s" else unit  # a clock's rate
        out.append(Var(f"der({name})", "local", f"Time derivative of {name} (model exchange)",
                       unit, _DERIVATIVE_QUANTITY[state.quantity], derivative_of=name))
    return out


def units() -> dict[str, str]:
    """The unit (Modelica.Units.SI string) of every variable of both FMUs by name, parameters
    included, plus the master's ``time`` [s]: the units result files carry in their headers."""
    out = {"time": "s"}
    for v in (*terrain_variables(), *rig_variables(), *rover_variables(), *ground_variables()):
        out.setdefault(v.name, v.unit)
    return out
