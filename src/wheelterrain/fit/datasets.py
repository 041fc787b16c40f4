"""Single-wheel test data: the shipped cross-wheel data set and users' own files, one format.

A file is ``#`` comment lines, then a CSV header, then one row per test point (the format of
``wheelterrain validate --data FILE.csv``; the shipped ``wheel_tests.csv`` is written in it, and
validation/DATA.md documents every data set in it). Columns, SI units only; a header name may
carry its unit in brackets (``load [N]``), which must then be the unit below:

- the wheel: ``wheel.radius`` [m], ``wheel.width`` [m], ``grouser.height`` [m], ``grouser.count``;
- the test: ``load`` [N], ``slip`` (traction slip i = (omega*R - V)/(omega*R)),
  ``drawbar_pull`` [N], ``sinkage`` [m], optional ``torque`` [N.m], optional ``dataset`` (groups
  rows; default ``user``) and ``case`` (a label), optional ``sinkage_from``: where the sinkage
  is measured from, ``surface`` (the undisturbed soil surface: the total sinkage; the default)
  or ``rest`` (the wheel resting on the soil under its load before it drives: the static
  sinkage zeroed, as a rig that zeroes its sinkage sensor after placing the wheel reports it);
- the soil, in the parameter table's names (``soil.n0``, ``soil.k_c``, ``soil.k_phi``,
  ``soil.cohesion`` [Pa], ``soil.phi`` [rad], ``soil.gamma`` [N/m3], ``soil.shear_modulus``
  [m]) or with the pressure-sinkage moduli in Bekker's form (``bekker.k_c`` [N/m^(n+1)],
  ``bekker.k_phi`` [N/m^(n+2)]), converted by :func:`reece_from_bekker`;
- optional spreads ``sd.<soil column>``: one standard deviation of that value, in its unit;
- optional ``soil_source``: where the soil values come from (:data:`SOIL_SOURCES`), one per
  data set.

An empty cell is "not given". Anything else that is wrong (a missing column, a value that is
not a number, a unit that is not the column's, a row without a complete soil) is one
:class:`DataError` naming the line.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass, field
from pathlib import Path

from wheelterrain import data
from wheelterrain.errors import DataError, WheelTerrainError
from wheelterrain.parameters import SLIP_ANGLE_LIMIT, lookup

SHIPPED = "wheel_tests.csv"
WHEEL_COLUMNS = ("wheel.radius", "wheel.width", "grouser.height", "grouser.count")
TEST_COLUMNS = ("load", "slip", "drawbar_pull", "sinkage")
SOIL_COMMON = ("soil.n0", "soil.cohesion", "soil.phi", "soil.gamma", "soil.shear_modulus")
REECE = ("soil.k_c", "soil.k_phi")
BEKKER = ("bekker.k_c", "bekker.k_phi")
UNITS = {"load": "N", "slip": "1", "drawbar_pull": "N", "sinkage": "m", "torque": "N.m",
         "slip_angle": "rad", "lateral_force": "N",
         "bekker.k_c": "N/m^(n+1)", "bekker.k_phi": "N/m^(n+2)", "dataset": "", "case": "",
         "sinkage_from": "", "soil_source": ""}
SOIL_SOURCES = {
    "measured": "measured on the tested soil, or on the same soil prepared to the same "
                "nominal density (validation/DATA.md says which)",
    "table-i": "the source paper's Table I (the collected soil's values)",
    "sourcebook-nominal": "c and phi measured; n, k_c, k_phi the Lunar Sourcebook's nominal "
                          "lunar-soil values (Carrier, Olhoeft & Mendell 1991, Table 9.28), "
                          "not a measurement of the tested soil",
    "unstated": "not said (a user's file without the column)",
}
"""Where a data set's soil values come from (the data column ``soil_source``), in words."""
SINKAGE_FROM = ("surface", "rest")
"""Where a measured sinkage is measured from: the undisturbed surface (total sinkage) or the
wheel at rest under its load (the static sinkage zeroed); see the module doc."""
DEFAULT_SPREAD = {
    "soil.phi": (0.0, 2.0 * math.pi / 180),
    "soil.cohesion": (0.3, 100.0),
    "soil.k_phi": (0.3, 0.0),
    "soil.k_c": (0.3, 0.0),
    "soil.n0": (0.0, 0.1),
    "soil.gamma": (0.05, 0.0),
    "soil.shear_modulus": (0.3, 0.0),
}
"""One standard deviation of a soil value where a data set states none, as (relative, absolute)
added in quadrature: friction angle 2 deg, cohesion 30 % + 100 Pa, moduli and K 30 %, exponent
0.1, density 5 %. This project's assumption of the repeatability of direct-shear and bevameter
tests on one prepared soil, not a measured figure (validation/DATA.md says so too)."""


