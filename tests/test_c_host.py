"""The pythonfmu FMUs in a C host, to the end of the process.

A C host (tests/fmi_host.c, compiled here) loads the pythonfmu binary with libpython preloaded,
as C hosts of pythonfmu FMUs must (fmu_src/README.md), instantiates, steps, terminates and frees
it, then returns from main. Before the fix in wheelterrain.fmu.slaves (CasADi objects released
when the last instance is freed) the WheelTerrain FMU aborted the host at exit: "pure virtual
method called", exit status 134, after a clean run."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from fmpy import extract, read_model_description

from wheelterrain import compiled as native
from wheelterrain.cosim import ssp
from wheelterrain.fmu import toolchain

HERE = Path(__file__).resolve().parent

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(native.compiler() is None, reason="needs a C compiler"),
    pytest.mark.skipif(ssp.libpython() is None,
                       reason="needs a shared libpython to preload (this Python is static)"),
]


@pytest.fixture(scope="module")
def host(tmp_path_factory) -> Path:
    binary = tmp_path_factory.mktemp("host") / "fmi_host"
    subprocess.run([native.compiler(), "-O1", "-Wall", "-Werror", "-I",
                    str(toolchain.fmi_headers()), str(HERE / "fmi_host.c"), "-o", str(binary),
                    "-ldl"], check=True)
    return binary


def run_in_c_host(host: Path, fmu: Path, folder: Path, steps: int, get: str,
                  set_: str = "-", at_exit: str = "free",
                  reload: bool = False) -> subprocess.CompletedProcess:
    """Unzip ``fmu`` into ``folder`` and run it in the C host; the embedded interpreter finds
    numpy and casadi on this Python's path. ``at_exit``: what the host calls before it returns
    from main (FMI_HOST_EXIT of tests/fmi_host.c); ``reload``: the library closed and opened
    again with the first instance alive, a second one beside it (FMI_HOST_RELOAD)."""
    unzip = Path(extract(str(fmu), unzipdir=str(folder)))
    md = read_model_description(str(fmu))
    library = unzip / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so"
    env = {**ssp.c_host_environment(), "FMI_HOST_RESOURCES": (unzip / "resources").as_uri(),
           "FMI_HOST_EXIT": at_exit, **({"FMI_HOST_RELOAD": "1"} if reload else {})}
    return subprocess.run([str(host), str(library), md.guid, str(steps), "0.01", set_, "-", get],
                          capture_output=True, text=True, env=env, timeout=300, check=False)


def vr(fmu: Path, name: str) -> int:
    return {v.name: v.valueReference for v in
            read_model_description(str(fmu)).modelVariables}[name]


@pytest.mark.parametrize(("name", "output"), [("WheelTerrain", "normal_force"),
                                              ("SingleWheelRig", "carriage_speed")])
def test_the_host_runs_to_the_end_and_exits_with_status_0(fmu_dir, host, tmp_path, name, output):
    fmu = fmu_dir / f"{name}.fmu"
    for attempt in range(2):  # the abort was 2 of 2 before the fix: twice, in fresh processes
        run = run_in_c_host(host, fmu, tmp_path / f"run{attempt}", 20, str(vr(fmu, output)))
        assert run.returncode == 0, (run.returncode, run.stderr[-2000:])
        rows = [[float(x) for x in line.split()] for line in run.stdout.splitlines()]
        assert len(rows) == 20
        assert all(row[1] == row[1] and row[1] != 0.0 for row in rows)  # computed, not NaN or 0


@pytest.mark.parametrize("name", ["WheelTerrain", "SingleWheelRig"])
def test_a_percent_encoded_non_ascii_resource_uri_runs_in_a_c_host(fmu_dir, host, tmp_path,
                                                                   name):
    """A C host passes the resource URI percent-encoded (file:///.../r%C3%BCn); pythonfmu
    decoded only %20 and crashed the host (SIGSEGV). The guard library decodes it whole."""
    fmu = fmu_dir / f"{name}.fmu"
    output = {"WheelTerrain": "normal_force", "SingleWheelRig": "carriage_speed"}[name]
    folder = tmp_path / "rüb ünï"
    run = run_in_c_host(host, fmu, folder, 5, str(vr(fmu, output)))
    assert "%C3%BC" in (folder / "resources").as_uri()  # the URI the host passed
    assert run.returncode == 0, (run.returncode, run.stderr[-2000:])
    assert len(run.stdout.splitlines()) == 5


@pytest.mark.parametrize("at_exit", ["terminate", "none"])
@pytest.mark.parametrize("name", ["WheelTerrain", "RoverChassis"])
def test_a_host_that_exits_without_freeing_exits_with_status_0(fmu_dir, host, tmp_path, name,
                                                               at_exit):
    """A C host returning from main without fmi2FreeInstance (or without terminate and free)
    aborted: "pure virtual method called", exit status 134, 5 of 5 (CasADi objects released at
    the interpreter's finalisation, after CasADi's static destructors). The guard library
    frees the instances left at exit, before those destructors run."""
    fmu = fmu_dir / f"{name}.fmu"
    output = {"WheelTerrain": "normal_force", "RoverChassis": "position"}[name]
    for attempt in range(2):
        run = run_in_c_host(host, fmu, tmp_path / f"run{attempt}", 5, str(vr(fmu, output)),
                            at_exit=at_exit)
        assert run.returncode == 0, (run.returncode, run.stderr[-2000:])
        assert len(run.stdout.splitlines()) == 5


@pytest.mark.parametrize(("name", "output"), [("WheelTerrain", "normal_force"),
                                              ("Terrain", "q1.rut_met")])
def test_a_host_that_unloads_the_library_between_two_instances_runs_both(fmu_dir, host,
                                                                         tmp_path, name,
                                                                         output):
    """ecos closes an FMU's library and opens it again between two instances of one model,
    the first alive. The guard's exit handler then ran at the unload and freed the live
    instance; the reloaded guard handed the next instance the same memory: wrong numbers,
    then SIGSEGV (Rover-level.ssp on the pythonfmu FMUs, 3 of 3 SSPs with two instances of one
    model). The guard is linked never to be unloaded (-z nodelete)."""
    fmu = fmu_dir / f"{name}.fmu"
    run = run_in_c_host(host, fmu, tmp_path / "run", 20, str(vr(fmu, output)), reload=True)
    assert run.returncode == 0, (run.returncode, run.stderr[-2000:])
    assert len(run.stdout.splitlines()) == 20  # both instances, the same values every step
