"""The ``wheelterrain`` command line.

Exit codes: 0 success; 2 bad usage, unknown parameter or value out of range; 3 an operating point
the model cannot represent (e.g. a load the wheel cannot carry); 4 a numerical failure.
"""

from __future__ import annotations

import contextlib
import errno
import json
import math
import sys
import time

import click
import numpy as np

from wheelterrain import __version__, files, model, presets
from wheelterrain.cosim import ROVER_CONTROLLERS, ROVER_ENGINES
from wheelterrain.errors import (
    CalibrationError,
    CosimulationError,
    DataError,
    FMUError,
    InputError,
    LoadTooLargeError,
    ParameterError,
    UsageError,
    WheelTerrainError,
)
from wheelterrain.model import slip as slips
from wheelterrain.parameters import (
    DEG,
    ROWS,
    SLIP_ANGLE_LIMIT,
    TABLE,
    TURN_SLIP_LIMIT,
    parse_assignments,
    rover_lookup,
)

EXIT_USAGE, EXIT_INFEASIBLE, EXIT_NUMERICAL = 2, 3, 4
OUTPUT_ERRORS = {errno.ENOSPC, errno.EPIPE, errno.EIO, getattr(errno, "EDQUOT", errno.ENOSPC)}
"""Errors of writing output (a full disk or quota, a closed pipe): one line, not a traceback."""

EPILOG = """\b
Exit codes: 0 ok, 2 bad usage or parameter, 3 infeasible operating point, 4 numerical failure,
130 interrupted (Ctrl-C), 143 terminated (SIGTERM); an interrupted run writes none of its files.
Parameter names are those of `wheelterrain params`; they are also the FMU parameter names."""


def _fail(err: WheelTerrainError) -> None:
    """One line and the exit code of the error's kind: 2 what was asked (a parameter, an
    input, a file, an FMU of another version, a request that cannot be carried out), 3 an
    operating point the model cannot represent (a load it cannot carry, an FMU that refused a
    step of a run), 4 a numerical failure."""
    code = EXIT_NUMERICAL
    if isinstance(err, LoadTooLargeError | CosimulationError):
        code = EXIT_INFEASIBLE
    elif isinstance(err, ParameterError | InputError | CalibrationError | DataError
                    | UsageError | FMUError):
        code = EXIT_USAGE
    click.echo(f"error: {err}", err=True)
    sys.exit(code)


def _load(preset: str, assignments: tuple[str, ...]):
    try:
        return presets.load(preset).with_values(parse_assignments(assignments))
    except WheelTerrainError as err:
        _fail(err)


def json_option(what: str):
    """``--json [FILE]``, the same in every subcommand: ``what`` as one JSON document, to FILE,
    or to standard output (instead of the text) when no FILE is given."""
    return click.option(
        "--json", "json_target", is_flag=False, flag_value="-", default=None, metavar="[FILE]",
        help=f"{what} as JSON: to FILE (the text is still printed), or alone to standard "
             "output instead of the text. FILE's folder must exist.")


PROGRESS_LINES_EVERY = 10.0
"""s: where standard error is not a terminal (a log, a pipe), a progress line at most this often
(and at each stage's start and end); on a terminal, a bar."""


@contextlib.contextmanager
def _progress_bars():
    """``progress(stage, done, total)`` for the run layer: one progress bar per stage on
    standard error (a new stage ends the one before), each drawn to ``done`` of ``total``; in a
    log or a pipe, lines 'stage: 40 %' instead (a bar there shows only its label)."""
    current: dict = {}  # the stage, its bar and how far it is drawn
    terminal = sys.stderr.isatty()

    def say(text: str) -> None:
        with contextlib.suppress(OSError):
            click.echo(text, err=True)

    def close() -> None:
        if current:
            if terminal:
                current["bar"].__exit__(None, None, None)
            elif current["drawn"] < current["length"]:
                say(f"{current['stage']}: ended at {current['percent']:.0f} %")
            current.clear()

    def progress(stage: str, done: float, total: float) -> None:
        if current.get("stage") != stage:
            close()
            length = max(round(total), 1)
            current.update(stage=stage, drawn=0, length=length, said=time.monotonic(),
                           percent=0.0)
            if terminal:
                current["bar"] = click.progressbar(length=length, label=stage,
                                                   file=sys.stderr, show_pos=False)
                current["bar"].__enter__()
            else:
                say(f"{stage} ...")
        now = min(round(done), current["length"])
        if now > current["drawn"]:
            if terminal:
                current["bar"].update(now - current["drawn"])
            current["drawn"] = now
            current["percent"] = 100 * now / current["length"]
            due = time.monotonic() - current["said"] >= PROGRESS_LINES_EVERY
            if not terminal and (due or now == current["length"]):
                say(f"{stage}: {current['percent']:.0f} %")
                current["said"] = time.monotonic()

    try:
        yield progress
    finally:
        close()


def _usage_error(message: str) -> None:
    click.echo(f"error: {message}", err=True)
    sys.exit(EXIT_USAGE)


def _check_file_target(target: str | None, option: str = "--json") -> None:
    """Refuse, before any work, a file the command could not write at the end: its folder
    missing or not writable, or the path a folder. '-' (standard output) and None pass."""
    import os
    from pathlib import Path

    if target in (None, "-"):
        return
    path = Path(target)
    folder = path.parent
    if path.is_dir():
        _usage_error(f"{option} {target} is a folder; give a file name")
    if not folder.is_dir():
        _usage_error(f"{option} {target}: folder {folder} does not exist (it is not created)")
    if not os.access(folder, os.W_OK) or not _can_create_in(folder):
        _usage_error(f"{option} {target}: folder {folder} is not writable")


def _can_create_in(folder) -> bool:
    """Whether a file can really be created in ``folder`` (os.access says yes to root on a
    read-only or pseudo file system)."""
    import tempfile

    try:
        with tempfile.TemporaryFile(dir=folder):
            return True
    except OSError:
        return False


def slip_definition_option(what: str):
    """--slip-definition, one default for every command (slips.DEFAULT_DEFINITION)."""
    return click.option(
        "--slip-definition", type=click.Choice(slips.DEFINITIONS),
        default=slips.DEFAULT_DEFINITION, show_default=True,
        help=f"Which slip {what} is in. traction: i = (wR - V)/(wR), up to 1 (spinning); "
        "braking below 0, a locked wheel at -inf. paper: s = (wR - V)/V as in the source "
        "paper (C1-C4 are s = 0, 0.25, 0.5, 0.75), from -1 (a locked wheel); i = s/(1 + s). "
        "unified: the model's own, (wR - V)/max(wR, V), i driving and s braking, in [-1, 1].")


def _check_out_dir(out: str, option: str = "--out") -> None:
    """Refuse, before any work, an output folder the command could not create or write."""
    import os
    from pathlib import Path

    path = Path(out)
    if path.exists() and not path.is_dir():
        _usage_error(f"{option} {out} is a file, not a folder")
    existing = path
    while not existing.exists():  # the folder is created; its first existing ancestor decides
        existing = existing.parent
    if not existing.is_dir() or not os.access(existing, os.W_OK | os.X_OK):
        _usage_error(f"{option} {out}: {existing} is not a writable folder")
    try:  # created now, so that a folder that cannot be made fails before the run, not after
        path.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        _usage_error(f"{option} {out}: cannot create the folder ({err.strerror or err})")
    if path != existing:  # made here: removed again if the command ends having written nothing
        click.get_current_context().call_on_close(lambda: _remove_empty(path, existing))
    if not _can_create_in(path):
        _usage_error(f"{option} {out}: {path} is not a writable folder")


def _remove_empty(path, stop) -> None:
    """Remove ``path`` and its parents up to (not including) ``stop`` while they are empty
    folders: a refused or failed run leaves no empty output folder behind."""
    while path != stop:
        try:
            path.rmdir()  # only an empty folder
        except OSError:
            return
        path = path.parent


