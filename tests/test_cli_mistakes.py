"""A user's mistake gets one line naming what was wrong and exit 2, never a traceback, and is
found before any long run starts; files the CLI writes get the user's normal permissions."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest
from click.testing import CliRunner

from wheelterrain.cli import main
from wheelterrain.files import write_atomic


def _one_line_exit_2(result, needle: str) -> None:
    assert result.exit_code == 2, result.output
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert len(lines) == 1, result.output
    assert needle in lines[0]
    assert "Traceback" not in result.output


def test_malformed_preset_json(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    result = CliRunner().invoke(main, ["steady", "--preset", str(bad), "--slip", "0.2",
                                       "--load", "62"])
    _one_line_exit_2(result, "is not valid JSON")


@pytest.mark.parametrize("command", [
    ["steady", "--slip", "0.2", "--load", "62"],
    ["params"],
    ["reproduce", "--fmu-dir", "nowhere"],
    ["mpc", "--fmu-dir", "nowhere"],
    ["validate"],
], ids=["steady", "params", "reproduce", "mpc", "validate"])
def test_json_into_a_missing_folder_is_refused_before_the_run(tmp_path, command):
    target = tmp_path / "missing" / "x.json"
    result = CliRunner().invoke(main, [*command, "--json", str(target)])
    _one_line_exit_2(result, "does not exist (it is not created)")
    assert not target.parent.exists()


def test_json_onto_a_folder_is_refused(tmp_path):
    result = CliRunner().invoke(main, ["params", "--json", str(tmp_path)])
    _one_line_exit_2(result, "is a folder")


@pytest.mark.parametrize("command", [["reproduce"], ["mpc"], ["sweep"],
                                     ["calibrate", "--params", "soil.phi"]])
def test_an_out_folder_that_cannot_be_made_is_refused_before_the_run(tmp_path, command):
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    out = blocker / "sub" / "dir"
    result = CliRunner().invoke(main, [*command, "--out", str(out)])
    _one_line_exit_2(result, "is not a writable folder")


@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="needs Linux's /proc")
def test_a_folder_that_only_looks_writable_is_refused_before_the_run():
    """os.access says yes to root on /proc; the check creates the folder (or a probe file)
    instead, so the mistake is one line before the run, not a traceback after it."""
    result = CliRunner().invoke(main, ["reproduce", "--out", "/proc/wheelterrain-out"])
    _one_line_exit_2(result, "cannot create the folder")
    result = CliRunner().invoke(main, ["steady", "--slip", "0.2", "--load", "62", "--json",
                                       "/proc/wheelterrain.json"])
    _one_line_exit_2(result, "is not writable")


def test_calibrate_out_is_a_folder_holding_the_named_preset(tmp_path):
    """--out DIR writes DIR/NAME.json, the file --preset reads back; FILE.json still works."""
    out = tmp_path / "fits"
    result = CliRunner().invoke(main, ["calibrate", "--params", "soil.phi", "--starts", "1",
                                       "--out", str(out), "--name", "my-fit"])
    assert result.exit_code == 0, result.output
    doc = json.loads((out / "my-fit.json").read_text())
    assert doc["name"] == "my-fit"
    result = CliRunner().invoke(main, ["steady", "--preset", str(out / "my-fit.json"),
                                       "--slip", "0.25", "--load", "62", "--json"])
    assert json.loads(result.output)["preset"] == str(out / "my-fit.json")
    legacy = tmp_path / "legacy.json"
    result = CliRunner().invoke(main, ["calibrate", "--params", "soil.phi", "--starts", "1",
                                       "--out", str(legacy)])
    assert result.exit_code == 0, result.output
    assert json.loads(legacy.read_text())["provenance"]["fitted"]["soil.phi"]


def test_infinite_load_names_a_half_open_range():
    result = CliRunner().invoke(main, ["steady", "--slip", "0.2", "--load", "inf"])
    _one_line_exit_2(result, "must be finite; valid range [0, inf)")


def test_a_full_standard_output_is_one_line_not_a_traceback():
    with open("/dev/full", "w") as full:
        run = subprocess.run([sys.executable, "-m", "wheelterrain.cli", "params"], stdout=full,
                             stderr=subprocess.PIPE, text=True, check=False)
    assert run.returncode == 2
    assert run.stderr.strip().splitlines() == [
        "error: cannot write the output: No space left on device"]


def test_json_without_a_file_prints_the_document_and_with_one_writes_it(tmp_path):
    printed = CliRunner().invoke(main, ["steady", "--slip", "0.2", "--load", "62", "--json"])
    assert printed.exit_code == 0
    doc = json.loads(printed.stdout)
    target = tmp_path / "s.json"
    written = CliRunner().invoke(main, ["steady", "--slip", "0.2", "--load", "62", "--json",
                                        str(target)])
    assert written.exit_code == 0
    assert json.loads(target.read_text()) == doc
    assert "drawbar_pull" in written.stdout  # the text is still printed beside the file
    assert doc["preset"] in written.stdout  # and it names the preset


def test_written_files_get_the_users_normal_permissions(tmp_path):
    mask = os.umask(0o022)
    try:
        write_atomic(tmp_path / "r.csv", "a,b\n")
    finally:
        os.umask(mask)
    assert (tmp_path / "r.csv").stat().st_mode & 0o777 == 0o644


def test_writes_never_replace_a_named_pipe_or_a_link(tmp_path):
    """`--json /dev/null` used to replace the device by a regular file (the atomic write
    renamed onto any path). A named pipe stands in for the device here; a link stays a link
    and its target gets the text."""
    import os
    import threading

    pipe = tmp_path / "pipe"
    os.mkfifo(pipe)
    received = []
    reader = threading.Thread(target=lambda: received.append(pipe.read_text()))
    reader.start()
    write_atomic(pipe, '{"a": 1}\n')
    reader.join(timeout=10)
    assert received == ['{"a": 1}\n']
    assert pipe.is_fifo()
    target = tmp_path / "real.json"
    target.write_text("old")
    link = tmp_path / "link.json"
    link.symlink_to(target)
    write_atomic(link, "new\n")
    assert link.is_symlink()
    assert target.read_text() == "new\n"


@pytest.mark.parametrize("name", ["afile.txt", "missing.fmu"])
def test_sweep_of_a_file_that_is_not_an_fmu_is_one_line(tmp_path, name):
    """It was a 46-line traceback from zipfile."""
    if name == "afile.txt":
        (tmp_path / name).write_text("hello\n")
    result = CliRunner().invoke(main, ["sweep", "--fmu", str(tmp_path / name), "--out",
                                       str(tmp_path / "out")])
    assert result.exit_code == 2, result.output
    errors = [line for line in result.output.splitlines() if line.startswith("error:")]
    assert len(errors) == 1, result.output
    assert name in errors[0]
    assert "Traceback" not in result.output
    assert not (tmp_path / "out").exists()  # a refused run leaves no empty folder


@pytest.mark.parametrize("command", [
    ["reproduce"],
    ["mpc", "--plant", "fmu"],
    ["rover", "--scenario", "level", "--engine", "fmus"],
    ["rover", "--scenario", "level", "--engine", "libcosim"],
    ["rover", "--scenario", "level", "--engine", "ecos"],
], ids=["reproduce", "mpc", "rover-fmus", "rover-libcosim", "rover-ecos"])
def test_a_folder_of_files_that_are_not_fmus_is_one_line(tmp_path, command):
    """--fmu-dir holding files named like the FMUs that are not FMUs: ecos crashed
    (SIGSEGV, an empty output folder), the others ended in tracebacks (BadZipFile,
    AssertionError). Every FMU is read before any engine loads it."""
    for name in ("WheelTerrain", "SingleWheelRig", "RoverChassis", "Terrain"):
        (tmp_path / f"{name}.fmu").write_text("not an FMU")
    result = CliRunner().invoke(main, [*command, "--fmu-dir", str(tmp_path),
                                       "--out", str(tmp_path / "out")])
    assert result.exit_code == 2, result.output
    assert "is not an FMU fmpy can read" in result.output
    assert "Traceback" not in result.output


def test_build_into_a_folder_it_cannot_make_is_one_line(tmp_path):
    """`build --out` where the folder cannot be made ended in a traceback (OSError)."""
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    result = CliRunner().invoke(main, ["build", "--out", str(blocker / "fmus")])
    _one_line_exit_2(result, "cannot write to")


# a run that lasts (the Moon's pull test at a 0.1 ms step: about 40 s on a quiet 2-core
# machine), so that a signal sent after a few seconds lands inside it
LONG_RUN = ("rover", "--scenario", "pull-test", "--gravity", "moon", "--step", "1e-4")


def _signalled_long_run(tmp_path, out, signum: int) -> tuple[int, str]:
    """(exit status, standard error) of LONG_RUN writing to ``out``, sent ``signum`` once it
    is well inside the run. SIGINT as a terminal delivers it: a process started by one that
    ignores it (a background job, a test runner's worker) would inherit the ignoring."""
    import signal
    import time

    def as_from_a_terminal() -> None:
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})
        signal.signal(signal.SIGINT, signal.SIG_DFL)

    run = subprocess.Popen([sys.executable, "-m", "wheelterrain.cli", *LONG_RUN,
                            "--out", str(out)],
                           cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           text=True, preexec_fn=as_from_a_terminal)
    time.sleep(4.0)
    assert run.poll() is None  # still running
    run.send_signal(signum)
    _, err = run.communicate(timeout=60)
    return run.returncode, err