@dataclass(frozen=True)
class Point:
    """One test point: the wheel, the soil (table names, Reece form), the test and its
    measurements (NaN where not given)."""

    dataset: str
    case: str
    values: dict[str, float]  # wheel and soil values in the table's names
    spread: dict[str, float]  # one standard deviation of soil values (table names)
    load: float
    slip: float
    drawbar_pull: float
    sinkage: float
    torque: float = math.nan
    sinkage_from: str = "surface"  # one of SINKAGE_FROM
    slip_angle: float = 0.0  # rad: between the wheel's heading and its velocity
    lateral_force: float = math.nan  # N: along the axle, positive to the wheel's left


@dataclass
class Dataset:
    name: str
    points: list[Point] = field(default_factory=list)
    soil_source: str = "unstated"  # one of SOIL_SOURCES


def reece_from_bekker(k_c: float, k_phi: float, n: float, width: float,
                      gamma: float) -> tuple[float, float]:
    """Bekker's p = (k_c/b + k_phi)*z**n as Reece's p = (c*k_c' + gamma*b*k_phi')*(z/b)**n at
    the wheel's width b: k_c' = 0 and k_phi' = (k_c/b + k_phi)*b**(n - 1)/gamma.

    Exact at that width (Reece 1965; Wong, *Theory of Ground Vehicles*, ch. 2), and it keeps the
    measured cohesion out of the pressure (Bekker's k_c does not scale with c)."""
    return 0.0, (k_c / width + k_phi) * width ** (n - 1) / gamma


def _split_header(name: str, line: int) -> tuple[str, str | None]:
    name = name.strip()
    if "[" in name:
        base, _, rest = name.partition("[")
        if not rest.endswith("]"):
            raise DataError(f"line {line}: header {name!r}: a unit goes in brackets, e.g. "
                            "'load [N]'")
        return base.strip(), rest[:-1].strip()
    return name, None


def _unit_of(column: str) -> str:
    if column.startswith("sd."):
        return _unit_of(column[3:])
    if column in UNITS:
        return UNITS[column]
    return lookup(column).unit


def _number(text: str, column: str, line: int) -> float:
    try:
        value = float(text)
    except ValueError:
        raise DataError(f"line {line}: {column} = {text!r} is not a number") from None
    if not math.isfinite(value):
        raise DataError(f"line {line}: {column} = {text!r} is not finite")
    return value