def _finite(value):
    """``value`` with every non-finite float as None (JSON has no NaN or infinity)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_finite(v) for v in value]
    return value


def _emit_json(target: str | None, document) -> bool:
    """Write ``document`` as JSON to ``target`` ('-': standard output; None: nothing). True when
    it went to standard output, where it replaces the text."""
    from pathlib import Path

    from wheelterrain.files import write_atomic

    if target is None:
        return False
    text = json.dumps(_finite(document), indent=2, allow_nan=False) + "\n"
    if target == "-":
        click.echo(text, nl=False)
        return True
    write_atomic(Path(target), text)
    return False


@click.group(epilog=EPILOG)
@click.version_option(__version__, prog_name="wheelterrain")
def main() -> None:
    """Wheel-terrain interaction of a grousered rover wheel on loose soil.

    \b
    Start here:
      wheelterrain params --preset paper-table2
      wheelterrain steady --slip 0.25 --slip-definition paper --load 62
    """


preset_option = click.option(
    "--preset", default=presets.DEFAULT_PRESET, show_default=True, metavar="NAME|FILE.json",
    help=f"Parameter preset: one of {', '.join(presets.available())}, or a preset JSON file.")
set_option = click.option(
    "--set", "assignments", multiple=True, metavar="NAME=VALUE",
    help="Override one parameter by its table name, SI units (angles also as e.g. 23deg). "
         "Repeatable.")


@main.command(epilog=EPILOG)
@preset_option
@set_option
@json_option("A list of parameter objects")
def params(preset: str, assignments: tuple[str, ...], json_target: str | None) -> None:
    """List every parameter: name, unit, value, valid range, description, source.

    First the wheel and soil (WheelTerrain.fmu; the value column is the preset's, after any
    --set), then the other FMUs' rows at their defaults: the single-wheel rig (rig.*,
    SingleWheelRig.fmu), the rover's chassis (rover.*, RoverChassis.fmu; `wheelterrain rover
    --set` changes them) and the terrain map (patch.*, Terrain.fmu). JSON rows carry name,
    unit, value, default, min, max, kind, description, source and fmu.
    """
    _check_file_target(json_target)
    ps = _load(preset, assignments)
    doc = presets.read(preset)
    fitted = doc.get("provenance", {}).get("fitted", {})
    terrain = {p.name for p in TABLE}
    others = [p for p in ROWS if p.name not in terrain]
    rows = [p.as_dict(ps[p.name]) for p in TABLE] + [p.as_dict() for p in others]
    for row in rows:
        if row["name"] in fitted:
            row["fitted"] = fitted[row["name"]]  # value, plausible range and its source, ...
    if _emit_json(json_target, rows):
        return
    click.echo(f"preset {doc.get('name', preset)}: {doc.get('description', '')}\n")
    def line(p, value: float) -> str:
        shown = f"{value:.6g}" + (f" ({value / DEG:.4g} deg)" if p.unit == "rad" else "")
        rng = f"[{p.min:g}, {p.max:g}]"
        return f"{p.name:30} {shown:>12} {p.unit:6} {rng:>24}  {p.description}"

    click.echo(f"{'name':30} {'value':>12} {'unit':6} {'range':>24}  description")
    for p in TABLE:
        click.echo(line(p, ps[p.name]))
    fmu = None
    for p in others:
        if p.fmu != fmu:
            fmu = p.fmu
            click.echo(f"\n{fmu}.fmu (defaults):")
        click.echo(line(p, p.default))
    if fitted:
        prov = doc["provenance"]
        click.echo(f"\nfitted on {', '.join(prov['fitted_on'])} ({prov['date_of_fit']}, "
                   f"{prov['code_version']}); value beside its plausible range:")
        for name, f in fitted.items():
            lo, hi = f["plausible_range"]
            scale, unit = (1 / DEG, " deg") if name == "soil.phi" else (1.0, "")
            flag = "  AT BOUND" if f.get("at_bound") else ""
            click.echo(f"  {name:30} {f['value'] * scale:10.5g}{unit}  [{lo * scale:g}, "
                       f"{hi * scale:g}]{flag}  ({f['range_source']})")
    readings = doc.get("provenance", {}).get("readings", {})
    if readings:
        click.echo("\nreadings of the source's symbols:")
        for name, text in readings.items():
            click.echo(f"  {name}: {text}")


@main.command(epilog=EPILOG)
@preset_option
@set_option
@click.option("--slip", required=True, type=float,
              help="Slip, in the definition chosen by --slip-definition.")
@slip_definition_option("--slip")
@click.option("--load", required=True, type=float, help="Vertical load on the wheel [N], >= 0.")
@click.option("--interval", is_flag=True,
              help="Also a 90 % interval for drawbar pull and sinkage: the soil values' spread "
                   "through the exact Jacobian, and the preset's model-form error on the "
                   "shipped data sets of other wheels (validation/DATA.md).")
@click.option("--slip-angle", "slip_angle_deg", type=float, default=None, metavar="DEG",
              help="Slip angle [deg] between the wheel's heading and its velocity (positive: "
                   "it moves toward its left; |angle| <= 80), --slip then the slip along its "
                   "heading: adds lateral_force [N] (the soil's force along the axle, positive "
                   "to the left), aligning_moment [N.m] (about the vertical through the "
                   "centre, positive counter-clockwise from above), lateral_shear_force and "
                   "side_bulldozing [N] (Ishigami et al. 2007's side force: lateral shear on "
                   "the rim and the side face's bulldozing), turning_moment [N.m] (the "
                   "soil's whole moment about that vertical) and overturning_moment [N.m] "
                   "(the lateral stresses' moment about the heading axis).")
@click.option("--turn-slip", "turn_slip", type=float, default=None, metavar="PER_M",
              help="Turn slip [rad/m]: the wheel's yaw rate over its forward speed (positive "
                   f"counter-clockwise from above; |turn slip| <= {TURN_SLIP_LIMIT:g}, a path "
                   "no tighter than 0.1 m), e.g. 2/track for a skid-steered rover's point "
                   "turn: adds the lateral outputs as --slip-angle, turning_moment [N.m] then "
                   "also the moment of the longitudinal shear across the tread's width that "
                   "resists the yawing.")
@json_option("One object (the contract's keys, with `preset`)")
def steady(preset: str, assignments: tuple[str, ...], slip: float, slip_definition: str,
           load: float, interval: bool, slip_angle_deg: float | None, turn_slip: float | None,
           json_target: str | None) -> None:
    """Quasi-static operating point: solve the sinkage that carries LOAD at SLIP.

    Prints sinkage [m], drawbar_pull [N], normal_force [N], torque [N.m], both slips, the entry,
    exit and max-stress angles [rad], gross thrust, compaction resistance, contact length and mean
    pressure; with --slip-angle or --turn-slip also the lateral force and moments. Values are
    grouser-period means (ripple-free) at zero sinkage rate.
    """
    _check_file_target(json_target)
    ps = _load(preset, assignments)
    limit = math.degrees(SLIP_ANGLE_LIMIT)
    if slip_angle_deg is not None and not (math.isfinite(slip_angle_deg)
                                           and abs(slip_angle_deg) <= limit):
        _usage_error(f"--slip-angle {slip_angle_deg:g}: valid range [-{limit:g}, {limit:g}] deg "
                     "(a wheel moving sideways has no heading to slip along)")
    if turn_slip is not None and not (math.isfinite(turn_slip)
                                      and abs(turn_slip) <= TURN_SLIP_LIMIT):
        _usage_error(f"--turn-slip {turn_slip:g}: valid range [-{TURN_SLIP_LIMIT:g}, "
                     f"{TURN_SLIP_LIMIT:g}] rad/m (the wheel's path no tighter than a 0.1 m "
                     "radius; a wheel yawing on the spot is outside the model)")
    beta = None if slip_angle_deg is None else math.radians(slip_angle_deg)
    try:
        result = model.steady_state(ps, load, slip, slip_definition, slip_angle=beta,
                                    turn_slip=turn_slip)
        if interval:
            from wheelterrain.fit import crosswheel, datasets

            result["interval"] = crosswheel.preset_interval(ps, load, result["slip"],
                                                            datasets.shipped())  # unified
    except WheelTerrainError as err:
        _fail(err)
    result = {"preset": preset, **result}
    if _emit_json(json_target, result):
        return
    click.echo(f"{'preset':22} {preset}")
    from wheelterrain.fmu.variables import units as variable_units

    shown = ("sinkage", "drawbar_pull", "normal_force", "torque", "gross_thrust",
             "compaction_resistance", "entry_angle", "exit_angle", "max_stress_angle",
             "contact_length", "mean_pressure", "load", "slip", "slip_paper", "capacity")
    table = {**variable_units(), "capacity": "N"}  # units of the FMU variables' table
    notes = {"slip": " (the model's: traction driving, skid braking)",
             "slip_paper": " (paper)"}
    for key in shown:
        value, unit = result[key], table[key] + notes.get(key, "")
        extra = f"   ({value / DEG:.3f} deg)" if unit == "rad" else ""
        extra = f"   ({value * 1e3:.3f} mm)" if key == "sinkage" else extra
        click.echo(f"{key:22} {value:14.6g} {unit}{extra}")
    if "slip_angle" in result:
        lateral = {"slip_angle": "rad", "turn_slip": "rad/m", "lateral_force": "N",
                   "aligning_moment": "N.m", "turning_moment": "N.m",
                   "overturning_moment": "N.m",
                   "lateral_shear_force": "N", "side_bulldozing": "N"}
        for key, unit in lateral.items():
            extra = f"   ({result[key] / DEG:.3f} deg)" if unit == "rad" else ""
            click.echo(f"{key:22} {result[key]:14.6g} {unit}{extra}")
    for key, (lo, hi) in result.get("interval", {}).items():
        click.echo(f"{key + ' 90 %':22} [{lo:.6g}, {hi:.6g}] {table[key]}")



def _slip_list(text: str) -> list[float]:
    """``--slip`` of multipass: one slip or several, comma-separated."""
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        values = []
    if not values or not all(math.isfinite(v) for v in values):
        _usage_error(f"--slip {text!r}: give a slip or a comma-separated list (0.1,0.3,0.5)")
    return values


@main.command(epilog=EPILOG)
@preset_option
@set_option
@click.option("--slip", "slip_text", required=True, metavar="S[,S...]",
              help="Slip of every pass, in the definition chosen by --slip-definition; a "
                   "comma-separated list runs the passes at each.")
@slip_definition_option("--slip")
@click.option("--load", default=62.0, show_default=True, type=float,
              help="Vertical load on the wheel [N] (the rig's 62 N by default).")
@click.option("--passes", default=5, show_default=True, type=click.IntRange(1, 100),
              help="Passes over the same strip (Tanaka et al. ran five with the Rashid wheel).")
@click.option("--compare", "compare", multiple=True, metavar="NAME=VALUE",
              help="Run the passes again with this assignment added (repeatable), printed "
                   "after the first and drawn dashed: e.g. --compare model.rut_shear=0 shows "
                   "what the shear a rut remembers changes.")
@click.option("--scm-reference", "scm", is_flag=True,
              help="Add the independent reference: the Soil Contact Model's node law "
                   "(elastic reloading up to the pressure a node carried, the "
                   "pressure-sinkage law beyond, its shear displacement kept by the share "
                   "model.rut_shear) on a discretised rim of the same wheel and soil; driving "
                   "slips 0 <= i < 1.")
@click.option("--out", default="validation/output", show_default=True,
              type=click.Path(file_okay=False), help="Folder for multipass.png.")
@json_option('One object {"preset", "load", "soil_memory", "rut_shear", "runs": [{"slip", '
             '"slip_paper", "passes": [{"pass", "traction_coefficient", "sinkage", "rut_left", '
             '...}]}], "units"}; with --compare also "compare": {"set", "rut_shear", "runs"}; '
             'with --scm-reference also "scm_reference": {"runs": [{"slip", "passes": [{"pass", '
             '"traction_coefficient", "sinkage", "sinkage_increment", ...}]}]}')
def multipass(preset: str, assignments: tuple[str, ...], slip_text: str, slip_definition: str,
              load: float, passes: int, compare: tuple[str, ...], scm: bool, out: str,
              json_target: str | None) -> None:
    """The single-wheel rig run PASSES times over the same strip: per pass, the traction
    coefficient (drawbar pull / load), the sinkage from the original surface and the rut left.

    Each pass is the rig's quasi-static operating point (as `wheelterrain steady`) on the
    rut the pass before left (soil.rut_depth): with model.soil_memory = 1 (the default) the
    soil is elastic-plastic, it answers elastically up to the pressure it has carried and
    along the pressure-sinkage law beyond, and the wheel's contact begins at the rut's
    surface; with 0 every pass meets virgin soil. A pass counts its shear displacement on
    from the share model.rut_shear of the displacement the pass before left (default 1, all
    of it, as the Soil Contact Model's node keeps it: every later pass pulls more per
    newton); with 0 each pass starts its shear afresh and later passes pull less (their
    contact from the rut's surface is short). --scm-reference adds the independent
    reference: SCM's node law on a discretised rim, same wheel and soil (drawn dotted).
    The soil's constants are the virgin soil's in every pass: no cited rule for how a pass
    compacts a soil (density, modulus, strength) is applied. Writes OUT/multipass.png.
    """
    from pathlib import Path

    from wheelterrain import plots
    from wheelterrain.model import multipass as mp

    _check_file_target(json_target)
    _check_out_dir(out)
    slips_given = _slip_list(slip_text)
    ps = _load(preset, assignments)
    other = _load(preset, assignments + compare) if compare else None

    def passes_at_each_slip(params) -> list[dict]:
        runs = []
        for s in slips_given:
            rows = mp.run(params, load, s, passes, slip_definition)
            sigma = slips.to_unified(s, slip_definition)
            runs.append({"slip": sigma, "slip_paper": slips.paper_from_unified(sigma),
                         "passes": rows})
        return runs

    if scm:  # refused before any pass is run
        for s in slips_given:
            try:
                sigma = slips.to_unified(s, slip_definition)
            except WheelTerrainError as err:
                _fail(err)
            if not 0 <= sigma < 1:
                _usage_error(f"--scm-reference takes driving slips (0 <= i < 1); slip {s:g} "
                             f"is {sigma:g} in the model's definition")

    def scm_reference() -> list[dict]:
        from wheelterrain.fit import scm_reference as scm_law

        out = []
        for s in slips_given:
            sigma = slips.to_unified(s, slip_definition)
            try:
                rows = scm_law.passes(ps, load, sigma, passes)
            except ValueError as err:
                _fail(WheelTerrainError(f"the SCM reference at slip {s:g}: {err}"))
            out.append({"slip": sigma, "slip_paper": slips.paper_from_unified(sigma),
                        "passes": rows})
        return out

    try:
        runs = passes_at_each_slip(ps)
        compared = passes_at_each_slip(other) if compare else None
    except WheelTerrainError as err:
        _fail(err)
    reference = scm_reference() if scm else None
    document = {"preset": preset, "set": list(assignments), "load": load,
                "soil_memory": int(ps["model.soil_memory"]),
                "rut_shear": ps["model.rut_shear"], "runs": runs, "units": mp.UNITS}
    if compare:
        document["compare"] = {"set": list(compare), "rut_shear": other["model.rut_shear"],
                               "runs": compared}
    if reference is not None:
        document["scm_reference"] = {"runs": reference}
    with files.one_set(Path(out)) as staging:
        plots.multipass(runs, staging / "multipass.png",
                        f"{preset}, {load:g} N" + (f", {' '.join(assignments)}"
                                                    if assignments else ""),
                        (" ".join(compare), compared) if compare else None, reference)
    if _emit_json(json_target, document):
        return
    for label, params, of in (("", ps, runs), (" ".join(compare), other, compared)):
        if of is None:
            continue
        click.echo(f"multi-pass, preset {preset}, load {load:g} N"
                   + (f", compared: {label}" if label else "") + ", soil memory "
                   f"{'on' if params['model.soil_memory'] == 1 else 'off'}, rut shear "
                   f"{params['model.rut_shear']:g}")
        _multipass_table(of)
    if reference is not None:
        click.echo("the SCM reference (node law on a discretised rim, same wheel and soil, shear "
                   f"share {ps['model.rut_shear']:g})")
        _multipass_table(reference)
    click.echo(f"wrote {Path(out) / 'multipass.png'}")


def _multipass_table(runs: list[dict]) -> None:
    for run in runs:
        click.echo(f"slip {run['slip']:g} (the model's; paper {run['slip_paper']:.4g})")
        click.echo(f"  {'pass':>4}  {'pull/load':>9}  {'pull [N]':>8}  {'sinkage [mm]':>12}  "
                   f"{'increment [mm]':>14}  {'rut left [mm]':>13}  {'its p [kPa]':>11}  "
                   f"{'torque [N.m]':>12}")
        for r in run["passes"]:
            pressure = (f"{r['rut_pressure_left'] * 1e-3:11.3f}" if "rut_pressure_left" in r
                        else f"{'-':>11}")  # the SCM reference keeps no rut pressure row
            click.echo(f"  {r['pass']:4d}  {r['traction_coefficient']:9.4f}  "
                       f"{r['drawbar_pull']:8.3f}  {r['sinkage'] * 1e3:12.3f}  "
                       f"{r['sinkage_increment'] * 1e3:14.3f}  {r['rut_left'] * 1e3:13.3f}  "
                       f"{pressure}  {r['torque']:12.4f}")


@main.command(epilog=EPILOG)
@preset_option
@set_option
@click.option("--system", type=click.Choice(["rig", "rover"]), default="rig", show_default=True,
              help="The paper's single-wheel rig (at --cases), or the rover (on --slope), its "
                   "rear wheels in the front wheels' ruts.")
@click.option("--cases", default="C1,C2,C3,C4", show_default=True, metavar="C1[,C2...]",
              help="The rig's cases (the paper's Table III: its slip 0, 0.25, 0.5, 0.75).")
@click.option("--gravity", type=click.Choice(["earth", "moon"]), default="earth",
              show_default=True, help="The rover's gravity.")
@click.option("--slope", default=0.0, show_default=True, type=click.FloatRange(-45.0, 45.0),
              metavar="DEG",
              help="The rover's slope [deg]: a steady climb (> 0) or descent (< 0), started in "
                   "its steady motion there; 0: level ground, from rest.")
@click.option("--stop", default=None, type=click.FloatRange(0.5, 120.0),
              help="Seconds of the run (default: 4 for the rig, from rest in the soil at "
                   "10 mm; 20 for the rover, from 1 mm in the soil on level ground: its rear "
                   "wheels reach the front wheels' ruts at about 13 s).")
@json_option('One object {"system", "preset", "set", "stop", "runs": [{"case" (rig), "motor", '
             '..., "residual", "relative_residual"}], "units"}')
def energy(preset: str, assignments: tuple[str, ...], system: str, cases: str, gravity: str,
           slope: float, stop: float | None, json_target: str | None) -> None:
    """Where the motor's energy goes: the work of every power term over a run, the system in
    continuous time on the contact with the soil's memory (its FMUs' model exchange, CVODES).

    \b
    supplied: motor (the wheel motors' work); load (the rig's load as the wheel sinks) or
              gravity (the rover's weight: its sinking, its climbing)
    spent:    kinetic (spin, heave, pitch, travel gained); pull (the work the rig's wheel
              does on the carriage) or towing (against the rover's holding force); slip (the
              shear stresses' work against the slip); compaction and bulldozing (the
              resistances times the travel); damping (the contact damper); pressing (the soil
              pressed vertically)
    The two sides agree to the integration's tolerance; `residual` says by how much. The
    rover runs with the rut profiles, as it is simulated (its JSON says "ruts": true); each
    wheel's soil terms count its own axle's speed (the chassis' and its pitch rate's share).
    """
    from wheelterrain.cosim import energy as ledger
    from wheelterrain.cosim import master
    from wheelterrain.parameters import GRAVITY

    _check_file_target(json_target)
    slips_of = {c["case"]: c["slip_paper"] for c in master.table3()["cases"]}
    chosen = [c.strip().upper() for c in cases.split(",") if c.strip()]
    unknown = [c for c in chosen if c not in slips_of]
    if system == "rig" and (not chosen or unknown):
        _usage_error(f"--cases {cases!r}: choose among {', '.join(slips_of)}")
    if system == "rig" and slope != 0:
        _usage_error("--slope is the rover's (--system rover): the rig runs on level ground")
    ps = _load(preset, assignments)
    rows = []
    try:
        if system == "rig":
            stop = ledger.STOP if stop is None else stop
            for case in chosen:
                rows.append({"case": case, **ledger.rig_ledger(ps, slips_of[case], stop)})
            terms = ledger.TERMS
        else:
            import math

            stop = 20.0 if stop is None else stop
            where = "level" if slope == 0 else f"{slope:g} deg"
            rows.append({"case": f"{where}, {gravity}", **ledger.rover_ledger(
                ps, {"rover.gravity": GRAVITY[gravity]}, stop, slope=math.radians(slope))})
            terms = ledger.ROVER_TERMS
    except WheelTerrainError as err:
        _fail(err)
    except RuntimeError as err:  # CVODES gave up: the run left the model's domain
        click.echo(f"error: the {system}'s run could not be integrated ({str(err)[-300:]})",
                   err=True)
        sys.exit(EXIT_NUMERICAL)
    units = {k: "J" for k in terms} | {"residual": "J", "relative_residual": "1", "stop": "s",
                                       "final_sinkage": "m", "mean_drawbar_pull": "N",
                                       "slope_deg": "deg", "rut_met": "m"}
    document = {"system": system, "preset": preset, "set": list(assignments), "stop": stop,
                "runs": rows, "units": units}
    if _emit_json(json_target, document):
        return
    click.echo(f"energy over {stop:g} s, the {system}, preset {preset}"
               + (f", {' '.join(assignments)}" if assignments else "") + " [J, % of supplied]")
    click.echo(f"  {'term':11}" + "".join(f"{r['case']:>19}" for r in rows))
    for term in terms:
        cells = []
        for r in rows:
            supplied = sum(r[k] for k in terms if k in ledger.SUPPLIED)
            cells.append(f"{r[term]:10.4g} {100 * r[term] / supplied:6.2f} %")
        click.echo(f"  {term:11}" + "".join(f"{c:>19}" for c in cells))
    click.echo(f"  {'residual':11}" + "".join(f"{r['residual']:19.1e}" for r in rows))
    if system == "rig":
        click.echo(f"  {'pull [N]':11}" + "".join(f"{r['mean_drawbar_pull']:19.3f}"
                                                for r in rows) + "   (mean, last second)")


def _platforms(fmu) -> str:
    """" (linux64, win64)": the platforms an FMU has binaries for."""
    import zipfile

    with zipfile.ZipFile(fmu) as z:
        found = sorted({n.split("/")[1] for n in z.namelist()
                        if n.startswith("binaries/") and n.count("/") == 2})
    return f" ({', '.join(found)})" if found else ""


@main.command(epilog=EPILOG)
@click.option("--out", default="build", show_default=True, type=click.Path(file_okay=False),
              help="Directory for the FMUs (the native flavour goes to OUT/native).")
@click.option("--flavor", type=click.Choice(["pythonfmu", "native", "modelica", "all"]),
              default="pythonfmu", show_default=True,
              help="Which FMUs to build, or the Modelica library (all: every one).")
def build(out: str, flavor: str) -> None:
    """Build the FMUs: WheelTerrain, SingleWheelRig, RoverChassis and Terrain (a terrain map),
    or the WheelTerrain Modelica library.

    \b
    pythonfmu (OUT/): for Python hosts (fmpy); the host needs numpy and casadi, the
      wheelterrain package is bundled inside. Every table parameter is an FMU parameter.
    native (OUT/native/): CasADi-generated C of the same model in our own FMI 2.0
      wrapper; no Python at run time, for any FMI host (C masters, system simulators,
      ecos). Needs a C compiler to build; ships its C sources in sources/. Binaries for
      linux64 and, with the MinGW-w64 cross compiler (x86_64-w64-mingw32-gcc), win64.
    Both have the same modelDescription (names, units, structure). Try one alone:
      fmpy simulate build/WheelTerrain.fmu --output-file wheel.csv --start-values
        quasi_static true soil.phi 0.45
    modelica (OUT/WheelTerrain/): a Modelica library generated from the same CasADi
      Functions and parameter table: the contact as pure functions with derivatives,
      records, components on MSL flanges, examples with reference results. Its
      examples SteadyC2 and SlipRamp need no Modelica Standard Library; the rest need
      MSL 4.x on the MODELICAPATH. Try it with rumoca (pip install rumoca).
      Functions.External has the same functions as CasADi's C (Resources/C-Sources),
      compiled for linux64 and, with MinGW-w64, win64 (cached after the first build).
    """
    from pathlib import Path

    from wheelterrain.compiled import compiler as native_compiler
    from wheelterrain.fmu.build_native import build as build_native
    from wheelterrain.fmu.build_pythonfmu import build as build_pythonfmu
    from wheelterrain.fmu.toolchain import WIN64_CC, BuildError, cross_compiler

    try:
        paths = []
        if flavor in ("modelica", "all"):
            from wheelterrain.modelica import library

            notes: list[str] = []
            folder = library.write(Path(out), notes=notes,
                                   say=lambda message: click.echo(message, err=True))
            count = sum(1 for _ in folder.rglob("*.mo"))
            click.echo(f"wrote {folder} (Modelica library, {count} files; open "
                       f"{folder / 'package.mo'} in a Modelica tool)")
            for note in notes:
                click.echo(f"note: {note}", err=True)
        def say(message: str) -> None:  # each FMU and platform as it starts
            click.echo(f"{message} ...", err=True)

        if flavor in ("pythonfmu", "all"):
            paths += build_pythonfmu(out, say=say)
        # --flavor all builds what this machine can; --flavor native without a compiler is
        # an error (build_native says so)
        native = flavor == "native" or (flavor == "all" and native_compiler() is not None)
        if flavor == "all" and not native:
            click.echo("note: no C compiler (cc/gcc, or $CC) on PATH, so only the pythonfmu "
                       "FMUs were built; the native ones need one (Debian/Ubuntu: apt-get "
                       "install gcc)", err=True)
        if native:  # its descriptions from the pythonfmu FMUs just built, where they were
            paths += build_native(Path(out) / "native",
                                  reference_dir=Path(out) if flavor == "all" else None, say=say)
            if cross_compiler() is None:
                click.echo(f"note: no {WIN64_CC} on PATH, so the native FMUs have no win64 "
                           "binary (Debian/Ubuntu: apt-get install gcc-mingw-w64-x86-64)",
                           err=True)
        for path in paths:
            click.echo(f"wrote {path}{_platforms(path)}")
    except BuildError as err:
        click.echo(f"error: {err}", err=True)
        sys.exit(EXIT_USAGE)
    except OSError as err:  # e.g. --out in a read-only folder
        click.echo(f"error: cannot write to {out}: {err.strerror or err}"
                   f"{f' ({err.filename})' if err.filename else ''}", err=True)
        sys.exit(EXIT_USAGE)


@main.command(epilog=EPILOG)
@click.option("--preset", default=presets.DEFAULT_PRESET, show_default=True,
              metavar="NAME|FILE.json",
              help="Parameter preset (paper-table2 gives the paper's own model and values, "
              "nothing fitted, and adds the comparison with the paper's simulation).")
@set_option
@click.option("--fmu-dir", default=None, type=click.Path(file_okay=False),
              help="Where `wheelterrain build` wrote the FMUs. Default: the fastest built "
              "pair, build/native (native flavour) if `wheelterrain build --flavor all` or "
              "`--flavor native` wrote it, else build (pythonfmu flavour).")
@click.option("--workers", type=click.IntRange(1, 64), default=None,
              help="Processes running the four cases side by side (the results do not "
              "depend on it). Default: one per case, at most one per core.")
@json_option("The results (preset, the four cases' means beside the experiment and the "
             "paper's simulation, mean absolute errors)")
@click.option("--out", default="validation/output", show_default=True,
              type=click.Path(file_okay=False),
              help="Directory for the time-series CSVs, the PNG plots and the SSP files.")
@click.option("--step", default=1e-3, show_default=True, type=click.FloatRange(1e-5, 0.05),
              help="Communication step [s].")
@click.option("--stop", default=30.0, show_default=True, type=click.FloatRange(12.0, 3600.0),
              help="Simulated time per case [s] (averages start after 10 s).")
@click.option("--interface", type=click.Choice(["cs", "me"]), default="cs", show_default=True,
              help="cs: FMI co-simulation, each FMU steps itself. me: model exchange, the "
              "master integrates both FMUs' states (classical Runge-Kutta at --step); needs "
              "the native FMUs (build/native).")
def reproduce(preset: str, assignments: tuple[str, ...], fmu_dir: str | None,
              workers: int | None, json_target: str | None, out: str, step: float, stop: float,
              interface: str) -> None:
    """Reproduce the paper's C1-C4 by co-simulating the two FMUs.

    \b
    Each case: the rig drives the wheel at 3 cm/s rim speed with the carriage at
    3 cm/s/(1 + s), s = 0, 0.25, 0.5, 0.75, under 62 N. After a 10 s settling time the
    means are taken over whole grouser periods up to the stop time, and printed against
    the experiment and the paper's own simulation (Table III). Writes OUT/<case>.csv,
    OUT/<case>.png, OUT/means.png and OUT/<case>.ssp.
    \b
    Runs the fastest pair built (build/native, else build; --fmu-dir chooses), the cases
    in parallel processes (--workers), and says which pair and path it used.
    """
    from pathlib import Path

    from wheelterrain.cosim import master as cosim
    from wheelterrain.run import rig

    _check_file_target(json_target)
    _check_out_dir(out)
    ps = _load(preset, assignments)
    try:
        with _progress_bars() as progress:
            run = rig.reproduce(ps, preset, Path(out), None if fmu_dir is None else Path(fmu_dir),
                                interface, workers, step, stop, fitted=not assignments,
                                progress=progress)
    except FileNotFoundError as err:
        click.echo(f"error: {err}", err=True)
        sys.exit(EXIT_USAGE)
    except WheelTerrainError as err:
        _fail(err)
    processes = f"{run.workers} worker process{'es' if run.workers > 1 else ''}"
    click.echo(f"FMUs: {run.folder}, {run.flavour}; {processes}", err=True)
    if run.note:
        click.echo(f"note: {run.note}", err=True)
    name = preset if not assignments else f"{preset} with {' '.join(assignments)}"
    text = json_target != "-"  # --json alone: the JSON document replaces the text
    say = click.echo if text else (lambda *a, **k: None)
    how = "co-simulation" if interface == "cs" else "model exchange (RK4)"
    say(f"C1-C4 {how}, preset {name}, step {step:g} s, {stop:g} s per case "
        f"(wall time {run.elapsed:.1f} s, {run.folder}, {processes})")
    say(cosim.format_table(run.rows, run.mae))
    if run.in_sample_on:
        say(f"in-sample: {preset} was fitted on {', '.join(run.in_sample_on)}; its held-out "
            "errors are printed by `wheelterrain validate`")
    say(f"wrote {Path(out)}/C1..C4.csv, C1..C4.png, means.png, C1..C4.ssp")
    if json_target:  # the JSON document: replacing the text, or beside it in a file
        payload = {"preset": preset, "set": list(assignments), "interface": interface,
                   "step": step, "stop": stop,
                   "in_sample": bool(run.in_sample_on),
                   "averaging_windows": {r.case: list(r.window) for r in run.results},
                   "cases": [{"case": row["case"], "slip_paper": row["slip_paper"],
                              "drawbar_pull": row["drawbar_pull"],
                              "normal_force": row["normal_force"], "sinkage": row["sinkage"],
                              "experiment": {k: row[f"{k}_experiment"] for k in
                                             ("drawbar_pull", "normal_force", "sinkage")},
                              "paper_simulation": {k: row[f"{k}_paper_simulation"] for k in
                                                   ("drawbar_pull", "normal_force", "sinkage")}}
                             for row in run.rows],
                   "mean_absolute_error": run.mae,
                   "fmu_dir": str(run.folder), "workers": run.workers,
                   "wall_time_s": run.elapsed}
        _emit_json(json_target, payload)


@main.command(epilog=EPILOG)
@preset_option
@set_option
@click.option("--params", "free", required=True, metavar="NAME[,NAME...]",
              help="Parameters to fit, by table name (`wheelterrain params` lists them).")
@click.option("--cases", default="C1,C2,C3,C4", show_default=True, metavar="C1[,C2...]",
              help="Cases of the paper's Table III to fit to.")
@click.option("--starts", default=8, show_default=True, type=click.IntRange(1, 200),
              help="Starting points (the base preset, then random over the plausible box).")
@click.option("--seed", default=0, show_default=True, type=int, help="Seed of the starts.")
@click.option("--out", "out", type=click.Path(),
              help="Folder to write the fitted preset (values and provenance) into, as "
              "NAME.json (--name; created if needed). The earlier form, a FILE.json, still "
              "names the file.")
@click.option("--name", default="fitted", show_default=True, help="Name of the written preset.")
@click.option("--protocol", default=None, help="How the fit was chosen, for the preset's "
              "provenance (default: 'least squares on <cases>').")
@click.option("--profile", "profile_points", default=0, show_default=True,
              type=click.IntRange(0, 101), help="Profile each parameter at this many values "
              "across its plausible range (the others refitted): the identifiability measure "
              "where standard errors do not exist (no more residuals than parameters).")
@click.option("--outputs", default="drawbar_pull,sinkage", show_default=True,
              help="The measured quantities the fit matches. drawbar_pull alone asks how "
              "closely the model's pull-slip curve can follow the rig's at all, whatever the "
              "sinkage does (both are reported either way).")
@json_option("The fit (values, ranges, residuals, held-out errors, profiles)")
def calibrate(preset: str, assignments: tuple[str, ...], free: str, cases: str, starts: int,
              seed: int, out: str | None, name: str, protocol: str | None,
              profile_points: int, outputs: str, json_target: str | None) -> None:
    """Fit parameters to the rig's C1-C4 drawbar pull and sinkage by least squares.

    \b
    Exact CasADi Jacobians, bounds = physically plausible ranges (printed with their
    sources), several starts. Reports the fitted values beside their ranges, standard
    errors and correlations (when there are more residuals than parameters), the
    residual per case, and the held-out errors on the cases not fitted. Example, the
    paper's protocol (fit on C2, predict C1, C3, C4):
      wheelterrain calibrate --params soil.phi,soil.k_phi --cases C2
    """
    from pathlib import Path

    from wheelterrain.fit import calibration
    from wheelterrain.run import calibrate as calibrate_run

    _check_file_target(json_target)
    out_file = None
    if out:
        out_file = Path(out) if out.endswith(".json") else Path(out) / f"{name}.json"
        _check_out_dir(str(out_file.parent), "--out")
        if out_file.is_dir():
            _usage_error(f"--out {out} is a folder named like a JSON file")
    base = _load(preset, assignments)
    names = [n.strip() for n in free.split(",") if n.strip()]
    case_names = [c.strip() for c in cases.split(",") if c.strip()]
    matched = tuple(o.strip() for o in outputs.split(",") if o.strip())
    try:
        fit = calibrate_run.calibrate(base, preset, names, case_names, starts, seed, matched,
                                      profile_points, out_file, name, protocol)
    except WheelTerrainError as err:
        _fail(err)
    result, held, profiles = fit.result, fit.held_out, fit.profiles
    if not _emit_json(json_target, fit.document):
        click.echo(f"fit of {', '.join(names)} to the {' and '.join(result.outputs)} of "
                   f"{', '.join(case_names)} ({result.starts} starts, base preset {preset})")
        for n in names:
            lo, hi = result.bounds[n]
            unit = "deg" if n == "soil.phi" else ""
            scale = 1 / DEG if n == "soil.phi" else 1.0
            se = (result.standard_errors or {}).get(n)
            flag = "  AT BOUND" if n in result.at_bound else ""
            se_text = f" +- {se * scale:.3g}" if se is not None else ""
            click.echo(f"  {n:30} {result.values[n] * scale:12.5g}{se_text} {unit}  plausible "
                       f"[{lo * scale:g}, {hi * scale:g}]{flag}")
            click.echo(f"  {'':30} range: {calibration.PLAUSIBLE[n][2]}")
            if n in profiles:
                a, b = profiles[n]["interval"]
                click.echo(f"  {'':30} profile: within one unit of the best fit for "
                           f"[{a * scale:.4g}, {b * scale:.4g}] {unit}")
        if result.correlation is not None and len(names) > 1:
            click.echo("  correlation:")
            for k, n in enumerate(names):
                row = " ".join(f"{v:+.2f}" for v in result.correlation[k])
                click.echo(f"    {n:30} {row}")
        for title, rows in (("fitted", result.residuals), ("held out", held)):
            for case, r in rows.items():
                click.echo(f"  {title:8} {case}: drawbar pull error {r['drawbar_pull']:+.2f} N, "
                           f"sinkage error {1e3 * r['sinkage']:+.2f} mm")
    if fit.written:
        click.echo(f"wrote {fit.written}", err=True)


@main.command(epilog=EPILOG)
@preset_option
@set_option
@click.option("--fmu", default="build/WheelTerrain.fmu", show_default=True,
              type=click.Path(dir_okay=False), help="The WheelTerrain.fmu to sweep (either "
              "flavour).")
@click.option("--slip", default="0:0.75:7", show_default=True, metavar="GRID",
              help="Slip grid: a:b:n, a,b,c or a value.")
@slip_definition_option("the --slip grid")
@click.option("--slip-angle", "slip_angle_grid", default=None, metavar="GRID",
              help="Slip angles [deg] to sweep (the input slip_angle; |angle| <= 80), a grid "
                   "as --slip's: the CSV gains a slip_angle [rad] axis and the outputs "
                   "lateral_force and aligning_moment vary with it. Default: none (0).")
@click.option("--load", "load_grid", default="62", show_default=True, metavar="GRID",
              help="Vertical load grid [N].")
@click.option("--grid", "extra", multiple=True, metavar="NAME=GRID",
              help="A further axis over a table parameter, e.g. soil.phi=25deg:45deg:5. "
              "Repeatable.")
@click.option("--workers", default=0, show_default=True, type=click.IntRange(0, 512),
              help="Worker processes (0: one per core, 1: none).")
@click.option("--max-points", default=1_000_000, show_default=True,
              type=click.IntRange(1, None),
              help="Refuse a grid of more points (every row is held until the CSV is written).")
@click.option("--dask", "dask_address", metavar="ADDRESS|local",
              help="Run on a dask.distributed scheduler instead (or 'local' for a "
              "LocalCluster); workers need wheelterrain installed.")
@click.option("--out", default="validation/output", show_default=True,
              type=click.Path(), help="Folder for sweep.csv and sweep.png (created if needed). "
              "The earlier form, a FILE.csv, still names the CSV (the PNG beside it).")
def sweep(preset: str, assignments: tuple[str, ...], fmu: str, slip: str, slip_definition: str,
          slip_angle_grid: str | None, load_grid: str, extra: tuple[str, ...], workers: int,
          dask_address: str | None, max_points: int, out: str) -> None:
    """Sweep WheelTerrain.fmu (quasi-static mode, through fmpy) over slip, load and any table
    parameter, in parallel.

    \b
    Examples:
      wheelterrain sweep --slip 0:0.75:16 --load 30,62,90
      wheelterrain sweep --slip 0.25 --grid soil.phi=25deg:45deg:9 --grid soil.k_phi=80,800
      wheelterrain sweep --slip 0.2 --slip-angle 0:30:7        # the side force
      wheelterrain sweep --dask tcp://scheduler:8786 --slip 0:0.9:50 --load 10:100:50
    Writes one CSV row per point (the axes, the outputs, status ok|infeasible) and a plot of
    drawbar pull and sinkage against slip (or the longest axis), one line per other point;
    with more than one slip angle, the lateral force, aligning moment and pull against it.
    """
    from pathlib import Path

    from wheelterrain import plots
    from wheelterrain.cosim import sweep as sweeper

    csv_path = Path(out) if out.endswith(".csv") else Path(out) / "sweep.csv"
    _check_out_dir(str(csv_path.parent), "--out")
    if csv_path.is_dir():
        _usage_error(f"--out {out} is a folder named like a CSV file")
    ps = _load(preset, assignments)
    try:
        axes = {"slip": sweeper.parse_axis("slip", slip),
                "load": sweeper.parse_axis("load", load_grid)}
        if slip_angle_grid is not None:
            degrees = slip_angle_grid.replace("deg", "")  # degrees, with or without the unit
            axes["slip_angle"] = [math.radians(v) for v in
                                  sweeper.parse_axis("slip_angle", degrees)]
        for item in extra:
            name, sep, spec = item.partition("=")
            if not sep:
                raise ParameterError(item, "", "must be NAME=GRID")
            axes[name.strip()] = sweeper.parse_axis(name.strip(), spec)
        sweeper.check_axes(axes, slip_definition)
    except WheelTerrainError as err:
        _fail(err)
    total = int(np.prod([len(v) for v in axes.values()]))
    if total > max_points:  # every row is kept until the CSV is written
        _usage_error(f"the grid has {total:.3g} points, more than --max-points {max_points} "
                     f"(at ~1 ms a point per core that is {total / 3.6e6:.3g} core-hours, and "
                     f"about {total * 1e-6:.3g} GB of rows held in memory): a coarser grid, "
                     "several sweeps, or a higher --max-points")
    try:
        label = f"sweeping {total} point{'s' if total != 1 else ''}"
        with _progress_bars() as progress:  # drawn from the first points done
            done = [0]

            def advance(points: int) -> None:
                done[0] += points
                progress(label, done[0], total)

            rows = sweeper.run(Path(fmu), sweeper.base_values(ps), axes, slip_definition,
                               workers=workers, dask_address=dask_address, progress=advance)
    except FileNotFoundError as err:
        click.echo(f"error: {err}", err=True)
        sys.exit(EXIT_USAGE)
    except WheelTerrainError as err:
        _fail(err)
    sweeper.write_csv(csv_path, rows)
    bad = sum(r["status"] != "ok" for r in rows)
    if len(axes.get("slip_angle", ())) > 1:  # the side force against the slip angle
        x = "slip_angle"
    else:
        x = "slip" if len(axes["slip"]) > 1 else max(axes, key=lambda k: len(axes[k]))
    group = [k for k in axes if k != x and len(axes[k]) > 1]
    png = csv_path.with_suffix(".png")
    plots.sweep_curves(rows, x, group, png, f"WheelTerrain.fmu sweep, preset {preset} "
                       f"(slip: {slip_definition} definition)")
    click.echo(f"preset {preset}: wrote {csv_path} ({total} points, {bad} infeasible) and "
               f"{png}")


@main.command(epilog=EPILOG)
@click.option("--scenario", type=click.Choice(["nominal", "terrain-change", "free-carriage",
                                               "efficiency"]), default="nominal",
              show_default=True, help="What the controller faces (see above).")
@click.option("--plant", type=click.Choice(["fmu", "casadi"]), default="fmu", show_default=True,
              help="fmu: SingleWheelRig.fmu + WheelTerrain.fmu through fmpy; casadi: the same "
              "Functions in process.")
@click.option("--preset", default=presets.DEFAULT_PRESET, show_default=True,
              metavar="NAME|FILE.json", help="Soil and wheel of plant and model.")
@set_option
@click.option("--solver", type=click.Choice(["sqpmethod", "ipopt", "rti"]),
              default="sqpmethod", show_default=True,
              help="sqpmethod: CasADi's SQP with the qrqp QP solver, to convergence. rti: the "
              "real-time iteration, one Gauss-Newton QP per sample with the states condensed "
              "out, solved by DAQP: the fastest set-up (with --compiled, ~0.6 ms per solve on "
              "the nominal scenario, the same tracking); not for the efficiency scenario.")
@click.option("--compiled", is_flag=True, help="Generate and compile C for the prediction "
              "model and its Jacobian (15-80 s the first time, by host; cached per model "
              "version in $WHEELTERRAIN_CACHE or ~/.cache).")
@click.option("--iterations", default=None, type=click.IntRange(1, 1000),
              help="SQP iterations per sample, at most (default: the controller's own limit, "
              "mpc.Settings.max_iterations). 1 is sqpmethod's real-time iteration: one "
              "iteration from the shifted warm start (--solver rti takes the same step faster).")
@click.option("--memory", is_flag=True,
              help="Predict with the soil's memory: the plant's plastic sinkage a state of "
                   "the prediction, the yield smoothed over 0.01 mm (nominal slip RMS 4.1e-4 "
                   "on the memory plant, against 6.3e-3 without; in-sample: the smoothing "
                   "width was chosen on that scenario). Not yet for free-carriage and "
                   "efficiency (docs/mpc.md).")
@click.option("--horizon", default=30, show_default=True, type=click.IntRange(1, 500),
              help="Prediction intervals.")
@click.option("--interval", default=0.02, show_default=True, type=click.FloatRange(1e-3, 1.0),
              help="MPC interval [s]; a whole number of 1 ms plant steps.")
@click.option("--fmu-dir", default="build", show_default=True,
              type=click.Path(file_okay=False), help="Where `wheelterrain build` put the FMUs.")
@click.option("--out", default="validation/output/mpc", show_default=True,
              type=click.Path(file_okay=False), help="Directory for the plot and the CSV.")
@json_option("The figures (slip_rms_error, solve times, the plant, the preset, ...)")
def mpc(scenario: str, plant: str, preset: str, assignments: tuple[str, ...], solver: str,
        compiled: bool, iterations: int | None, memory: bool,
        horizon: int, interval: float, fmu_dir: str, out: str, json_target: str | None) -> None:
    """Slip-control NMPC in closed loop: the CasADi twin drives the wheel on the rig.

    \b
    The controller predicts with the full contact model (the FMUs' own Functions, grouser
    ripple included) and commands the wheel speed to the drive's speed loop; limits on
    motor torque, power and sinkage. Scenarios:
      nominal         slip reference 0.2, then 0.35 at 3 s
      terrain-change  at 2 s soil.phi -15 %, soil.k_phi +20 %; an EKF re-estimates both
      free-carriage   a rover wheel: the carriage is free, towing its steady drawbar pull
      efficiency      maximise drawbar pull per unit of motor power instead of tracking
    Prints slip_rms_error (after each transient), solve_time_median_s, solve_time_p90_s and
    more; writes OUT/<scenario>.png (slip, reference, torque, sinkage, drawbar pull, solve
    time) and OUT/<scenario>.csv. Try: wheelterrain mpc --plant casadi --scenario efficiency,
    or the fastest controller: wheelterrain mpc --compiled --solver rti

    
    The prediction is the soil without memory (smooth, for the optimiser) unless --memory.
    The plant's soil is the preset's: with model.soil_memory = 1 (the default) the grouser
    ripple digs the wheel in, a disturbance the memory-less prediction does not model
    (nominal slip RMS 6.3e-3; 4.1e-4 with --memory, in-sample; 5.2e-5 on the elastic soil,
    --set model.soil_memory=0; docs/mpc.md).
    """
    from pathlib import Path

    from wheelterrain import plots
    from wheelterrain.control import closed_loop
    from wheelterrain.control import mpc as mpc_module
    from wheelterrain.cosim import master as cosim

    _check_file_target(json_target)
    _check_out_dir(out)
    ps = _load(preset, assignments)
    the_scenario = closed_loop.SCENARIOS[scenario]
    if solver == "rti" and iterations not in (None, 1):
        _usage_error(f"--iterations {iterations} does not apply to --solver rti: the real-time "
                     "iteration takes one iteration per sample by definition; for more use "
                     "--solver sqpmethod")
    settings = mpc_module.Settings(horizon=horizon, interval=interval, solver=solver,
                                   compiled=compiled, objective=the_scenario.objective,
                                   memory=memory,
                                   max_iterations=iterations or
                                   mpc_module.Settings.max_iterations)
    try:
        settings.check()  # refused before the progress bar starts
        steps = round(the_scenario.duration / interval)
        with click.progressbar(length=steps, label=f"closed loop '{scenario}' ({plant} plant)",
                               file=sys.stderr) as bar:
            result = closed_loop.run(the_scenario, ps, plant, settings, Path(fmu_dir),
                                     progress=lambda _: bar.update(1))
    except (FileNotFoundError, FMUError, mpc_module.MPCError) as err:
        click.echo(f"error: {err}", err=True)
        sys.exit(EXIT_USAGE)
    except mpc_module.PlantError as err:
        click.echo(f"error: {err}", err=True)
        sys.exit(EXIT_NUMERICAL)
    figures = {**result.figures(the_scenario), "preset": preset, "set": list(assignments)}
    out_dir = Path(out)
    plots.closed_loop(result, the_scenario, out_dir / f"{scenario}.png")
    cosim.write_series(out_dir / f"{scenario}.csv", result.series, every=5,
                       units=closed_loop.record_units())
    if _emit_json(json_target, figures):
        return
    click.echo(f"NMPC '{scenario}' ({the_scenario.description}), preset {preset}"
               + (f" with {' '.join(assignments)}" if assignments else ""))
    for key, value in figures.items():
        text = f"{value:.4g}" if isinstance(value, float) else str(value)
        click.echo(f"  {key:34} {text}")
    click.echo(f"wrote {out_dir}/{scenario}.png, {out_dir}/{scenario}.csv")


@main.command(epilog=EPILOG)
@click.option("--scenario", required=True,
              type=click.Choice(["level", "slope", "soft-patch", "descent", "pull-test"]),
              help="What the rover does (see above).")
@click.option("--gravity", type=click.Choice(["earth", "moon"]), default="earth",
              show_default=True, help="Earth test bed (9.81 m/s2) or the Moon (1.62 m/s2).")
@click.option("--preset", default=presets.DEFAULT_PRESET, show_default=True,
              metavar="NAME|FILE.json", help="The wheels' and the soil's terrain parameters.")
@set_option
@click.option("--step", default=None, type=click.FloatRange(1e-4, 1e-2),
              help="Communication step [s] of every engine (halve it to check convergence). "
              "Default: the scenario's, 1 ms; 0.25 ms for the Moon's slope, descent and "
              "pull-test, which end in an instability that a force handed over one step late "
              "(libcosim, ecos) hastens.")
@click.option("--engine", type=click.Choice(ROVER_ENGINES),
              default="in-process", show_default=True,
              help="in-process: the chassis and contact Functions stepped together, compiled; "
              "fmus: RoverChassis.fmu + four WheelTerrain.fmu through fmpy, our master; "
              "libcosim, ecos, omsimulator, fmpy-ssp: Rover.ssp in those engines (omsimulator: "
              "OpenModelica's OMSimulator, its command-line tool on the PATH or in "
              "$OMSIMULATOR; fmpy-ssp: fmpy's own SSP runner; soft-patch adds four "
              "Terrain.fmu, the soil map's query points, which fmpy-ssp cannot start).")
@click.option("--controller", type=click.Choice(ROVER_CONTROLLERS), default="speed",
              show_default=True,
              help="speed: the four speed loops to the common rim speed; mpc: from 2 s on, the "
              "slip NMPC (real-time iteration) per wheel commands its speed, holding the "
              "steady level slip and speed (level and soft-patch, in process).")
@click.option("--band", is_flag=True,
              help="slope and descent, in process: also run the scenario at each end of the "
              "bands of the unmeasured values its limit depends on (soil.unloading_stiffness "
              "4e6 and 4e8 Pa/m, the grouser phases aligned, soil.damping halved and "
              "doubled), one at a time; the figures gain limit_band (six runs: minutes on "
              "the Moon).")
@click.option("--fmu-dir", default=None, type=click.Path(file_okay=False),
              help="Where the FMUs are (default: build/native if built, else build).")
@click.option("--out", default="validation/output/rover", show_default=True,
              type=click.Path(file_okay=False),
              help="Directory for the plot, the CSV and Rover-<scenario>.ssp.")
@json_option("One object (the contract: scenario, gravity, engine, simulated_time_s, "
             "wall_time_s, real_time_factor, wheels, and per scenario its predictions)")
def rover(scenario: str, gravity: str, preset: str, assignments: tuple[str, ...],
          step: float | None,
          engine: str, controller: str, band: bool, fmu_dir: str | None, out: str,
          json_target: str | None) -> None:
    """The Rashid rover on four wheels: one scenario, its figures, a plot and a CSV.

    \b
    The chassis (rigid, in the vertical plane: position, heave, pitch; four rigidly mounted
    wheels, a speed loop each) and the four wheel-soil contacts of the one CasADi core: stepped
    together in process (compiled C where a compiler is available), or as RoverChassis.fmu and
    four WheelTerrain.fmu in our master, libcosim or ecos (--engine); on soft-patch each
    wheel's soil comes from a Terrain.fmu at the wheel's position. Scenarios:
      level       steady traverse at the commanded rim speed: per-wheel slip, sinkage, load
      slope       the slope rises until the rover stalls (slip 0.95), beside the predicted
                  stall slope (traction limit, or loss of stability of the steady motion)
      soft-patch  a looser soil under the front, then the rear axle: the transients
      descent     20 deg downhill, the speed loops braking, beside the predicted limit
      pull-test   a resisting force rising slowly: the rover's pull-slip curve, beside the
                  sum of four single-wheel curves at the axle loads
    --controller mpc: traction control, an NMPC per wheel (slip and speed held at the steady
    level motion); the figures then include slip_rms and speed_rms_relative, which the speed
    loops' run of the same scenario also reports.
    --set changes the terrain (soil, wheel, model) and the chassis (rover.*) parameters.
    Writes OUT/<scenario>-<gravity>.png and .csv, and OUT/Rover-<scenario>.ssp (the FMUs,
    their connections, the scenario's parameters, its slope and towing ramps included as the
    chassis' input profile) where the FMUs are built.
    """
    from pathlib import Path

    from wheelterrain.run import rover as rover_run

    _check_file_target(json_target)
    _check_out_dir(out)
    rover_items = [a for a in assignments if a.strip().startswith("rover.")]
    try:
        chassis_values = parse_assignments(rover_items, find=rover_lookup)
    except WheelTerrainError as err:
        _fail(err)
    ps = _load(preset, tuple(a for a in assignments if a not in rover_items))
    request = rover_run.Request(scenario, ps, gravity, chassis_values, step, engine, controller,
                                band)
    try:
        with _progress_bars() as progress:
            outcome = rover_run.run(request, Path(out), None if fmu_dir is None else Path(fmu_dir),
                                    preset, progress)
    except WheelTerrainError as err:
        _fail(err)
    except ValueError as err:  # an MPC setting
        click.echo(f"error: {err}", err=True)
        sys.exit(EXIT_USAGE)
    figures, out_dir = outcome.figures, Path(out)
    stem = outcome.written[0].stem
    ssp_path, folder = outcome.ssp, outcome.fmu_folder
    if _emit_json(json_target, figures):
        return
    click.echo(f"rover '{scenario}' ({gravity}), preset {preset}, {figures['engine']}: "
               f"{figures['simulated_time_s']:.1f} s simulated at a {figures['step_s'] * 1e3:g} ms "
               f"step in {figures['wall_time_s']:.2f} s ({figures['real_time_factor']:.3g}x real "
               "time)")
    if figures.get("left_domain"):
        click.echo(f"  stopped {figures['left_domain']}")
    click.echo(f"  {'wheel':12} {'slip':>8} {'sinkage [mm]':>13} {'load [N]':>9} "
               f"{'pull [N]':>9} {'power [W]':>10} {'rut [mm]':>9} {'peak [mm]':>10}   "
               f"(means from {figures['averaged_from_s']:g} s)")
    for w in figures["wheels"]:
        if w["mean_slip"] is None:
            click.echo(f"  {w['name']:12} (the run ended before the averaging window)")
            continue
        peak = "" if w["peak_sinkage"] is None else f"{1e3 * w['peak_sinkage']:10.3f}"
        click.echo(f"  {w['name']:12} {w['mean_slip']:8.4f} {1e3 * w['mean_sinkage']:13.3f} "
                   f"{w['mean_normal_force']:9.3f} {w['mean_drawbar_pull']:9.3f} "
                   f"{w['mean_motor_power']:10.4f} {1e3 * w['rut_depth']:9.3f} {peak}")
    for key in ("stall_slope_deg", "predicted_stall_slope_deg", "predicted_stall_limit",
                "slide_slope_deg", "predicted_descent_limit_deg", "predicted_descent_limit",
                "locked_limit_deg", "stall_cause",
                "stall_towing_force", "pull_curve_max_error_n", "slip_reference", "slip_rms",
                "speed_reference", "speed_rms_relative", "solve_time_median_s",
                "failed_solves"):
        if key in figures:
            value = figures[key]
            click.echo(f"  {key:30} {value:.4g}" if isinstance(value, float)
                       else f"  {key:30} {value}")
    if figures.get("predicted_stability_mode"):
        m = figures["predicted_stability_mode"]
        click.echo(f"  {'predicted_stability_mode':30} {m['leading']} grows at "
                   f"{m['growth_rate_per_s']:.3g} 1/s, {m['frequency_hz']:.3g} Hz"
                   + (" (a divergence, no oscillation)" if m["frequency_hz"] == 0 else ""))
    if figures.get("limit_band"):
        b = figures["limit_band"]
        span = "none" if b["low"] is None else f"{b['low']:.2f} .. {b['high']:.2f} deg"
        click.echo(f"  limit band (unmeasured values, one at a time): {span}"
                   + (f", {b['without_limit']} run(s) without a limit" if b["without_limit"]
                      else ""))
        for r in b["runs"]:
            limit = "none" if r["limit_deg"] is None else f"{abs(r['limit_deg']):.2f} deg"
            click.echo(f"    {r['variant']:15} {limit} ({r['cause']})")
    if figures.get("slip_vs_slope"):
        rows = figures["slip_vs_slope"]
        click.echo("  slip vs slope (four wheels' means over 1 s from each whole degree):")
        click.echo("    " + " ".join(f"{r['slope_deg']:6.0f}" for r in rows) + "  deg")
        click.echo("    " + " ".join(f"{r['mean_slip']:6.3f}" for r in rows) + "  slip")
        click.echo("    " + " ".join(f"{1e3 * r['mean_sinkage']:6.2f}" for r in rows) + "  mm")
    click.echo(f"wrote {out_dir}/{stem}.png, {out_dir}/{stem}.csv"
               + (f", {ssp_path}" if ssp_path else
                  f" (no Rover-{scenario}.ssp: the FMUs are not built in {folder})"))


@main.command(epilog=EPILOG)
@json_option('One object {"rows": [...]} (the README\'s contract)')
@click.option("--starts", default=4, show_default=True, type=click.IntRange(1, 64),
              help="Starting points of each fit (the unfitted preset, then random).")
@click.option("--data", "data_file", type=click.Path(dir_okay=False), default=None,
              help="Your own single-wheel tests (CSV, format below): every shipped model form "
                   "predicts them, fitted on the shipped data sets only.")
def validate(json_target: str | None, starts: int, data_file: str | None) -> None:
    """Prediction protocols: every shipped preset held out, beside a straight line, and every
    model form held out data set by data set.

    \b
    Rows (drawbar-pull MAE [N], sinkage MAE [mm]; held-out unless marked in-sample):
      line              y = a + b*s in the paper's slip: the baseline to beat
      PRESET all-case   the preset as shipped on C1-C4 (in-sample if fitted on them)
      PRESET c2-only    the paper's protocol: phi and n0 fitted on C2, judged on C1, C3, C4
      PRESET leave-one-out  the preset's own free parameters refitted without each case
      PRESET transfer   Ding et al. 2011's wheels and soil (80 N), the preset's model form,
                        that soil's own values, nothing refitted
      FORM nested       the headline, first: for each data set of validation/DATA.md
                        held out, a rule written once picks the form (and so its mechanisms)
                        on the other data sets alone (each candidate held out in turn among
                        them; the lowest mean pull/W wins), that form is fitted on them and
                        predicts the held-out set with its own soil values; beside it, under
                        the same protocol, the two baselines: classical Wong-Reece and the line
      FORM leave-data-out  each form's global constants fitted on every other data set,
                        judged on the one left out: forms compared with every set in view
                        (picking the best of these rows is not a held-out figure)
    Every cross-wheel row gives pull/W and z/R beside N and mm, the sinkage gained from the
    set's lowest slip (no datum needed: where a rig zeroed its sensor at rest, the datum is
    inferred), and the share of its points inside their 90 % interval (the soil values'
    spread, the form's errors on data sets it was not fitted to, learned inside the fold, and
    an inferred datum's uncertainty; nested, widened to every form the rule cannot tell from
    its choice). Below the rows: the rule against each baseline paired data set by data set
    (mean difference, its standard error, a verdict at 95 %), and an oracle that picks the
    best form per data set with hindsight: the most these forms could gain on the line.
    Folds start from the preset as it was before its own fit, so no held-out case reaches a
    fit. Takes under a minute on a 2-core machine (the nested rule fits 6 candidates in 5
    inner folds of each of 7 outer ones; a fit asked for again is remembered, not redone).

    \b
    --data FILE.csv: '#' comment lines, a header, one row per test point. Columns (SI; a
    header may carry its unit in brackets, e.g. 'load [N]'):
      wheel.radius, wheel.width, grouser.height, grouser.count, load, slip (traction),
      drawbar_pull, sinkage, optional torque, optional dataset (groups rows), optional case,
      optional sinkage_from: surface (the default: from the undisturbed soil) or rest (from
      the wheel resting under its load: the static sinkage zeroed, as a rig reports it that
      zeroes its sensor after placing the wheel; compared as the prediction less its sinkage
      at zero slip);
      soil.n0, soil.cohesion, soil.phi [rad], soil.gamma, soil.shear_modulus, and
      soil.k_c + soil.k_phi (Reece) or bekker.k_c [N/m^(n+1)] + bekker.k_phi [N/m^(n+2)];
      optional sd.<soil column>: its standard deviation; optional soil_source: where the soil
      values come from (measured, table-i, sourcebook-nominal; one per data set);
      optional slip_angle [rad] and lateral_force [N] (along the axle, positive to the
      wheel's left; slip is then the slip along the wheel's heading): each form's
      lateral_force_mae beside the baseline -W*tan(phi)*sin(beta).
    The shipped data set is in this format: wheelterrain/data/wheel_tests.csv.
    """
    from wheelterrain.fit import prediction

    _check_file_target(json_target)
    if data_file is not None:
        _validate_user_data(data_file, json_target, starts)
        return
    total, done = prediction.step_count(), [0]
    with _progress_bars() as progress:
        def advance(_row: str) -> None:
            done[0] += 1
            progress("prediction protocols", done[0], total)

        progress("prediction protocols", 0, total)
        result = prediction.run(progress=advance, starts=starts)
    if _emit_json(json_target, result):
        return
    click.echo(prediction.format_table(result))


def _validate_user_data(data_file: str, json_target: str | None, starts: int) -> None:
    """`validate --data`: every shipped form on the user's data sets."""
    from wheelterrain.fit import crosswheel, datasets, prediction

    try:
        user = datasets.read(data_file)
    except WheelTerrainError as err:
        _fail(err)
    shipped = datasets.shipped()
    with click.progressbar(length=len(crosswheel.FORMS), label="model forms",
                           file=sys.stderr) as bar:
        rows = crosswheel.user_rows(user, shipped, starts=min(starts, 3),
                                    progress=lambda _: bar.update(1))
    result = {"rows": rows, "data": data_file,
              "units": {"drawbar_pull_mae": "N", "sinkage_mae": "m",
                        "drawbar_pull_mae_per_load": "1", "sinkage_mae_per_radius": "1"}}
    result["beats_the_line"] = crosswheel.verdicts(rows)
    lateral = crosswheel.lateral_table(user, rows)
    if lateral:
        result["lateral"] = lateral
        result["units"]["lateral_force_mae"] = "N"
    result["sinkage_datum"] = crosswheel.datum_check(user)
    result["soil_sources"] = {ds.name: ds.soil_source for ds in user}
    forms = [r for r in rows if r["model"] != "line"]
    failed = [r for r in forms if r.get("error")]
    if not _emit_json(json_target, result):
        click.echo(prediction.format_table(result))
        for name, better in result["beats_the_line"].items():
            click.echo(f"{name}: " + (f"{', '.join(better)} beat the line on pull"
                                      if better else "no form beats the line on pull"))
        for name, lat in lateral.items():
            forms = ", ".join(f"{form} {mae:.3g}" if mae is not None else f"{form} (failed)"
                              for form, mae in lat["forms"].items())
            click.echo(f"{name}: lateral force MAE [N] over {lat['points']} point(s): "
                       f"baseline W*tan(phi)*sin(beta) {lat['baseline']:.3g}; {forms}")
    if forms and len(failed) == len(forms):  # nothing was predicted: not a result
        click.echo(f"error: no model form could predict {data_file}: {failed[0]['error']}",
                   err=True)
        sys.exit(EXIT_INFEASIBLE)


class _Terminated(BaseException):
    """SIGTERM, raised where the process is, so that every cleanup on the way out runs."""


def entry() -> None:
    """The console script: ``main`` with a clear line, not a traceback, when standard output
    cannot be written (a full disk, a closed pipe)."""
    import os
    import signal

    def terminated(signum, frame):  # SIGTERM: unwind, so temporary files and folders go
        raise _Terminated

    with contextlib.suppress(ValueError):  # not the main thread: keep the default
        signal.signal(signal.SIGTERM, terminated)
        # a forked pool worker, which its pool ends with SIGTERM, ends at once as before (a
        # Python handler would wait for the C call it is in, and print a traceback)
        os.register_at_fork(
            after_in_child=lambda: signal.signal(signal.SIGTERM, signal.SIG_DFL))
    try:
        code = main(standalone_mode=False)
    except _Terminated:
        with contextlib.suppress(OSError):
            click.echo("terminated", err=True)
        sys.exit(128 + signal.SIGTERM)
    except (click.exceptions.Abort, KeyboardInterrupt):  # Ctrl-C (click: Abort)
        click.echo("interrupted", err=True)
        sys.exit(128 + signal.SIGINT)  # the shell's convention: 130
    except click.ClickException as err:
        err.show()
        sys.exit(err.exit_code)
    except OSError as err:
        if err.errno not in OUTPUT_ERRORS:
            raise
        with contextlib.suppress(OSError):
            click.echo(f"error: cannot write the output: {err.strerror or err}", err=True)
        with contextlib.suppress(OSError):  # nothing more reaches the broken stream at exit
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        sys.exit(EXIT_USAGE)
    sys.exit(code if isinstance(code, int) else 0)


if __name__ == "__main__":  # pragma: no cover
    entry()