def test_ctrl_c_exits_130_with_one_line(tmp_path):
    """Ctrl-C exited 1, a code the CLI documents for nothing; the shell's convention is 130."""
    import signal

    code, err = _signalled_long_run(tmp_path, tmp_path, signal.SIGINT)
    assert code == 130, (code, err[-2000:])
    assert "interrupted" in err
    assert "Traceback" not in err


def test_setting_the_rovers_gravity_is_refused_not_ignored():
    """`--set rover.gravity=1.62` ran at --gravity's 9.81 m/s2, silently."""
    result = CliRunner().invoke(main, ["rover", "--scenario", "level",
                                       "--set", "rover.gravity=1.62"])
    _one_line_exit_2(result, "the gravity is --gravity's (earth 9.81, moon 1.62 m/s2)")


def test_a_sweep_too_large_to_hold_is_refused_with_its_size():
    """A 1e8-point grid was neither refused nor warned: every row is held in memory until
    the CSV is written."""
    result = CliRunner().invoke(main, ["sweep", "--slip", "0:0.9:10000",
                                       "--load", "10:100:10000"])
    _one_line_exit_2(result, "the grid has 1e+08 points, more than --max-points 1000000")


def test_an_interrupted_set_of_results_is_left_whole_or_not_at_all(tmp_path):
    """Ctrl-C while reproduce wrote its files left part of a set (C1.csv alone, or
    C1.csv C1.png C1.ssp C2.csv) in 4 of 5 tries. The set is written aside and moved in
    once whole."""
    from wheelterrain.files import one_set

    out = tmp_path / "out"
    (out / "old.txt").parent.mkdir()
    (out / "old.txt").write_text("kept")

    def interrupted_while_writing():
        with one_set(out) as staging:
            (staging / "C1.csv").write_text("1")
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        interrupted_while_writing()
    assert sorted(p.name for p in out.iterdir()) == ["old.txt"]  # nothing of it, no folder
    with one_set(out) as staging:
        for case in ("C1", "C2"):
            (staging / f"{case}.csv").write_text(case)
    assert sorted(p.name for p in out.iterdir()) == ["C1.csv", "C2.csv", "old.txt"]