def parse(text: str, source: str = "data") -> list[Dataset]:
    """The data sets of a test-data file's ``text`` (see the module doc), in file order."""
    numbered = [(k + 1, line) for k, line in enumerate(text.splitlines())
                if line.strip() and not line.lstrip().startswith("#")]
    if not numbered:
        raise DataError(f"{source}: no header and no rows (only comments or empty lines)")
    header_line = numbered[0][0]
    reader = csv.reader(io.StringIO("\n".join(line for _, line in numbered)))
    rows = list(reader)
    columns = []
    for raw in rows[0]:
        name, unit = _split_header(raw, header_line)
        try:
            expected = _unit_of(name)
        except WheelTerrainError:
            raise DataError(f"line {header_line}: unknown column {name!r}; see "
                            "`wheelterrain validate --help` for the columns") from None
        if unit is not None and unit != expected:
            raise DataError(f"line {header_line}: column {name!r} is in [{expected}] "
                            f"(SI), not [{unit}]")
        columns.append(name)
    if len(set(columns)) != len(columns):
        raise DataError(f"line {header_line}: a column appears twice")
    required = (*WHEEL_COLUMNS, *TEST_COLUMNS, *SOIL_COMMON)
    missing = [c for c in required if c not in columns]
    if missing:
        raise DataError(f"line {header_line}: missing column(s) {', '.join(missing)}")
    if not (set(REECE) <= set(columns) or set(BEKKER) <= set(columns)):
        raise DataError(f"line {header_line}: the soil needs soil.k_c and soil.k_phi, or "
                        "bekker.k_c and bekker.k_phi")
    if len(rows) < 2:
        raise DataError(f"{source}: a header but no rows")
    sets: dict[str, Dataset] = {}
    for (line, _), row in zip(numbered[1:], rows[1:], strict=True):
        if len(row) != len(columns):
            raise DataError(f"line {line}: {len(row)} cells, the header has {len(columns)}")
        cells = {c: v.strip() for c, v in zip(columns, row, strict=True)}
        point = _point(cells, line)
        source = cells.get("soil_source") or "unstated"
        if source not in SOIL_SOURCES:
            raise DataError(f"line {line}: soil_source = {source!r}: one of "
                            f"{', '.join(SOIL_SOURCES)} (or empty)")
        ds = sets.setdefault(point.dataset, Dataset(point.dataset, soil_source=source))
        if ds.soil_source != source:
            raise DataError(f"line {line}: soil_source = {source!r}, but data set "
                            f"{point.dataset!r} said {ds.soil_source!r} before: one soil, one "
                            "source")
        ds.points.append(point)
    return list(sets.values())


def _point(cells: dict[str, str], line: int) -> Point:
    def get(column: str, required: bool = True) -> float:
        text = cells.get(column, "")
        if not text:
            if required:
                raise DataError(f"line {line}: {column} is empty")
            return math.nan
        return _number(text, column, line)

    values = {c: get(c) for c in (*WHEEL_COLUMNS, *SOIL_COMMON)}
    spread = {c[3:]: get(c, False) for c in cells if c.startswith("sd.soil.")}
    spread = {k: v for k, v in spread.items() if not math.isnan(v)}
    reece = [cells.get(c, "") for c in REECE]
    bekker = [cells.get(c, "") for c in BEKKER]
    if all(reece):
        values.update({c: get(c) for c in REECE})
    elif all(bekker):
        n, b, gamma = values["soil.n0"], values["wheel.width"], values["soil.gamma"]
        k_c, k_phi = (get(c) for c in BEKKER)
        if k_c / b + k_phi <= 0:
            raise DataError(
                f"line {line}: bekker.k_c/b + bekker.k_phi = {k_c / b + k_phi:g} N/m^(n+2) at "
                f"this wheel's width b = {b:g} m: no pressure under the wheel. A bevameter "
                "fit's negative k_c (KLS-1's is) holds only near the plate widths it was "
                "measured with")
        values["soil.k_c"], values["soil.k_phi"] = reece_from_bekker(k_c, k_phi, n, b, gamma)
        sd_c, sd_phi = (get("sd." + c, False) for c in BEKKER)
        parts = [(sd_c / b if not math.isnan(sd_c) else 0.0),
                 (sd_phi if not math.isnan(sd_phi) else 0.0)]
        if any(parts):
            spread["soil.k_phi"] = math.hypot(*parts) * b ** (n - 1) / gamma
    else:
        raise DataError(f"line {line}: the soil needs soil.k_c and soil.k_phi, or bekker.k_c "
                        "and bekker.k_phi, all filled in")
    for name, value in values.items():
        try:
            lookup(name).check(value)
        except WheelTerrainError as err:
            raise DataError(f"line {line}: {err}") from None
    load = get("load")
    if load <= 0:
        raise DataError(f"line {line}: load = {load:g} N must be > 0")
    slip = get("slip")
    if not -1 < slip < 1:
        raise DataError(f"line {line}: slip = {slip:g} must be a traction slip in (-1, 1)")
    datum = cells.get("sinkage_from") or "surface"
    if datum not in SINKAGE_FROM:
        raise DataError(f"line {line}: sinkage_from = {datum!r}: one of "
                        f"{', '.join(SINKAGE_FROM)} (or empty: surface)")
    _check_measured(line, values, load, get("drawbar_pull"), get("sinkage"),
                    get("torque", False), datum)
    beta, lateral = get("slip_angle", False), get("lateral_force", False)
    if not math.isnan(lateral) and math.isnan(beta):
        raise DataError(f"line {line}: lateral_force is given without its slip_angle [rad]")
    beta = 0.0 if math.isnan(beta) else beta
    if abs(beta) > SLIP_ANGLE_LIMIT:
        raise DataError(f"line {line}: slip_angle = {beta:g} rad is beyond "
                        f"{SLIP_ANGLE_LIMIT:.4g} rad (80 deg); check its unit (rad)")
    if not math.isnan(lateral) and abs(lateral) > PULL_BOUND * load:
        raise DataError(f"line {line}: lateral_force = {lateral:g} N is beyond {PULL_BOUND:g} "
                        f"times the load ({load:g} N); check its unit (N)")
    return Point(dataset=cells.get("dataset") or "user", case=cells.get("case") or f"line {line}",
                 values=values, spread=spread, load=load, slip=slip,
                 drawbar_pull=get("drawbar_pull"), sinkage=get("sinkage"),
                 torque=get("torque", False), sinkage_from=datum, slip_angle=beta,
                 lateral_force=lateral)



