"""fmpy validation sweeps: WheelTerrain.fmu in quasi-static mode over grids of slip, load and any
table parameter, in parallel worker processes or on a Dask cluster.

Each worker extracts the FMU once and instantiates it once. Every grid point then sets the
tunable parameters and inputs, takes one tiny communication step (so the FMU checks the
operating point and refuses an infeasible one with fmi2Discard), and reads the outputs. A
refused point is recorded with ``status`` "infeasible" and NaN outputs, never with stale
numbers. The FMU's slip output (the model's: traction driving, skid braking) is the column
``slip_traction``; ``slip`` is the grid's, in the definition the sweep was given.

Grid syntax (``parse_axis``): ``a:b:n`` (n points from a to b inclusive), ``a,b,c`` (a list),
or a single value; angles accept ``deg`` (``soil.phi=25deg:45deg:5``).
"""

from __future__ import annotations

import itertools
import math
import os
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np

from wheelterrain.errors import ParameterError, UsageError
from wheelterrain.fmu.instance import Instance, read_description
from wheelterrain.fmu.variables import TERRAIN_OUTPUTS
from wheelterrain.model.slip import DEFAULT_DEFINITION, reference_radius, speeds, to_unified
from wheelterrain.parameters import BY_NAME, DEG, SLIP_ANGLE_LIMIT, TABLE

OUTPUTS = TERRAIN_OUTPUTS  # every output WheelTerrain.fmu computes, one column each
COLUMNS = {"slip": "slip_traction"}  # the FMU's output 'slip' next to the grid's 'slip' axis
WHEEL_SPEED = 0.6  # rad/s; only the ratio of the speeds matters in quasi-static mode


def _number(text: str, name: str) -> float:
    text = text.strip()
    scale = 1.0
    if text.endswith("deg"):
        text, scale = text[:-3], DEG
    try:
        return float(text) * scale
    except ValueError:
        raise ParameterError(name, text, "is not a number (grid: a:b:n, a,b,c or a value)") \
            from None


def parse_axis(name: str, spec: str) -> list[float]:
    """Grid values of one axis from ``a:b:n``, ``a,b,c`` or ``a``."""
    if ":" in spec:
        parts = spec.split(":")
        if len(parts) != 3:
            raise ParameterError(name, spec, "grid must be a:b:n, a,b,c or a single value")
        a, b = _number(parts[0], name), _number(parts[1], name)
        try:
            n = int(parts[2])
        except ValueError:
            raise ParameterError(name, spec, "is not a grid: the point count n of a:b:n must "
                                 "be an integer") from None
        if n < 1:
            raise ParameterError(name, spec, "is not a grid: the point count n of a:b:n must "
                                 "be >= 1")
        return list(np.linspace(a, b, n))
    return [_number(x, name) for x in spec.split(",") if x.strip()]


def grid(axes: dict[str, list[float]]) -> Iterator[dict[str, float]]:
    names = list(axes)
    for values in itertools.product(*(axes[n] for n in names)):
        yield dict(zip(names, values, strict=True))


def check_axes(axes: dict[str, list[float]], slip_definition: str) -> None:
    for name, values in axes.items():
        if name == "slip":
            for v in values:
                to_unified(v, slip_definition)  # an InputError naming the range
        elif name == "load":
            for v in values:
                if not v >= 0 or not math.isfinite(v):
                    raise ParameterError("load", v, "must be finite and >= 0 N")
        elif name == "slip_angle":
            for v in values:
                if not abs(v) <= SLIP_ANGLE_LIMIT:
                    raise ParameterError("slip_angle", v, f"is out of range; valid range "
                                         f"[-{SLIP_ANGLE_LIMIT:.6g}, {SLIP_ANGLE_LIMIT:.6g}] "
                                         "rad (80 deg)")
        elif name in BY_NAME:
            for v in values:
                BY_NAME[name].check(v)
        else:
            raise ParameterError(name, "", "is not a sweep axis; use slip, load, slip_angle "
                                 "or a table parameter (wheelterrain params)")


# --- worker side (module-level so that process pools and Dask can pickle it) ---------------

_WORKER: dict = {}