def test_sigterm_exits_143_and_leaves_no_output_or_temporary_folder(tmp_path):
    """SIGTERM left an empty output folder and temporary folders: it now unwinds like an
    error, so the folder made for the run and every temporary folder go."""
    import glob
    import signal
    import tempfile

    before = set(glob.glob(f"{tempfile.gettempdir()}/wheelterrain_*"))
    code, err = _signalled_long_run(tmp_path, tmp_path / "new" / "out", signal.SIGTERM)
    assert code == 143, (code, err[-2000:])
    assert "terminated" in err
    assert "Traceback" not in err
    assert not (tmp_path / "new").exists()  # the folder made for the run is gone
    assert set(glob.glob(f"{tempfile.gettempdir()}/wheelterrain_*")) <= before


def test_validate_data_that_no_form_can_predict_exits_3_with_no_coverage(tmp_path):
    """One point the wheel cannot carry (1e300 N): every form 'failed', exit 0, and a null MAE
    stood beside an interval coverage of 1.0."""
    from wheelterrain import data

    lines = [line for line in data.path("wheel_tests.csv").read_text().splitlines()
             if not line.startswith("#")][:3]
    header = lines[0].split(",")
    load = next(k for k, name in enumerate(header) if name.startswith("load"))
    bad = lines[2].split(",")
    bad[load] = "1e300"
    user = tmp_path / "mine.csv"
    user.write_text("\n".join([lines[0], lines[1], ",".join(bad)]) + "\n")
    result = CliRunner().invoke(main, ["validate", "--data", str(user), "--json",
                                       str(tmp_path / "out.json")])
    assert result.exit_code == 3, result.output
    assert "no model form could predict" in result.output
    rows = json.loads((tmp_path / "out.json").read_text())["rows"]
    forms = [row for row in rows if row["model"] != "line"]
    assert forms
    for row in forms:
        assert row["error"]
        assert row["drawbar_pull_mae"] is None
        assert row["interval_coverage"] is None
    line = [row for row in rows if row["model"] == "line"]  # the baseline has no interval
    assert len(line) == 1
    assert line[0]["interval_coverage"] is None


