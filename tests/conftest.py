"""Shared fixtures; ``classical_reference`` beside this file is the independent Wong-Reece code.

The builds (the FMUs of both flavours, the Modelica library) are made once per test run, also
when pytest-xdist runs the tests in several worker processes: the first worker to need one
builds it, holding a lock, and the others wait and read it (:func:`built_once`)."""

from __future__ import annotations

import math
import os
import shutil
import tarfile
import tempfile
from collections.abc import Callable
from pathlib import Path

import pytest

from wheelterrain import compiled as native
from wheelterrain import files, presets
from wheelterrain.fmu import build_native as nativebuild
from wheelterrain.fmu import build_pythonfmu as fmubuild
from wheelterrain.modelica import reference
from wheelterrain.parameters import ParameterSet

MODELICA_ARCHIVE = Path(os.environ.get(
    "WHEELTERRAIN_MODELICA_ARCHIVE",
    Path(__file__).resolve().parents[2] / "shared" / "modelica" / "modelica-libraries.tar.gz"))
"""The Modelica Standard Library 4.1.0 and PlanarMechanics 1.6.0 sources (BSD 3-Clause) beside
the repository, as the project's shared folder holds them (its README.txt), or where
$WHEELTERRAIN_MODELICA_ARCHIVE says: the MSL checks of tests/test_modelica.py unpack it when
MODELICAPATH has no MSL 4.x, so that they run in CI and not only where someone set it up."""


def _unpacked_modelica(archive: Path) -> Path:
    """The folder ``archive`` unpacks to (its modelica-libraries/), unpacked once per archive
    (its size and time in the folder's name) under the system's temporary folder, under a lock
    (xdist's workers configure at once) and marked done only when whole."""
    stat = archive.stat()
    name = f"wheelterrain-modelica-{stat.st_size}-{stat.st_mtime_ns}"
    folder = Path(tempfile.gettempdir()) / name
    with files.locked(folder.with_suffix(".lock")):
        if not (folder / ".unpacked").exists():
            shutil.rmtree(folder, ignore_errors=True)
            with tarfile.open(archive) as tar:
                if hasattr(tarfile, "data_filter"):  # Python >= 3.11.4: refuse unsafe members
                    tar.extractall(folder, filter="data")
                else:  # pragma: no cover
                    tar.extractall(folder)  # the project's own shared archive
            (folder / ".unpacked").touch()
    return folder / "modelica-libraries"


def pytest_configure(config):
    """MSL on MODELICAPATH for the MSL checks: the shared archive unpacked where it is at hand
    and MODELICAPATH holds no MSL 4.x (a MODELICAPATH that does is used as it is)."""
    if reference.find_msl() is None and MODELICA_ARCHIVE.is_file():
        libraries = _unpacked_modelica(MODELICA_ARCHIVE)
        os.environ["MODELICAPATH"] = os.pathsep.join(
            p for p in (str(libraries), os.environ.get("MODELICAPATH", "")) if p)


@pytest.fixture(scope="session")
def table2() -> ParameterSet:
    return presets.load("paper-table2-arc")


def built_once(tmp_path_factory, name: str, make: Callable[[Path], object]) -> Path:
    """A folder ``make(folder)`` fills once per test run, shared by every xdist worker of the
    run (a worker's base folder is the run's, one level down): the first to ask builds it under
    a lock, the others wait for it and read it. Tests only read it."""
    root = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        root = root.parent
    folder = root / f"shared-{name}"
    with files.locked(root / f".shared-{name}.lock"):
        if not (folder / ".built").exists():
            shutil.rmtree(folder, ignore_errors=True)
            folder.mkdir()
            make(folder)
            (folder / ".built").touch()
    return folder


@pytest.fixture(scope="session")
def fmu_dir(tmp_path_factory):
    """Every pythonfmu FMU, built once per test run for every test that only runs them."""
    return built_once(tmp_path_factory, "fmus", fmubuild.build)


@pytest.fixture(scope="session")
def native_dir(tmp_path_factory, fmu_dir):
    """Every native FMU (FMI 2 here, FMI 3 in fmi3/; win64 binaries where MinGW-w64 is
    installed), built once per test run for every test that only runs them (their
    descriptions from the pythonfmu FMUs of the run, as `build --flavor all` does)."""
    if native.compiler() is None:
        pytest.skip("the native FMUs need a C compiler")
    return built_once(tmp_path_factory, "native",
                      lambda out: nativebuild.build(out, reference_dir=fmu_dir))


@pytest.fixture(scope="session")
def modelica_root(tmp_path_factory):
    """The Modelica library as `wheelterrain build --flavor modelica` writes it, once per run:
    the folder holding WheelTerrain/ (tests read it, never write into it)."""
    from wheelterrain.modelica import library

    return built_once(tmp_path_factory, "modelica", library.write)


@pytest.fixture(scope="session")
def wine_prefix(tmp_path_factory):
    """One Wine prefix for every test that runs a win64 binary under Wine (a new prefix takes
    ~20 s to set up)."""
    return tmp_path_factory.mktemp("wine") / "prefix"


@pytest.fixture(scope="session")
def built_root(tmp_path_factory, fmu_dir, native_dir):
    """A folder with both flavours as pythonfmu/ and native/ (native/fmi3/ inside), built once
    per test run (links to :func:`fmu_dir` and :func:`native_dir`): tests only read it."""
    root = tmp_path_factory.mktemp("flavours")
    (root / "pythonfmu").symlink_to(fmu_dir, target_is_directory=True)
    (root / "native").symlink_to(native_dir, target_is_directory=True)
    return root


def first_steps(fmu: Path, runs, outputs: list[str]) -> list[list[float]]:
    """For each set of start values in ``runs``: a fresh instance of ``fmu`` started with them,
    one co-simulation step of 1 ms, its ``outputs``; no error logged (asserted)."""
    from wheelterrain.fmu.instance import Instance

    results = []
    for values in runs:
        with Instance(fmu, log=True) as inst:
            inst.start(values, 1.0)
            inst.fmu.doStep(0.0, 1e-3)
            results.append(inst.get(outputs))
            assert inst.errors() == []
    return results


def classical_set(R: float, b: float, c: float, phi_deg: float, kc: float, kphi: float, n: float,
                  gamma: float, K: float, a0: float = 0.4, a1: float = 0.15) -> ParameterSet:
    """Parameters with every extension off: the classical Wong-Reece wheel."""
    return ParameterSet({
        "wheel.radius": R, "wheel.width": b, "soil.cohesion": c, "soil.phi": math.radians(phi_deg),
        "soil.k_c": kc, "soil.k_phi": kphi, "soil.n0": n, "soil.n1": 0.0, "soil.gamma": gamma,
        "soil.shear_modulus": K, "model.a0": a0, "model.a1": a1, "model.exit_ratio": 0.0,
        "model.shear_model": 0, "ripple.k_g": 0.0, "ripple.k_0": 0.0,
        "model.contact_radius_factor": 0.0, "model.shear_radius_factor": 0.0,
        "model.slip_radius_factor": 0.0,
    })
