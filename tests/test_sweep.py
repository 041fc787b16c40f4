"""`wheelterrain sweep`: fmpy sweeps of WheelTerrain.fmu agree with the core model, in every
execution mode; infeasible points are flagged, never filled with stale numbers."""

from __future__ import annotations

import csv
import math
import os
import subprocess
import sys
import time

import pytest
from click.testing import CliRunner

from wheelterrain import model, presets
from wheelterrain.cli import main
from wheelterrain.cosim import sweep as sweeper
from wheelterrain.errors import ParameterError
from wheelterrain.model.slip import traction_from_paper
from wheelterrain.parameters import DEG


@pytest.fixture(scope="module")
def fmu(fmu_dir):
    return fmu_dir / "WheelTerrain.fmu"


def test_parse_axis():
    assert sweeper.parse_axis("slip", "0:0.5:3") == pytest.approx([0, 0.25, 0.5])
    assert sweeper.parse_axis("load", "10,20") == [10.0, 20.0]
    assert sweeper.parse_axis("soil.phi", "30deg") == pytest.approx([30 * DEG])
    for bad in ("0:1", "a:b:3", "0:1:0"):
        with pytest.raises(ParameterError):
            sweeper.parse_axis("slip", bad)
    with pytest.raises(ParameterError, match="not a sweep axis"):
        sweeper.check_axes({"soil.bogus": [1.0]}, "paper")
    with pytest.raises(ParameterError, match="valid range"):
        sweeper.check_axes({"soil.phi": [2.0]}, "paper")


AXES = {"slip": [0.0, 0.5], "load": [30.0, 200.0], "soil.phi": [25 * DEG, 40 * DEG]}


def _check(rows, ps):
    assert len(rows) == 8
    for row in rows:
        q = ps.with_values({"soil.phi": row["soil.phi"]})
        i = traction_from_paper(row["slip"])
        if row["load"] > model.capacity(q, i):
            assert row["status"] == "infeasible"
            assert math.isnan(row["drawbar_pull"])
            continue
        want = model.steady_state(q, row["load"], i)
        assert row["status"] == "ok"
        assert row["drawbar_pull"] == pytest.approx(want["drawbar_pull"], rel=1e-9)
        assert row["contact_sinkage"] == pytest.approx(want["sinkage"], rel=1e-9)


@pytest.mark.parametrize("workers", [1, 2])
def test_sweep_matches_the_core_model(fmu, workers):
    ps = presets.load("paper-table2-arc")
    rows = sweeper.run(fmu, sweeper.base_values(ps), AXES, "paper", workers=workers, chunk=3)
    assert any(r["status"] == "infeasible" for r in rows)  # 200 N is beyond capacity
    _check(rows, ps)


def test_sweep_on_a_local_dask_cluster(fmu):
    pytest.importorskip("dask.distributed")
    ps = presets.load("paper-table2-arc")
    rows = sweeper.run(fmu, sweeper.base_values(ps), AXES, "paper", dask_address="local",
                       chunk=3)
    _check(rows, ps)


def test_cli_writes_csv_and_plot(fmu, tmp_path):
    folder = tmp_path / "made" / "here"  # --out is a folder, created if needed
    out = folder / "sweep.csv"
    run = CliRunner().invoke(main, ["sweep", "--fmu", str(fmu), "--slip", "0:0.5:3",
                                    "--load", "62", "--workers", "1", "--out", str(folder)])
    assert run.exit_code == 0, run.output
    with out.open() as f:
        reader = csv.DictReader(f)
        rows = list(reader)
    # the header carries the units; a status column has none
    assert {"slip [1]", "load [N]", "drawbar_pull [N]", "contact_sinkage [m]", "torque [N.m]",
            "status"} <= set(reader.fieldnames)
    assert [float(r["slip [1]"]) for r in rows] == pytest.approx([0, 0.25, 0.5])
    assert out.with_suffix(".png").stat().st_size > 0
    bad = CliRunner().invoke(main, ["sweep", "--fmu", str(fmu), "--grid", "soil.phi=2"])
    assert bad.exit_code == 2
    assert "valid range" in bad.output


