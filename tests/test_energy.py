"""The energy ledgers (wheelterrain.cosim.energy), on level ground.

The paper's rig: the motor's and the load's work equal the kinetic energy gained, the traction
work, the slip losses, the compaction and bulldozing work, the damper's and the vertical
pressing of the soil, to 1e-6 of the motor's work, for every preset at C1 and C4, on the soil
with memory and the elastic one, with bulldozing on; each loss has its physical sign; leaving
any term out breaks the balance far beyond the tolerance (the test can fail).

The rover: the same per wheel, each with its own axle's speed (exact rigid-body kinematics),
with gravity and the chassis' kinetic energy (its centre of mass'), closing to 1e-9 on level
ground, a 10 deg climb and a 10 deg descent, on Earth and the Moon, with the rut profiles:
the rear wheels in the front wheels' ruts, as the rover is simulated."""

from __future__ import annotations

import json

import pytest

from wheelterrain import presets
from wheelterrain.cli import main
from wheelterrain.cosim import energy

BALANCE = 1e-6
"""Of the motor's work: what the ledger must close to (CVODES at 1e-10 leaves ~1e-11)."""


def _check(ledger: dict, driving: bool) -> None:
    assert abs(ledger["residual"]) <= BALANCE * ledger["motor"], ledger
    assert ledger["motor"] > 0
    for loss in ("compaction", "bulldozing", "damping"):
        assert ledger[loss] >= 0, (loss, ledger)
    if driving:
        assert ledger["slip"] > 0, ledger
    # every term that moves energy is needed: without it the balance is off by far more
    for term in energy.TERMS:
        if abs(ledger[term]) > 1e-3 * ledger["motor"]:
            assert abs(ledger[term]) > 1e3 * abs(ledger["residual"]), (term, ledger)


@pytest.mark.parametrize("name", presets.available())
@pytest.mark.parametrize("slip_paper", [0.0, 0.75])
def test_the_rig_ledger_closes_for_every_preset(name, slip_paper):
    _check(energy.rig_ledger(presets.load(name), slip_paper), driving=slip_paper > 0)


@pytest.mark.parametrize("values", [{"model.soil_memory": 0}, {"model.bulldozing": 1},
                                    {"model.grouser_thrust": 1, "model.contact_form": 0}])
def test_the_ledger_closes_on_the_elastic_soil_with_bulldozing_and_grouser_thrust(values):
    ledger = energy.rig_ledger(presets.load().with_values(values), 0.5)
    _check(ledger, driving=True)
    if "model.bulldozing" in values:
        assert ledger["bulldozing"] > 1e-3 * ledger["motor"]


def test_the_soil_takes_more_of_the_motors_work_as_slip_grows():
    """From C1 to C4 the slip losses' share rises and the compaction's falls (the wheel digs
    deeper but travels less per turn)."""
    runs = [energy.rig_ledger(presets.load(), s) for s in (0.0, 0.25, 0.5, 0.75)]
    slip_share = [r["slip"] / r["motor"] for r in runs]
    compaction_share = [r["compaction"] / r["motor"] for r in runs]
    assert slip_share == sorted(slip_share)
    assert compaction_share == sorted(compaction_share, reverse=True)


def test_the_cli_prints_the_ledger_and_writes_json(tmp_path, capsys):
    target = tmp_path / "energy.json"
    with pytest.raises(SystemExit) as done:
        main(["energy", "--cases", "C2", "--json", str(target)], standalone_mode=True)
    assert done.value.code == 0
    document = json.loads(target.read_text())
    (row,) = document["runs"]
    assert row["case"] == "C2"
    assert row["slip_paper"] == 0.25
    assert set(energy.TERMS) <= set(row)
    assert abs(row["residual"]) <= BALANCE * row["motor"]
    assert document["units"]["motor"] == "J"
    with pytest.raises(SystemExit) as done:
        main(["energy", "--cases", "C5"], standalone_mode=True)
    assert done.value.code == 2
    assert "choose among C1, C2, C3, C4" in capsys.readouterr().err