PULL_BOUND = 3.0
"""|drawbar_pull| <= PULL_BOUND * load: a measured pull beyond it is refused as impossible. The
soil's Mohr-Coulomb limit at the table's largest friction angle (60 deg) is tan(60 deg) = 1.73
times the load; the shipped data sets reach 0.6. The same bound times the wheel's outer radius
(R + h_g) bounds the torque."""


def _check_measured(line: int, values: dict, load: float, pull: float, sinkage: float,
                    torque: float, datum: str) -> None:
    """Refuse, naming the line, a measurement no wheel test can give: a pull or torque beyond
    PULL_BOUND times the load (and the outer radius), a sinkage below the surface it is counted
    from or past the wheel's axle."""
    radius = values["wheel.radius"]
    if abs(pull) > PULL_BOUND * load:
        raise DataError(f"line {line}: drawbar_pull = {pull:g} N is beyond {PULL_BOUND:g} times "
                        f"the load ({load:g} N): no wheel on soil pulls that (the Mohr-Coulomb "
                        "limit at phi = 60 deg is 1.73 times the load); check its unit (N)")
    outer = radius + values["grouser.height"]
    if not math.isnan(torque) and abs(torque) > PULL_BOUND * load * outer:
        raise DataError(f"line {line}: torque = {torque:g} N.m is beyond {PULL_BOUND:g} times "
                        f"the load times the wheel's outer radius ({PULL_BOUND * load * outer:g} "
                        "N.m); check its unit (N.m)")
    if datum == "surface" and sinkage < 0:
        raise DataError(f"line {line}: sinkage = {sinkage:g} m is below 0, above the soil's "
                        "surface it is counted from (sinkage_from = surface); if it is counted "
                        "from the wheel at rest, say sinkage_from = rest")
    if abs(sinkage) > radius:
        raise DataError(f"line {line}: sinkage = {sinkage:g} m is beyond the wheel's radius "
                        f"({radius:g} m): the axle would be below the surface; check its unit "
                        "(m)")


def read(path: str | Path) -> list[Dataset]:
    """The data sets of the test-data file at ``path``; a file that cannot be read is a
    :class:`DataError`."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise DataError(f"{path}: cannot read it ({err.__class__.__name__}: {err})") from None
    return parse(text, str(path))


def shipped() -> list[Dataset]:
    """The cross-wheel data set the package ships (validation/DATA.md)."""
    return parse(data.path(SHIPPED).read_text(encoding="utf-8"), SHIPPED)