def test_a_thousand_point_sweep_is_identical_on_a_local_dask_cluster(fmu, tmp_path):
    """The issue's gate: 1000 quasi-static points through the FMU with the progress bar and a
    CSV (the CLI), and the same sweep through a local Dask cluster, identical."""
    pytest.importorskip("dask.distributed")
    out = tmp_path / "k.csv"
    run = CliRunner().invoke(main, ["sweep", "--fmu", str(fmu), "--slip", "0:0.75:40",
                                    "--load", "10:100:25", "--workers", "2", "--out", str(out)])
    assert run.exit_code == 0, run.output
    assert "sweeping 1000 points" in run.output
    with out.open() as f:  # headers carry units: "drawbar_pull [N]"
        pooled = [{k.split(" [")[0]: v for k, v in row.items()} for row in csv.DictReader(f)]
    assert len(pooled) == 1000
    ps = presets.load(presets.DEFAULT_PRESET)  # the CLI's default
    axes = {"slip": sweeper.parse_axis("slip", "0:0.75:40"),
            "load": sweeper.parse_axis("load", "10:100:25")}
    on_dask = sweeper.run(fmu, sweeper.base_values(ps), axes, "traction",
                          dask_address="local")
    assert len(on_dask) == 1000
    for a, b in zip(pooled, on_dask, strict=True):
        assert a["status"] == b["status"]
        for key in ("drawbar_pull", "contact_sinkage", "normal_force"):
            x, y = float(a[key]), b[key]
            assert (math.isnan(x) and math.isnan(y)) or float(f"{y:.12g}") == x


def test_paper_findings_hold_in_an_fmu_sweep_with_the_calibrated_preset(fmu):
    """Drawbar pull grows with slip, the normal force stays at the load, sinkage grows with
    slip: through the FMU, with rashid-calibrated (untuned, the pull falls with slip; see
    tests/test_sensitivity.py)."""
    ps = presets.load("rashid-calibrated")
    axes = {"slip": sweeper.parse_axis("slip", "0:0.75:7"), "load": [62.0]}
    rows = sweeper.run(fmu, sweeper.base_values(ps), axes, "paper", workers=1)
    assert all(r["status"] == "ok" for r in rows)
    pull = [r["drawbar_pull"] for r in rows]
    sinkage = [r["contact_sinkage"] for r in rows]
    assert pull == sorted(pull)
    assert sinkage == sorted(sinkage)
    assert all(r["normal_force"] == pytest.approx(62.0, rel=1e-9) for r in rows)


def _children(pid: int) -> set[int]:
    """The process ids whose parent is ``pid`` (from /proc)."""
    from pathlib import Path

    found = set()
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            found.add(int(stat.parent.name))
    return found


@pytest.mark.slow
@pytest.mark.skipif(not __import__("pathlib").Path("/proc/self/stat").is_file(),
                    reason="reads the process table from /proc")
def test_ctrl_c_stops_a_parallel_sweep_at_once_and_leaves_no_worker(fmu, tmp_path):
    """Ctrl-C during a long parallel sweep hung in 2 of 5 tries (the pool waited for every
    queued chunk) and killing the parent orphaned the workers. Now the parent ends the pool at
    once, says so, writes no results, and its workers are gone."""
    import contextlib
    import os
    import signal
    import subprocess
    import sys
    import time
    from pathlib import Path

    def as_from_a_terminal() -> None:
        """Ctrl-C as a terminal delivers it: the default disposition, not blocked. A process
        inherits an ignored or blocked SIGINT from its parent (a shell's background job, or a
        test run that ignores it), and a Python started so keeps ignoring Ctrl-C."""
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
        signal.signal(signal.SIGINT, signal.SIG_DFL)

    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "wheelterrain.cli", "sweep", "--fmu",
                             str(fmu), "--slip", "0:0.9:400", "--load", "20:60:200",
                             "--workers", "2", "--out", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=as_from_a_terminal)
    workers: set[int] = set()
    deadline = time.monotonic() + 120
    while len(workers) < 2 and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.2)
        workers |= _children(proc.pid)
    assert len(workers) >= 2, "the sweep did not start its workers"
    time.sleep(2.0)  # working on their chunks
    proc.send_signal(signal.SIGINT)
    try:
        _, err = proc.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        for pid in (proc.pid, *workers):
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
        proc.communicate()
        pytest.fail("the sweep did not stop within 30 s of Ctrl-C")
    assert proc.returncode != 0
    assert "Traceback" not in err, err[-2000:]
    assert not (out / "sweep.csv").exists()
    time.sleep(1.0)
    alive = [pid for pid in workers if os.path.exists(f"/proc/{pid}")
             and "Z" not in Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]]
    assert not alive, f"workers left running: {alive}"


