"""The ``wheelterrain`` command line.

Exit codes: 0 success; 2 bad usage, unknown parameter or value out of range; 3 an operating point
the model cannot represent (e.g. a load the wheel cannot carry); 4 a numerical failure.
"""

from __future__ import annotations

import json
import math
import sys

import click

from . import __version__, model, presets
from .errors import InputError, LoadTooLargeError, ParameterError, WheelTerrainError
from .parameters import DEG, TABLE, parse_assignments

EXIT_USAGE, EXIT_INFEASIBLE, EXIT_NUMERICAL = 2, 3, 4

EPILOG = """\b
Exit codes: 0 ok, 2 bad usage or parameter, 3 infeasible operating point, 4 numerical failure.
Parameter names are those of `wheelterrain params`; they are also the FMU parameter names."""


def _fail(err: WheelTerrainError) -> None:
    code = EXIT_USAGE
    if isinstance(err, LoadTooLargeError):
        code = EXIT_INFEASIBLE
    elif not isinstance(err, ParameterError | InputError):
        code = EXIT_NUMERICAL
    click.echo(f"error: {err}", err=True)
    sys.exit(code)


def _load(preset: str, assignments: tuple[str, ...]):
    try:
        return presets.load(preset).with_values(parse_assignments(assignments))
    except WheelTerrainError as err:
        _fail(err)


def _json_number(x: float) -> float | None:
    return x if math.isfinite(x) else None


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
@click.option("--json", "as_json", is_flag=True, help="Print a JSON list of parameter objects.")
def params(preset: str, assignments: tuple[str, ...], as_json: bool) -> None:
    """List every parameter: name, unit, value, valid range, description, source.

    The value column is the preset's (after any --set). JSON rows carry name, unit, value, default,
    min, max, kind, description and source.
    """
    ps = _load(preset, assignments)
    rows = [p.as_dict(ps[p.name]) for p in TABLE]
    if as_json:
        click.echo(json.dumps(rows, indent=2))
        return
    doc = presets.read(preset)
    click.echo(f"preset {doc.get('name', preset)}: {doc.get('description', '')}\n")
    click.echo(f"{'name':30} {'value':>12} {'unit':6} {'range':>24}  description")
    for p in TABLE:
        value = ps[p.name]
        shown = f"{value:.6g}" + (f" ({value / DEG:.4g} deg)" if p.unit == "rad" else "")
        rng = f"[{p.min:g}, {p.max:g}]"
        click.echo(f"{p.name:30} {shown:>12} {p.unit:6} {rng:>24}  {p.description}")
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
@click.option("--slip-definition", type=click.Choice(["traction", "paper"]), default="traction",
              show_default=True,
              help="traction: i = (wR - V)/(wR). paper: s = (wR - V)/V as in the source paper "
                   "(C1-C4 are s = 0, 0.25, 0.5, 0.75); i = s/(1 + s).")
@click.option("--load", required=True, type=float, help="Vertical load on the wheel [N], >= 0.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object.")
def steady(preset: str, assignments: tuple[str, ...], slip: float, slip_definition: str,
           load: float, as_json: bool) -> None:
    """Quasi-static operating point: solve the sinkage that carries LOAD at SLIP.

    Prints sinkage [m], drawbar_pull [N], normal_force [N], torque [N.m], both slips, the entry,
    exit and max-stress angles [rad], gross thrust, compaction resistance, contact length and mean
    pressure. Values are grouser-period means (ripple-free) at zero sinkage rate.
    """
    ps = _load(preset, assignments)
    try:
        result = model.steady_state(ps, load, slip, slip_definition)
    except WheelTerrainError as err:
        _fail(err)
    result = {"preset": preset, **result}
    if as_json:
        out = {k: (_json_number(v) if isinstance(v, float) else v) for k, v in result.items()}
        click.echo(json.dumps(out, indent=2))
        return
    units = {"sinkage": "m", "drawbar_pull": "N", "normal_force": "N", "torque": "N.m",
             "gross_thrust": "N", "compaction_resistance": "N", "entry_angle": "rad",
             "exit_angle": "rad", "max_stress_angle": "rad", "contact_length": "m",
             "mean_pressure": "Pa", "load": "N", "slip": "1 (traction)",
             "slip_paper": "1 (paper)", "capacity": "N"}
    for key, unit in units.items():
        value = result[key]
        extra = f"   ({value / DEG:.3f} deg)" if unit == "rad" else ""
        extra = f"   ({value * 1e3:.3f} mm)" if key == "sinkage" else extra
        click.echo(f"{key:22} {value:14.6g} {unit}{extra}")


if __name__ == "__main__":  # pragma: no cover
    main()