@pytest.mark.parametrize("gravity", [9.81, 1.62])
def test_the_rover_ledger_closes_on_level_ground_with_the_ruts(gravity):
    """20 s from rest: the rear wheels reach the front wheels' ruts (at about 13 s)."""
    ledger = energy.rover_ledger(presets.load(), {"rover.gravity": gravity})
    assert ledger["ruts"] is True
    assert ledger["stop"] == 20.0
    assert abs(ledger["residual"]) <= 1e-9 * ledger["motor"], ledger
    for wheel in ledger["wheels"].values():
        for loss in ("slip", "compaction", "damping"):
            assert wheel[loss] >= 0, (loss, wheel)
    assert ledger["towing"] == 0
    # the weight's work as the chassis sinks in: m*g times the sinking, J
    assert 0 < ledger["gravity"] < 10.0 * gravity * 0.02
    met = ledger["rut_met"]
    assert met["front_left"] == met["front_right"] == 0.0
    assert met["rear_left"] > 1e-3  # in the front wheel's rut


@pytest.mark.parametrize("gravity", [9.81, 1.62])
@pytest.mark.parametrize("slope", [10.0, -10.0], ids=["climb", "descent"])
def test_the_rover_ledger_closes_climbing_and_descending(gravity, slope):
    """From the steady motion on the slope (the rear wheels in the front wheels' steady
    ruts): climbing, the motors lift the rover; descending, gravity drives it and the motors
    brake (their work negative: the braking shear and the compaction take the energy)."""
    import math

    ledger = energy.rover_ledger(presets.load(), {"rover.gravity": gravity}, stop=10.0,
                                 slope=math.radians(slope))
    assert ledger["start"] == "steady motion"
    assert abs(ledger["residual"]) <= 1e-9 * abs(ledger["motor"]), ledger
    assert ledger["rut_met"]["rear_left"] > 1e-3
    if slope > 0:
        assert ledger["gravity"] < 0 < ledger["motor"]
    else:
        assert ledger["motor"] < 0 < ledger["gravity"]
    assert ledger["slip"] > 0  # the slip always costs, driving or braking
    assert ledger["compaction"] > 0


def test_a_slope_without_a_steady_motion_is_refused_with_the_way_out(capsys):
    """A slope the rover cannot drive steadily is an input out of its range: one line naming
    it and the way to find the limit, exit 2 (it exited 4, a numerical failure's code)."""
    import math

    from wheelterrain.errors import InputError

    with pytest.raises(InputError, match=r"slope \[deg\] = 40.0 leaves the rover no steady motion"):
        energy.rover_ledger(presets.load(), {}, stop=1.0, slope=math.radians(40.0))
    with pytest.raises(SystemExit) as done:
        main(["energy", "--system", "rover", "--slope", "40"], standalone_mode=True)
    assert done.value.code == 2
    assert "rover --scenario slope|descent" in capsys.readouterr().err


def test_the_cli_runs_the_rovers_ledger_on_a_slope_with_its_ruts(tmp_path, capsys):
    target = tmp_path / "rover.json"
    with pytest.raises(SystemExit) as done:
        main(["energy", "--system", "rover", "--slope", "-10", "--stop", "2", "--json",
              str(target)], standalone_mode=True)
    assert done.value.code == 0
    (row,) = json.loads(target.read_text())["runs"]
    assert row["case"] == "-10 deg, earth"
    assert row["ruts"] is True
    assert row["slope_deg"] == pytest.approx(-10.0)
    assert set(energy.ROVER_TERMS) <= set(row)
    assert "pitch" not in row  # exact kinematics: no approximation left to count
    with pytest.raises(SystemExit) as done:
        main(["energy", "--slope", "5"], standalone_mode=True)
    assert done.value.code == 2
    assert "--slope is the rover's" in capsys.readouterr().err