@pytest.mark.slow
def test_an_unreachable_dask_scheduler_is_one_line_and_exit_2(fmu, tmp_path):
    """`--dask tcp://scheduler:8786` (the docs' own example) printed a 63-83-line traceback
    and exited 1 after 30 s; now one line, exit 2, within the connect timeout, no folder left."""
    pytest.importorskip("dask.distributed")
    out = tmp_path / "out"
    started = time.perf_counter()
    run = subprocess.run([sys.executable, "-m", "wheelterrain.cli", "sweep", "--fmu", str(fmu),
                          "--dask", "tcp://no-such-scheduler.invalid:8786", "--slip", "0.1",
                          "--out", str(out)], capture_output=True, text=True, timeout=120,
                         check=False)
    assert run.returncode == 2, run.stderr
    lines = [line for line in (run.stdout + run.stderr).splitlines() if line.strip()]
    assert len(lines) == 1, lines
    assert "no dask scheduler answered" in lines[0]
    assert time.perf_counter() - started < sweeper.DASK_CONNECT_TIMEOUT + 15
    assert not out.exists()


def test_a_local_dask_sweep_leaves_nothing_in_the_temporary_folder(fmu, tmp_path):
    """Each run on a local cluster left the extracted FMU (3.1 MB) and dask's scratch space in
    the temporary folder."""
    pytest.importorskip("dask.distributed")
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    run = subprocess.run([sys.executable, "-m", "wheelterrain.cli", "sweep", "--fmu", str(fmu),
                          "--dask", "local", "--slip", "0:0.5:20", "--out", str(tmp_path / "o")],
                         capture_output=True, text=True, timeout=300, check=False,
                         env={**os.environ, "TMPDIR": str(scratch)})
    assert run.returncode == 0, run.stderr[-2000:]
    assert (tmp_path / "o" / "sweep.csv").is_file()
    assert list(scratch.iterdir()) == []


def test_a_sweep_over_the_slip_angle_gives_the_core_models_side_force(fmu, tmp_path):
    """`sweep --slip-angle GRID` [deg]: a slip_angle [rad] axis, the lateral outputs of the
    core's steady state at each point; 0 at slip angle 0; a slip angle beyond 80 deg is one
    line, exit 2."""
    out = tmp_path / "sweep.csv"
    result = CliRunner().invoke(main, ["sweep", "--fmu", str(fmu), "--slip", "0.2", "--load",
                                       "40", "--slip-angle", "0:30:4", "--out", str(out),
                                       "--workers", "1"])
    assert result.exit_code == 0, result.output
    with open(out, newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 4
    ps = presets.load()
    for row in rows:
        beta = float(row["slip_angle [rad]"])
        want = model.steady_state(ps, 40.0, 0.2, slip_angle=beta)
        assert float(row["lateral_force [N]"]) == pytest.approx(want["lateral_force"],
                                                                 rel=1e-9, abs=1e-12)
        assert float(row["aligning_moment [N.m]"]) == pytest.approx(
            want["aligning_moment"], rel=1e-9, abs=1e-12)
    assert float(rows[0]["lateral_force [N]"]) == 0.0
    assert float(rows[-1]["slip_angle [rad]"]) == pytest.approx(math.radians(30.0))
    assert out.with_suffix(".png").is_file()
    bad = CliRunner().invoke(main, ["sweep", "--fmu", str(fmu), "--slip", "0.2",
                                    "--slip-angle", "85", "--out", str(tmp_path / "b.csv")])
    assert bad.exit_code == 2
    assert "slip_angle" in bad.output


def test_the_plot_of_a_slip_angle_sweep_draws_the_side_force_against_the_angle_in_degrees(
        tmp_path, monkeypatch):
    """With a slip-angle axis the sweep's plot is the lateral force, the aligning moment and
    the pull against the slip angle, in degrees, one line per slip."""
    from wheelterrain import plots

    drawn = {}
    monkeypatch.setattr(plots, "_save", lambda fig, path: drawn.update(fig=fig, path=path))
    rows = [{"slip": s, "slip_angle": math.radians(b), "lateral_force": -s - b,
             "aligning_moment": 0.01 * b, "drawbar_pull": 3.0 * s, "contact_sinkage": 0.01}
            for s in (0.0, 0.5) for b in (0.0, 10.0, 20.0)]
    plots.sweep_curves(rows, "slip_angle", ["slip"], tmp_path / "x.png", "t")
    axes = drawn["fig"].axes
    assert [ax.get_ylabel().split(" [")[0] for ax in axes] == [
        "lateral force", "aligning moment", "drawbar pull"]
    assert all(ax.get_xlabel() == "slip angle [deg]" for ax in axes)
    lines = axes[0].get_lines()
    assert len(lines) == 2
    assert list(lines[1].get_xdata()) == pytest.approx([0.0, 10.0, 20.0], rel=1e-12)
    assert list(lines[1].get_ydata()) == [-0.5, -10.5, -20.5]
    assert lines[1].get_label() == "slip = 0.5"