def _worker_instance(fmu: str, unzip_root: str | None = None) -> Instance:
    """The worker's FMU instance, quasi-static: extracted and initialised once per process
    (into ``unzip_root``/<pid> when given: the parent removes that folder whatever becomes of
    the worker; else into a folder of its own, removed when it is closed). Every point is
    solved cold (warm_start off), so a point's result does not depend on which points the
    worker solved before it."""
    if _WORKER.get("fmu") != fmu:
        _close_worker()
        unzip = None
        if unzip_root is not None:
            from fmpy import extract

            unzip = extract(fmu, unzipdir=os.path.join(unzip_root, str(os.getpid())))
        inst = Instance(fmu, unzip, name=f"sweep{os.getpid()}").start({"quasi_static": True,
                                                                        "warm_start": False})
        _WORKER.update(fmu=fmu, inst=inst, time=0.0)
    return _WORKER["inst"]


def run_points(fmu: str, base: dict[str, float], points: list[dict[str, float]],
               slip_definition: str, unzip_root: str | None = None) -> list[dict]:
    """Evaluate ``points`` (each: slip, load and parameter values) in this process."""
    from fmpy.fmi1 import FMICallException

    inst = _worker_instance(fmu, unzip_root)
    rows = []
    for point in points:
        values = {**base, **{k: v for k, v in point.items() if k not in ("slip", "load")}}
        try:
            sigma = to_unified(point.get("slip", 0.0), slip_definition)
            r_ref = reference_radius(values)
            # the faster of rim and carriage at WHEEL_SPEED*R_ref: down to a locked wheel
            rim, carriage = speeds(sigma, WHEEL_SPEED * r_ref)
            inst.set({**values, "wheel_speed": rim / r_ref, "carriage_speed": carriage,
                      "load": point.get("load", 62.0)})
            inst.fmu.doStep(_WORKER["time"], 1e-6)  # refuses (fmi2Discard) an infeasible point
            _WORKER["time"] += 1e-6
            out = inst.get(OUTPUTS)
            named = {COLUMNS.get(k, k): v for k, v in zip(OUTPUTS, out, strict=True)}
            rows.append({**point, **named, "status": "ok"})
        except FMICallException:
            rows.append({**point, **{COLUMNS.get(k, k): math.nan for k in OUTPUTS},
                         "status": "infeasible"})
    return rows


def _close_worker() -> None:
    if "inst" in _WORKER:
        _WORKER["inst"].close()
        _WORKER.clear()


# --- master side ----------------------------------------------------------------------------

def run(fmu: Path, base: dict[str, float], axes: dict[str, list[float]],
        slip_definition: str = DEFAULT_DEFINITION, workers: int = 0,
        dask_address: str | None = None, chunk: int = 16,
        progress: Callable[[int], None] | None = None) -> list[dict]:
    """The whole sweep, in grid order. ``workers`` = 0: one per core; 1: in this process.
    ``dask_address``: a dask.distributed scheduler ("tcp://host:8786") or "local" for a
    LocalCluster on this machine; the workers there need wheelterrain and the FMU's runtime."""
    check_axes(axes, slip_definition)
    fmu = str(Path(fmu).resolve())
    read_description(fmu)  # not found or not an FMU: one error before any worker starts
    points = list(grid(axes))
    chunks = [points[k:k + chunk] for k in range(0, len(points), chunk)]
    results: list[list[dict] | None] = [None] * len(chunks)
    if dask_address:
        _run_dask(fmu, base, chunks, slip_definition, dask_address, results, progress)
    elif workers == 1 or len(chunks) == 1:
        try:
            for k, c in enumerate(chunks):
                results[k] = run_points(fmu, base, c, slip_definition)
                if progress:
                    progress(len(c))
        finally:
            _close_worker()
    else:
        _run_pool(min(workers or os.cpu_count() or 1, len(chunks)), fmu, base, chunks,
                  slip_definition, results, progress)
    return [row for chunk_rows in results for row in chunk_rows]


