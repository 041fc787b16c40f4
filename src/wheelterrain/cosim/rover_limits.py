"""The rover's limits, predicted from its steady motion: the steepest slope it climbs or
descends, and what ends it (``traction``, ``slip_sinkage``, ``motor_torque``, ``stability``).

The steady motion on a slope is the force balance of :func:`wheelterrain.model.rover.steady_balance`
(each rear wheel in its front wheel's rut); its stability is the linearisation of the
continuous-time rover (exact Jacobian of the same Functions) on a soil without memory, or a run
of the perturbed steady motion on one with memory (:func:`holds`), which has no single
linearisation. The scenarios (:mod:`.rover_scenarios`) run the rover to these limits and name
the cause a run met (:func:`run_cause`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from functools import lru_cache

import casadi as ca
import numpy as np

from wheelterrain.cosim import ruts
from wheelterrain.cosim.rover import STEP, RoverResult, Soil, coupled_forces, simulate
from wheelterrain.errors import WheelTerrainError
from wheelterrain.model import api, rover
from wheelterrain.model.slip import ground_speed
from wheelterrain.parameters import NAMES

MOVING = tuple(n for n in rover.STATES if n not in ("position", "elapsed"))
"""The states of steady motion (the position and the clock only advance): what the
linearisation keeps (the input profile is off in a prediction)."""


@lru_cache(maxsize=1)
def _closed_loop() -> tuple[ca.Function, ca.Function]:
    """``rates(x, pt, pr, slope, tow) -> dx`` of the whole rover in continuous time (the
    contacts' forces at the state, ripple as the terrain parameters say) over MOVING, and its
    exact Jacobian ``jac(x, pt, pr, slope, tow)`` by MOVING."""
    x = ca.MX.sym("x", len(rover.STATES))
    pt = ca.MX.sym("pt", len(NAMES), len(rover.WHEELS))
    pr = ca.MX.sym("pr", len(rover.ROVER_NAMES))
    slope, tow = ca.MX.sym("slope"), ca.MX.sym("tow")
    xs = [x[k] for k in range(len(rover.STATES))]
    p = rover.named([pr[k] for k in range(len(rover.ROVER_NAMES))])
    u, _ = coupled_forces(xs, p, pt, [0.0] * len(rover.WHEELS))  # grouser-period mean
    u.update(slope=slope, towing_force=tow)
    dx = ca.vertcat(*rover.rates(tuple(xs), u, p))
    keep = [rover.STATES.index(n) for n in MOVING]
    f = ca.Function("rover_rates_closed", [x, pt, pr, slope, tow], [dx[keep]])
    jac = ca.Function("rover_jac_closed", [x, pt, pr, slope, tow],
                      [ca.jacobian(dx[keep], x)[:, keep]])
    return f, jac


def steady_state_vector(balance: dict, p: Mapping[str, float]) -> np.ndarray:
    """The rover's state (STATES) in the steady motion of :func:`rover.steady_balance`."""
    omega = p["rover.rim_speed"] / p["rover.slip_radius"]
    _, ki = rover.gains(p)
    zf = balance["wheels"]["front_left"]["sinkage"]
    zr = balance["wheels"]["rear_left"]["sinkage"]
    lf, lr = rover.lever(p, "front_left"), rover.lever(p, "rear_left")
    sin_t = (zf - zr) / (lf - lr)
    s = dict.fromkeys(rover.STATES, 0.0)
    s.update(speed=ground_speed(balance["slip"], p["rover.rim_speed"]),
             heave=zf - lf * sin_t,
             pitch=math.asin(sin_t))
    for w in rover.WHEELS:
        s[f"{w}.wheel_speed"] = omega
        s[f"{w}.speed_error_integral"] = balance["wheels"][w]["torque"] / ki
    return np.array([s[n] for n in rover.STATES])


def growth_rate(terrain: Mapping, p: Mapping[str, float], slope: float, slip: float,
                balance_tow: bool = False) -> dict:
    """The largest real part [1/s] of the eigenvalues of the rover's linearisation (exact
    Jacobian of the same Functions) about its steady motion at ``slip`` on ``slope``: > 0, the
    steady motion is unstable. The state is polished by Newton on the continuous rates.
    ``balance_tow``: the towing force is whatever holds the rover at that slip (the pull
    test), else 0 (``slip`` must then be the slope's steady slip)."""
    f, jac = _closed_loop()
    pr = [p[n] for n in rover.ROVER_NAMES]
    balance = rover.steady_balance(terrain, p, slope, slip)
    # each rear wheel in its front wheel's rut (the steady rover's soils)
    pt = np.column_stack([balance["terrain"][w].vector() for w in rover.WHEELS])
    tow = balance["surplus"] if balance_tow else 0.0
    x = steady_state_vector(balance, p)
    keep = [rover.STATES.index(n) for n in MOVING]
    for _ in range(20):
        r = np.array(f(x, pt, pr, slope, tow)).ravel()
        J = np.array(jac(x, pt, pr, slope, tow))
        step = np.linalg.solve(J, -r)
        x[keep] += step
        if np.max(np.abs(step)) < 1e-14 * max(1.0, np.max(np.abs(x))):
            break
    eig = np.linalg.eigvals(np.array(jac(x, pt, pr, slope, tow)))
    top = eig[np.argmax(eig.real)]
    return {"rate": float(top.real), "frequency_hz": float(abs(top.imag) / (2 * math.pi)),
            "state": x}


def steady_slip(terrain: Mapping, p: Mapping[str, float], slope: float) -> float | None:
    """The slip of steady motion on ``slope`` in [SLIDE_SLIP, STALL_SLIP] (the model's slip),
    or None (none there: the wheels cannot hold the rover; downhill, the rover slides: its
    brakes do not hold it below ten times its wheels' rim speed, :func:`locked_limit` says
    whether locked wheels would)."""
    from scipy.optimize import brentq

    def surplus(i: float) -> float:
        return rover.steady_balance(terrain, p, slope, i)["surplus"]

    lo, hi = SLIDE_SLIP, STALL_SLIP
    try:
        if surplus(lo) > 0 or surplus(hi) < 0:
            return None
        return brentq(surplus, lo, hi, xtol=1e-12)
    except WheelTerrainError:
        return None


def locked_limit(terrain: Mapping, p: Mapping[str, float]) -> float | None:
    """The steepest downhill slope [rad, < 0] on which the rover's four wheels, locked
    (slip LOCKED), hold it: the slope where their braking (the steady force balance at the
    locked slip) equals the weight's part along it. None where locked wheels hold it on every
    slope to 60 deg."""
    from scipy.optimize import brentq

    def surplus(slope: float) -> float:
        return rover.steady_balance(terrain, p, slope, LOCKED)["surplus"]

    steep = -math.radians(60)
    try:
        if surplus(steep) <= 0:
            return None
        return brentq(surplus, steep, 0.0, xtol=1e-9)
    except WheelTerrainError:
        return None


def has_memory(terrain: Mapping) -> bool:
    """True where the wheels' soil remembers (``model.soil_memory`` = 1)."""
    return any(terrain[w]["model.soil_memory"] == 1 for w in rover.WHEELS)


PROBE_TIME = 12.0  # s: the shortest a perturbed steady motion is run (PROBE_KICK's test)
PROBE_KICK = 1e-4  # rad/s: the pitch rate the steady motion is started with
PROBE_WHEELBASES = 12
"""Wheelbases of travel a perturbed steady motion is run at least (:func:`probe_time`): on a
soil with memory a disturbance goes round a loop, front wheel -> its rut -> the rear wheel a
wheelbase of travel later -> pitch and load transfer -> front wheel, so its period is one or
two wheelbases of travel (at slip 0.6, 33 s a wheelbase at 3 cm/s rim speed): a fixed 12 s
run saw none of it, and the Moon's climb was predicted stable 3.5 deg past where the run,
ramped, stalled. Twelve wheelbases is six periods of the slower form (measured 0.016 Hz at 31
deg on the Moon, where a 400 s run grows and a 60 s one holds)."""


def probe_time(p: Mapping[str, float], slip: float) -> float:
    """How long [s] :func:`probe` runs the steady motion at ``slip``: PROBE_WHEELBASES of
    travel at its ground speed, at least PROBE_TIME; whole seconds (a whole number of the
    in-process rover's blocks of steps)."""
    speed = ground_speed(slip, p["rover.rim_speed"])
    travel = PROBE_WHEELBASES * p["rover.wheelbase"]
    return float(max(PROBE_TIME, math.ceil(travel / speed))) if speed > 0 else PROBE_TIME


def holds(terrain: Mapping, p: Mapping[str, float], slope: float, slip: float,
          step: float = STEP, balance_tow: bool = False) -> bool:
    """Whether the rover's steady motion at ``slip`` on ``slope`` survives a small
    disturbance (:func:`probe`'s ``holds``)."""
    return probe(terrain, p, slope, slip, step, balance_tow)["holds"]


def probe(terrain: Mapping, p: Mapping[str, float], slope: float, slip: float,
          step: float = STEP, balance_tow: bool = False) -> dict:
    """The rover's steady motion at ``slip`` on ``slope`` disturbed and run: from the steady
    state (:func:`steady_state_vector`, each wheel's plastic sinkage at its sinkage) with the
    pitch rate PROBE_KICK, in process for :func:`probe_time` at that slope. ``holds``: the normal
    forces' deviation from the steady motion over the last second is below its largest over
    the first second (it dies out) and the slip stays below STALL_SLIP. The test for a soil
    with memory, which has no one linearisation: lifted, a wheel unloads along the stiff
    elastic line; pressed, it yields along the soft pressure-sinkage law. ``mode``: where it
    does not hold, the disturbance that grew, measured from the run (:func:`_grown_mode`).
    ``balance_tow``: the towing force is whatever holds the rover at that slip (the pull
    test), else 0 (``slip`` must be the slope's steady slip)."""
    balance = rover.steady_balance(terrain, p, slope, slip)
    tow = balance["surplus"] if balance_tow else 0.0
    x = steady_state_vector(balance, p)
    x[rover.STATES.index("pitch_rate")] += PROBE_KICK
    plastics = [float(rover.wheel_kinematics(list(x), p, w)[0]) for w in rover.WHEELS]
    x0 = [*x, *([0.0] * len(rover.WHEELS)), *plastics]
    soil = Soil(terrain["front_left"])
    run = probe_time(p, slip)
    res = simulate(soil, dict(p), run, step=step, slope=slope, towing=tow, x0=x0,
                   ruts0=ruts.steady_ruts(balance, p, x, soil.map_values()))
    steady = np.array([balance["wheels"][w]["normal_force"] for w in rover.WHEELS])
    strayed = np.array([res.wheels[w]["normal_force"] for w in rover.WHEELS]) - steady[:, None]
    if res.left_domain or res.time.size < round(run / step) - 1:
        return {"holds": False, "mode": _grown_mode(res.time, strayed)}
    deviation = np.max(np.abs(strayed), axis=0)
    second = round(1.0 / step)
    slips = np.array([res.wheels[w]["slip"] for w in rover.WHEELS])
    mode = _grown_mode(res.time, strayed)
    ok = bool(slips.max() < STALL_SLIP
              and (deviation[-second:].max() < deviation[:second].max() or not grows(mode, run)))
    return {"holds": ok, "mode": None if ok else mode}


def grows(mode: dict | None, run: float) -> bool:
    """Whether the disturbance of a probe run of ``run`` s grew: it at least doubles over the
    run's second half (:func:`_grown_mode`'s growth rate). A steady motion computed
    quasi-statically is not the memory soil's own to the last micrometre: the run settles to
    its own nearby, and its deviation from the computed one levels off (measured -0.04 to
    -0.006/s on the Moon's level ground and on climbs that hold); a mode that grows doubles
    within seconds (0.17-0.7/s measured on the climbs past their limit), a run that settles
    never doubles."""
    return mode is not None and mode["growth_rate_per_s"] * run / 2 > math.log(2)


MODE_CHUNKS = 6
"""Pieces of a probe run's second half whose largest deviations give the growth rate."""


def _grown_mode(time: np.ndarray, deviation: np.ndarray) -> dict | None:
    """The disturbance that grew in a probe run, from the wheels' normal-force deviations
    ``deviation`` (one row per wheel of rover.WHEELS) over ``time``: ``leading``, the wheel
    whose force strays furthest at the end; ``growth_rate_per_s``, the slope of the log of
    the largest |deviation| over MODE_CHUNKS pieces of the run's second half (the first
    mixes in the kick's own transient); ``frequency_hz``, half the leading wheel's sign
    changes per second over those pieces (0: a divergence, no oscillation). None for a run
    too short to tell (under 2 * MODE_CHUNKS samples)."""
    n = time.size
    if n < 2 * MODE_CHUNKS:
        return None
    tail = max(1, n // 10)
    lead = int(np.argmax(np.max(np.abs(deviation[:, -tail:]), axis=1)))
    start = n // 2
    x = deviation[lead, start:]
    t = time[start:]
    pieces = np.array_split(np.arange(x.size), MODE_CHUNKS)
    centres = np.array([t[k].mean() for k in pieces])
    peaks = np.array([np.max(np.abs(x[k])) for k in pieces])
    rate = float(np.polyfit(centres, np.log(np.maximum(peaks, 1e-300)), 1)[0])
    changes = int(np.count_nonzero(np.diff(np.sign(x[x != 0])) != 0))
    span = float(t[-1] - t[0]) if t.size > 1 else 0.0
    return {"leading": f"{rover.WHEELS[lead]}.normal_force", "growth_rate_per_s": rate,
            "frequency_hz": changes / (2 * span) if span > 0 else 0.0}


def statically_stable(terrain: Mapping, p: Mapping[str, float], slope: float,
                      slip: float) -> bool:
    """The force balance's slope at a steady slip: more slip must give more net forward force
    (the rover then slows less and the slip falls back). Where sinkage grows with slip faster
    than the thrust (``soil.n1``, bulldozing), the surplus can fall with slip: the steady
    motion is then statically unstable and the slip runs away (``slip_sinkage``)."""
    h = 1e-4
    lo, hi = max(slip - h, LOCKED), min(slip + h, 0.999)
    return (rover.steady_balance(terrain, p, slope, hi)["surplus"]
            > rover.steady_balance(terrain, p, slope, lo)["surplus"])


def pull_slope_at_sinkage(balance: dict) -> float:
    """d(sum of the wheels' pulls)/d(slip) [N] of the rover in steady motion (``balance``,
    :func:`rover.steady_balance`) with every wheel held at its sinkage there, each on its
    soil there (a rear wheel in its rut): the pull the slip changes before the wheels sink
    to the new slip's depth. Negative, more slip gives less pull at once: the slip-sinkage
    law lowers the load a sinkage carries, and so the thrust, faster than the shear
    displacement raises it (a rear wheel that inherits its rut's shear has it mobilised
    already); the rover slows, its slip grows, and the loop runs on the time scale of its
    speed, m*omega*R / |this| (0.3 s over 11 N at 30.5 deg on Earth), unless the wheels sink
    to the new balance first: the dynamic side of ``slip_sinkage``. Measured: on Earth it
    turns at 29.2 deg and the rover linearised on the pressing branch turns unstable with it
    (between 29.2 and 29.4 deg); on the Moon it turns at 27.3 deg, where the ramped climb
    stalls, the linearisation later (-0.26/s at 27.6 deg); with model.rut_shear 0 it stays
    positive and the linearisation stable."""
    slip = balance["slip"]
    h = 1e-4
    lo, hi = max(slip - h, LOCKED), min(slip + h, 0.999)
    total = 0.0
    for w in rover.WHEELS:
        z, ground = balance["wheels"][w]["sinkage"], balance["terrain"][w]
        total += (api.contact_forces(ground, z, hi)["drawbar_pull"]
                  - api.contact_forces(ground, z, lo)["drawbar_pull"]) / (hi - lo)
    return total


STALL_CAUSES = ("traction", "slip_sinkage", "stability", "motor_torque", "domain")
"""What can end a slope or descent run (``stall_cause``), in the order they are tested."""


def steady_cause(terrain: Mapping, p: Mapping[str, float], slope: float,
                 slip: float | None = None) -> str | None:
    """Which steady condition fails on ``slope``, or None: no steady slip in
    [SLIDE_SLIP, STALL_SLIP] (``traction``: the wheels cannot hold the rover; downhill, it
    slides), the force balance falls with slip there (``slip_sinkage``, with the wheels
    sunk to each slip's depth: :func:`statically_stable`), or the motors cannot give its
    torque (``motor_torque``, rover.motor_torque_limit). ``slip``: the slope's steady slip
    where the caller has it (:func:`steady_slip`)."""
    i = steady_slip(terrain, p, slope) if slip is None else slip
    if i is None:
        return "traction"
    if not statically_stable(terrain, p, slope, i):
        return "slip_sinkage"
    balance = rover.steady_balance(terrain, p, slope, i)
    if max(abs(balance["wheels"][w]["torque"]) for w in rover.WHEELS) \
            > p["rover.motor_torque_limit"]:
        return "motor_torque"
    return None


def unstable_cause(terrain: Mapping, p: Mapping[str, float], slope: float,
                   slip: float | None = None) -> str:
    """What a disturbance that grew out of a steady motion that exists, is statically stable
    and within the motors' torque (``slip``, else the slope's steady slip) is: on a soil with
    memory, ``slip_sinkage`` where the rover's pull at its wheels' sinkage falls with slip
    (:func:`pull_slope_at_sinkage`; measured: on Earth the rover linearised on the pressing
    branch turns unstable where it turns, the chassis' pitch inertia and speed loops barely
    move that growth, and without the rut's inherited shear neither happens), else
    ``stability``. On the elastic
    soil it stays ``stability``: there the pull at the wheels' sinkage falls with slip from
    10.5 deg on the Moon while the rover holds to 12.3 deg, so the test does not say what
    grew."""
    if not has_memory(terrain):
        return "stability"
    i = steady_slip(terrain, p, slope) if slip is None else slip
    if i is None:
        return "stability"
    falls = pull_slope_at_sinkage(rover.steady_balance(terrain, p, slope, i)) < 0
    return "slip_sinkage" if falls else "stability"


def run_cause(res: RoverResult, terrain: Mapping, p: Mapping[str, float],
              slope: float) -> str:
    """Which of STALL_CAUSES ended a run that stalled or slid at ``slope`` [rad]: ``domain``
    where it left the model's domain other than by its slip (a non-finite value, a refused
    step); else the first steady condition that fails there (:func:`steady_cause`, on the
    ripple-free soil ``terrain``); else what the disturbance that grew was
    (:func:`unstable_cause`: ``slip_sinkage`` or ``stability``): a steady motion that the
    motors can drive exists and is statically stable, and the run did not hold it."""
    if res.left_domain and "slip reached" not in res.left_domain:
        return "domain"
    i = steady_slip(terrain, p, slope)  # once, for both tests
    if i is None:
        return "traction"
    return steady_cause(terrain, p, slope, i) or unstable_cause(terrain, p, slope, i)


def limit_slope(terrain: Mapping, p: Mapping[str, float], direction: int = 1,
                tolerance: float = 1e-4,
                trials: Callable[[int, int], None] | None = None) -> dict:
    """The steepest slope [rad] (uphill for ``direction`` 1, downhill for -1) on which the rover
    has a steady motion that it also holds: a steady slip exists in [SLIDE_SLIP, STALL_SLIP]
    (else ``traction``: the wheels cannot hold the rover, downhill it slides), more slip gives
    more net force there (else ``slip_sinkage``, :func:`statically_stable`), and a disturbance
    dies out (else ``stability``, or on a soil with memory ``slip_sinkage`` where the pull at
    the wheels' sinkage falls with slip, :func:`unstable_cause`): on a soil without memory
    the linearisation about the steady motion has no eigenvalue with a positive real part; on
    a soil with memory, which has none, the perturbed motion is run (:func:`holds`).
    Bisection on the slope from level ground, every condition checked at every trial;
    ``limit`` says which one ended it (a tolerance of 1e-3 rad where the motion is run).
    ``mode``: for a disturbance that grew (``stability``, or ``slip_sinkage`` on a soil with
    memory), the disturbance that grew at the first slope past the limit
    (:func:`_grown_mode` from the probe run; on a soil without memory the eigenvalue's real
    part and frequency, ``leading`` "eigenvalue"), else None. ``trials(k, n)`` is told each
    trial done, of the n the bisection takes at most."""
    top = direction * math.radians(60)
    memory = has_memory(terrain)
    if memory:
        tolerance = max(tolerance, 1e-3)
    most = 2 + math.ceil(math.log2(abs(top) / tolerance))
    done = 0

    def verdict(slope: float) -> str | None:
        nonlocal done
        try:
            return _verdict(slope)
        finally:
            done += 1
            if trials is not None:
                trials(done, most)

    modes: dict[float, dict | None] = {}

    def _verdict(slope: float) -> str | None:
        i = steady_slip(terrain, p, slope)
        if i is None:
            return "traction"
        cause = steady_cause(terrain, p, slope, i)
        if cause is not None:
            return cause
        if memory:
            run = probe(terrain, p, slope, i)
            modes[slope] = run["mode"]
            return None if run["holds"] else unstable_cause(terrain, p, slope, i)
        g = growth_rate(terrain, p, slope, i)
        modes[slope] = {"leading": "eigenvalue", "growth_rate_per_s": g["rate"],
                        "frequency_hz": g["frequency_hz"]}
        return "stability" if g["rate"] > 0 else None

    def mode(slope: float, why: str | None) -> dict | None:
        return modes.get(slope) if why in ("stability", "slip_sinkage") else None

    level = verdict(0.0)  # each verdict once: on a soil with memory it runs the rover
    if level is not None:
        return {"slope": 0.0, "limit": level, "slip": None, "mode": mode(0.0, level)}
    why = verdict(top)
    if why is None:
        return {"slope": top, "limit": None, "slip": steady_slip(terrain, p, top),
                "mode": None}
    lo, hi = 0.0, top
    while abs(hi - lo) > tolerance:
        mid = (lo + hi) / 2
        v = verdict(mid)
        if v is None:
            lo = mid
        else:
            hi, why = mid, v
    return {"slope": lo, "limit": why, "slip": steady_slip(terrain, p, lo),
            "mode": mode(hi, why)}


STALL_SLIP = 0.95
"""Slip at which the rover counts as stalled: it moves at 5 % of its wheels' rim speed."""
LOCKED = -1.0
"""The model's slip of a locked wheel: the most a wheel can brake."""
SLIDE_SLIP = -0.9
"""Slip at which a descending rover counts as sliding: it moves at ten times its wheels' rim
speed, its brakes no longer governing its speed (the mirror of STALL_SLIP)."""