def test_a_rover_longer_than_the_rut_record_is_a_parameter_error_exit_2():
    """A wheelbase the rut profile cannot hold was refused with exit 4 (a numerical failure);
    it is the user's parameter: exit 2, naming what to change."""
    result = CliRunner().invoke(main, ["rover", "--scenario", "level", "--set",
                                       "rover.wheelbase=1.4", "--json"])
    _one_line_exit_2(result, "the rut profile holds 256 cells")
    assert "rover.wheelbase shorter" in result.output


@pytest.mark.parametrize(("arguments", "needle"), [
    (["--scenario", "pull-test", "--engine", "fmpy-ssp"], "fmpy's SSP runner cannot run"),
    (["--scenario", "slope", "--engine", "fmpy-ssp"], "fmpy's SSP runner cannot run"),
    (["--scenario", "soft-patch", "--engine", "fmpy-ssp"], "cannot run a soil map"),
    (["--scenario", "slope", "--controller", "mpc"], "--controller mpc runs level and"),
    (["--scenario", "level", "--controller", "mpc", "--engine", "ecos"],
     "--controller mpc runs with --engine in-process"),
    (["--scenario", "level", "--controller", "mpc", "--step", "0.0005"],
     "at the rover's step of 0.001 s"),
    (["--scenario", "level", "--set", "rover.gravity=3"], "the gravity is --gravity's"),
], ids=["fmpy-ssp-pull-test", "fmpy-ssp-slope", "fmpy-ssp-soft-patch", "mpc-slope",
        "mpc-ecos", "mpc-step", "gravity"])
def test_a_rover_run_the_registry_refuses_exits_2_before_any_work(tmp_path, arguments, needle):
    """An engine and scenario (or controller) that cannot go together: one line, exit 2, before
    the prediction or the run starts (`--engine fmpy-ssp --scenario pull-test` exited 4, as a
    numerical failure, after the prediction: the except for the engine's error could never
    run), and no output folder left behind."""
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["rover", *arguments, "--out", str(out),
                                       "--fmu-dir", str(tmp_path)])
    _one_line_exit_2(result, needle)
    assert not out.exists()
