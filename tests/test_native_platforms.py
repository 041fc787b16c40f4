"""The native FMUs' Windows binaries, run for real: a small C host (tests/fmi_host.c),
cross-compiled with MinGW-w64 like the DLLs, loads them under Wine and steps them; the same
host compiled for Linux steps the Linux binary of the same FMU with the same inputs, through
FMI 2.0 and through FMI 3.0. Both binaries come from the same sources/, so their outputs agree
to 1e-12."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest
from fmpy import extract, read_model_description

from wheelterrain import compiled as native
from wheelterrain.fmu import build_fmi3 as fmi3
from wheelterrain.fmu import toolchain

HERE = Path(__file__).resolve().parent
WINE = shutil.which("wine") or shutil.which("wine64")

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(toolchain.cross_compiler() is None or WINE is None
                       or native.compiler() is None,
                       reason="needs gcc-mingw-w64-x86-64, wine and a C compiler "
                              "(.ci/run installs them)"),
]


@pytest.fixture(scope="module")
def built(tmp_path_factory, native_dir, wine_prefix):
    root = tmp_path_factory.mktemp("platforms")
    built = [*native_dir.glob("*.fmu"), *(native_dir / "fmi3").glob("*.fmu")]
    fmus = {("3" if f.parent.name == "fmi3" else "2", f.stem): f for f in built}
    hosts = {"linux64": root / "fmi_host", "win64": root / "fmi_host.exe"}
    headers = str(toolchain.fmi_headers())
    subprocess.run([native.compiler(), "-O1", "-Wall", "-Werror", "-I", headers,
                    str(HERE / "fmi_host.c"), "-o", str(hosts["linux64"]), "-ldl"], check=True)
    subprocess.run([toolchain.cross_compiler(), "-O1", "-Wall", "-Werror", "-I", headers,
                    str(HERE / "fmi_host.c"), "-o", str(hosts["win64"])], check=True)
    unzip = {key: extract(str(fmu)) for key, fmu in fmus.items()}
    yield {"fmus": fmus, "unzip": unzip, "hosts": hosts, "prefix": wine_prefix}
    for d in unzip.values():
        shutil.rmtree(d, ignore_errors=True)


def _run(built, platform: str, fmi: str, model: str, steps: int, h: float, set_: str,
         ramp: str, get: str) -> list[list[float]]:
    binary = {"linux64": f"{model}.so", "win64": f"{model}.dll"}[platform]
    folder = {"2": platform, "3": fmi3.PLATFORMS[platform]}[fmi]
    library = Path(built["unzip"][(fmi, model)]) / "binaries" / folder / binary
    guid = read_model_description(str(built["fmus"][(fmi, model)])).guid
    args = [str(library), guid, str(steps), repr(h), set_, ramp, get, fmi]
    if platform == "win64":
        command = [WINE, str(built["hosts"]["win64"]), *args]
        env = {**os.environ, "WINEPREFIX": str(built["prefix"]), "WINEDEBUG": "-all"}
    else:
        command, env = [str(built["hosts"]["linux64"]), *args], None
    run = subprocess.run(command, capture_output=True, text=True, check=False, env=env,
                         timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    return [[float(x) for x in line.split()] for line in run.stdout.splitlines()]


def _vrs(built, model: str) -> dict[str, int]:
    md = read_model_description(str(built["fmus"][("2", model)]))
    return {v.name: v.valueReference for v in md.modelVariables}


def _scripts(built):
    t = _vrs(built, "WheelTerrain")
    r = _vrs(built, "SingleWheelRig")
    terrain_out = ",".join(str(t[n]) for n in ("normal_force", "drawbar_pull", "torque",
                                                 "entry_angle", "wheel_angle",
                                                 "plastic_sinkage", "rut_left"))
    rig_out = ",".join(str(r[n]) for n in ("sinkage", "sinkage_rate", "wheel_speed",
                                             "carriage_speed", "motor_torque"))
    v = _vrs(built, "RoverChassis")
    rover_out = ",".join(str(v[n]) for n in ("heave", "pitch", "speed", "front_left.sinkage",
                                             "rear_left.wheel_speed", "front_left.motor_torque"))
    rover_in = ",".join(f"{v[f'{w}.{n}']}={a}+{b}" for w in ("front_left", "front_right",
                                                               "rear_left", "rear_right")
                        for n, a, b in (("normal_force", 24.0, 1.0), ("drawbar_pull", 1.0, 0.5),
                                        ("torque", 0.1, 0.05)))
    g = _vrs(built, "Terrain")
    ground_out = ",".join(str(g[n]) for n in ("q1.ground.phi", "q1.ground.k_phi",
                                               "q1.ground.cohesion", "q2.rut_met"))
    return {
        # the terrain map: the leading query point runs from 0 to 3 m across a patch on
        # [1, 2) m leaving a rut, the other 0.3 m behind it meets that rut
        "Terrain": ("Terrain", 300, 1e-2, f"{g['patch.start']}=1,{g['patch.end']}=2,"
                    f"{g['patch.phi']}=0.3,{g['patch.k_phi']}=40,{g['patch.cohesion']}=200",
                    f"{g['q1.position']}=0+1,{g['q1.rut_left']}=0.004+0.002,"
                    f"{g['q2.position']}=-0.3+1", ground_out),
        # a wheel taking its soil from its ground.* inputs (another soil than its parameters)
        "WheelTerrain ground": ("WheelTerrain", 200, 2e-3,
                                f"b{t['soil_from_inputs']}=1,{t['ground.phi']}=0.5,"
                                f"{t['ground.k_phi']}=300",
                                f"{t['sinkage']}=0.01+0.02,{t['wheel_speed']}=0.6+0,"
                                f"{t['carriage_speed']}=0.024+0", terrain_out),
        # dynamic contact: the sinkage ramps from 10 to 20 mm while the wheel turns
        "WheelTerrain dynamic": ("WheelTerrain", 500, 2e-3, f"{t['soil.phi']}=0.6",
                                 f"{t['sinkage']}=0.01+0.02,{t['wheel_speed']}=0.6+0,"
                                 f"{t['carriage_speed']}=0.024+0", terrain_out),
        # quasi-static: the Newton solve for the sinkage that carries a ramping load
        "WheelTerrain quasi-static": ("WheelTerrain", 50, 1e-2,
                                      f"b{t['quasi_static']}=1,{t['soil.phi']}=0.6",
                                      f"{t['load']}=40+40,{t['wheel_speed']}=0.6+0,"
                                      f"{t['carriage_speed']}=0.02+0", terrain_out),
        # the rig under held soil forces: the speed loop and the vertical motion
        "SingleWheelRig": ("SingleWheelRig", 300, 1e-3, "-",
                           f"{r['normal_force']}=55+10,{r['drawbar_pull']}=5+0,"
                           f"{r['torque']}=0.4+0.2", rig_out),
        # the rover's chassis under held soil forces on its four wheels
        "RoverChassis": ("RoverChassis", 300, 1e-3, f"{v['rover.cg_forward']}=0.02", rover_in,
                         rover_out),
    }


@pytest.mark.parametrize("fmi", ["2", "3"])
@pytest.mark.parametrize("case", ["WheelTerrain dynamic", "WheelTerrain quasi-static",
                                  "WheelTerrain ground", "SingleWheelRig", "RoverChassis",
                                  "Terrain"])
def test_the_win64_binary_under_wine_gives_the_linux64_numbers(built, case, fmi):
    model, *script = _scripts(built)[case]
    linux = _run(built, "linux64", fmi, model, *script)
    windows = _run(built, "win64", fmi, model, *script)
    assert len(linux) == len(windows) == script[0]
    worst = 0.0
    for a, b in zip(linux, windows, strict=True):
        for x, y in zip(a, b, strict=True):
            worst = max(worst, abs(x - y) / max(abs(x), 1e-300) if x != y else 0.0)
    print(f"\nFMI {fmi} {case}: max relative difference win64 vs linux64 {worst:.3g}")
    assert worst <= 1e-12, worst
    assert len({tuple(row[1:]) for row in linux}) > 1  # the outputs moved: a real run