def _run_pool(count: int, fmu: str, base: dict[str, float], chunks: list, slip_definition: str,
              results: list, progress) -> None:
    """The chunks on ``count`` worker processes. Ctrl-C (or any error) in this process ends the
    pool at once: the workers ignore SIGINT (it is the parent's to handle) and are terminated
    (SIGTERM's default: no Python code of theirs runs, so none can be caught half-way inside
    an FMU call), not waited for. They extract the FMU into a folder this process removes
    afterwards. A worker whose parent dies reads the end of its task queue and exits: no
    orphans."""
    import multiprocessing
    import shutil
    import tempfile

    root = tempfile.mkdtemp(prefix="wheelterrain_sweep_")
    tasks = [(k, fmu, base, c, slip_definition, root) for k, c in enumerate(chunks)]
    pool = multiprocessing.Pool(count, initializer=_worker_start)
    try:
        for k, rows in pool.imap_unordered(_run_chunk, tasks):
            results[k] = rows
            if progress:
                progress(len(rows))
        pool.close()
    except BaseException:
        pool.terminate()
        raise
    finally:
        pool.join()
        shutil.rmtree(root, ignore_errors=True)


def _worker_start() -> None:
    """Pool initializer: leave Ctrl-C to the parent; free the FMU instance when the worker
    ends normally (a terminated worker's folder is removed by the parent)."""
    import signal
    from multiprocessing.util import Finalize

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    Finalize(None, _close_worker, exitpriority=10)


def _run_chunk(task: tuple) -> tuple[int, list[dict]]:
    k, *args = task
    return k, run_points(*args)


DASK_CONNECT_TIMEOUT = 10.0  # s: how long a scheduler's address is tried before it is refused


def _run_dask(fmu, base, chunks, slip_definition, address, results, progress) -> None:
    """The chunks on a dask.distributed cluster: a LocalCluster for "local", else the
    scheduler at ``address`` (UsageError, one line, where none answers within
    DASK_CONNECT_TIMEOUT). Each worker extracts the FMU once; when the sweep ends every worker
    frees its instance, which removes that folder (a worker outlives the sweep)."""
    import logging

    try:
        from dask.distributed import Client, LocalCluster, as_completed
    except ImportError as err:
        raise UsageError("--dask needs dask.distributed: pip install 'dask[distributed]'"
                         ) from err
    import shutil
    import tempfile

    import dask

    scratch = tempfile.mkdtemp(prefix="wheelterrain_dask_") if address == "local" else None
    if scratch is not None:  # dask's own scratch space goes there, not in the temp folder
        with dask.config.set({"temporary-directory": scratch}):
            cluster = LocalCluster(n_workers=os.cpu_count() or 1, threads_per_worker=1,
                                   processes=True, dashboard_address=None,
                                   local_directory=scratch)
    else:
        cluster = None
    quiet = logging.getLogger("distributed")
    level = quiet.level
    quiet.setLevel(logging.CRITICAL)  # its retries would print a traceback per attempt
    try:
        try:
            client = Client(cluster if cluster is not None else address,
                            timeout=DASK_CONNECT_TIMEOUT)
        except (OSError, TimeoutError, ValueError) as err:
            reason = str(err).splitlines()[0] if str(err) else "no reply"
            raise UsageError(f"--dask {address}: no dask scheduler answered within "
                             f"{DASK_CONNECT_TIMEOUT:g} s ({type(err).__name__}: {reason}); "
                             "give a running scheduler's address (tcp://host:8786) or 'local'"
                             ) from None
        finally:
            quiet.setLevel(level)
        with client:
            try:
                futures = [client.submit(run_points, fmu, base, c, slip_definition, pure=False)
                           for c in chunks]
                index = {f.key: k for k, f in enumerate(futures)}
                for future in as_completed(futures):
                    k = index[future.key]
                    results[k] = future.result()
                    if progress:
                        progress(len(chunks[k]))
            finally:
                client.run(_close_worker)  # each worker's extracted FMU removed
    finally:
        if cluster is not None:
            cluster.close()
        if scratch is not None:  # the local workers' scratch space
            shutil.rmtree(scratch, ignore_errors=True)


def write_csv(path: Path, rows: list[dict]) -> None:
    from wheelterrain.cosim.master import csv_header
    from wheelterrain.files import write_atomic
    from wheelterrain.fmu.variables import units as variable_units

    if not rows:
        raise ValueError("no rows to write")
    keys = list(rows[0])
    units = {**variable_units(), "slip": "1", "slip_traction": "1", "load": "N", "status": ""}
    lines = [csv_header(keys, units)]
    for row in rows:
        lines.append(",".join(row[k] if isinstance(row[k], str) else f"{row[k]:.12g}"
                              for k in keys))
    write_atomic(Path(path), "\n".join(lines) + "\n")


def base_values(ps) -> dict[str, float]:
    return {p.name: float(ps[p.name]) for p in TABLE}
