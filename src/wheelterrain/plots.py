"""Plots of the C1-C4 co-simulation: time series per case (like the paper's figures) and the
means against Table III. matplotlib with the Agg backend (no display needed)."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from wheelterrain.cosim.master import CaseResult
from wheelterrain.cosim.rover_scenarios import LIMIT_SCENARIOS
from wheelterrain.files import replacing


def _save(fig, path: Path) -> None:
    try:
        with replacing(path) as partial:  # never a half-written plot
            fig.savefig(partial, dpi=120, format="png")
    finally:
        plt.close(fig)


def time_series(result: CaseResult, experiment: dict, path: Path) -> None:
    """Drawbar pull, normal force and sinkage over time, the averaging window shaded, the
    experiment's mean as a dashed line."""
    s = result.series
    fig, axes = plt.subplots(3, 1, figsize=(8, 7.5), sharex=True)
    for ax, (key, label, scale, unit) in zip(axes, QUANTITIES, strict=True):
        ax.plot(s["time"], scale * s[key], lw=0.8, label=result.master or "co-simulation")
        ax.axhline(scale * result.means[key], color="C0", ls=":",
                   label=f"window mean {scale * result.means[key]:.2f} {unit}")
        ax.axhline(scale * experiment[key], color="C3", ls="--",
                   label=f"experiment mean {scale * experiment[key]:.2f} {unit}")
        ax.axvspan(*result.window, color="0.9", zorder=0)
        ax.set_ylabel(label)
        ax.legend(loc="best", fontsize=8)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("time [s] (shaded: averaging window)")
    fig.suptitle(f"{result.case}: slip s = {result.slip_paper:g} (paper's definition)")
    fig.tight_layout()
    _save(fig, path)


QUANTITIES = (("drawbar_pull", "drawbar pull [N]", 1.0, "N"),
              ("normal_force", "normal force [N]", 1.0, "N"),
              ("sinkage", "sinkage [mm]", 1e3, "mm"))
"""The rig's three measured quantities: key, axis label, scale to the shown unit, unit."""


def means_bar_chart(rows: list[dict], path: Path, preset: str,
                    fitted_on: list[str] | None = None) -> None:
    """Simulated means, experiment and the paper's own simulation per case (top), and the
    residuals against the experiment, this model's and the paper's simulation's (bottom).
    ``fitted_on``: the cases the preset was fitted on; its MAE is then labelled in-sample."""
    in_sample = " (in-sample)" if set(fitted_on or ()) & {r["case"] for r in rows} else ""
    fig, axes = plt.subplots(2, 3, figsize=(13, 7), sharex=True,
                             gridspec_kw={"height_ratios": (3, 2)})
    cases = [r["case"] for r in rows]
    x = np.arange(len(cases))
    w = 0.27
    for k, (key, label, scale, unit) in enumerate(QUANTITIES):
        top, bottom = axes[0, k], axes[1, k]
        ours = np.array([scale * r[key] for r in rows])
        measured = np.array([scale * r[f"{key}_experiment"] for r in rows])
        paper = np.array([scale * r[f"{key}_paper_simulation"] for r in rows])
        top.bar(x - w, ours, w, label=f"this model ({preset})")
        top.bar(x, measured, w, label="experiment")
        top.bar(x + w, paper, w, label="paper's simulation")
        top.set_ylabel(label)
        bottom.bar(x - w / 2, ours - measured, w, color="C0",
                   label=f"this model: MAE {np.mean(np.abs(ours - measured)):.2f} {unit}"
                   f"{in_sample}")
        bottom.bar(x + w / 2, paper - measured, w, color="C2",
                   label=f"paper's simulation: MAE {np.mean(np.abs(paper - measured)):.2f} "
                   f"{unit}")
        bottom.set_ylabel(f"{label.split(' [')[0]} - experiment [{unit}]")
        # below the axes: inside, a legend can hide a bar
        bottom.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.12))
        for ax in (top, bottom):
            ax.axhline(0, color="k", lw=0.6)
            ax.grid(axis="y", alpha=0.3)
        bottom.set_xticks(x, cases)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="upper center", ncol=3, fontsize=9,
               bbox_to_anchor=(0.5, 0.955))
    fig.suptitle("C1-C4 means against Table III (bottom: residuals against the experiment)")
    fig.tight_layout(rect=(0, 0, 1, 0.93))
    _save(fig, path)


SWEEP_PANELS = {
    "default": (("drawbar_pull", "drawbar pull [N]", 1.0),
                ("contact_sinkage", "sinkage [mm]", 1e3)),
    "slip_angle": (("lateral_force", "lateral force [N] (to the wheel's left)", 1.0),
                   ("aligning_moment", "aligning moment [N·m] (counter-clockwise from above)",
                    1.0),
                   ("drawbar_pull", "drawbar pull [N]", 1.0)),
}
"""What :func:`sweep_curves` draws: drawbar pull and sinkage; against the slip angle, the side
force, the aligning moment and the pull (output, axis label, scale)."""


def _unit_suffix(unit: str) -> str:
    """A unit to print after a value: none for a dimensionless one ("1")."""
    return "" if unit == "1" else unit


def sweep_curves(rows: list[dict], x: str, group: list[str], path: Path, title: str) -> None:
    """The sweep's outputs against ``x`` (:data:`SWEEP_PANELS`; a slip angle drawn in degrees),
    one line per combination of the ``group`` axes (infeasible points are gaps)."""
    from wheelterrain.fmu.variables import units as variable_units

    units = {**variable_units(), "slip": "1"}  # the sweep's axes: slip, load, table names
    panels = SWEEP_PANELS.get(x, SWEEP_PANELS["default"])
    degrees = x == "slip_angle"
    fig, axes = plt.subplots(1, len(panels), figsize=(6 * len(panels), 4.5))
    keys = sorted({tuple(r[g] for g in group) for r in rows})
    for key in keys:
        sel = [r for r in rows if tuple(r[g] for g in group) == key]
        sel.sort(key=lambda r: r[x])
        xs = [math.degrees(r[x]) if degrees else r[x] for r in sel]
        label = ", ".join(f"{g} = {v:.4g} {_unit_suffix(units.get(g, ''))}".rstrip()
                          for g, v in zip(group, key, strict=True)) or None
        for ax, (name, _, scale) in zip(axes, panels, strict=True):
            ax.plot(xs, [scale * r[name] for r in sel], marker="o", ms=3, label=label)
    for ax, (_, label, _) in zip(axes, panels, strict=True):
        ax.set_xlabel("slip angle [deg]" if degrees else f"{x} [{units.get(x, '1')}]")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    if group:
        axes[0].legend(fontsize=7)
    fig.suptitle(title)
    fig.tight_layout()
    _save(fig, path)


def sensitivity_bars(elasticity: dict, swing: dict, path: Path, title: str) -> None:
    """Elasticities and swings over the plausible ranges, ranked by drawbar-pull elasticity."""
    names = sorted(elasticity, key=lambda n: -abs(elasticity[n]["drawbar_pull"]))
    y = np.arange(len(names))
    fig, axes = plt.subplots(1, 2, figsize=(12, 4))
    axes[0].barh(y - 0.2, [abs(elasticity[n]["drawbar_pull"]) for n in names], 0.4,
                 label="drawbar pull")
    axes[0].barh(y + 0.2, [abs(elasticity[n]["sinkage"]) for n in names], 0.4, label="sinkage")
    axes[0].set_xlabel("|elasticity| (dy/dp)(p/y) at the preset [1]")
    axes[1].barh(y - 0.2, [swing[n]["drawbar_pull"] for n in names], 0.4, label="drawbar pull [N]")
    axes[1].barh(y + 0.2, [1e3 * swing[n]["sinkage"] for n in names], 0.4, label="sinkage [mm]")
    axes[1].set_xlabel("swing over the plausible range (one at a time, FMU sweep) [N, mm]")
    for ax in axes:
        ax.set_yticks(y, names)
        ax.invert_yaxis()
        ax.grid(axis="x", alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    _save(fig, path)


def closed_loop(result, scenario, path: Path) -> None:
    """Slip and its reference, the command and torque, sinkage, drawbar pull and the solve time
    per MPC step of one closed-loop run; the scored samples unshaded."""
    s = result.series
    t = s["time"]
    fig, axes = plt.subplots(5, 1, figsize=(8, 10), sharex=True)
    axes[0].plot(t, s["slip"], lw=0.8, label="slip (plant)")
    axes[0].plot(t, s["slip_reference"], "k--", lw=0.8, label="reference")
    axes[0].set_ylabel("slip [1]")
    axes[1].plot(t, s["motor_torque"], lw=0.8, label="motor torque [N.m]")
    axes[1].plot(t, s["command"], lw=0.8, label="speed command [rad/s]")
    axes[1].set_ylabel("drive [N.m, rad/s]")
    axes[2].plot(t, 1e3 * s["sinkage"], lw=0.8)
    axes[2].set_ylabel("sinkage [mm]")
    axes[3].plot(t, s["drawbar_pull"], lw=0.8)
    axes[3].set_ylabel("drawbar pull [N]")
    steps = np.arange(len(result.solve_times)) * result.settings.interval
    axes[4].semilogy(steps, 1e3 * result.solve_times, ".", ms=2)
    axes[4].set_ylabel("solve time [ms]")
    axes[4].set_xlabel("time [s]")
    unscored = ~scenario.scored(t)
    for ax in axes:
        ax.fill_between(t, 0, 1, where=unscored, color="0.9", transform=ax.get_xaxis_transform(),
                        zorder=0)
        ax.grid(True, alpha=0.3)
    for ax in axes[:2]:
        ax.legend(loc="best", fontsize=8)
    settings = result.settings
    axes[0].set_title(f"NMPC '{scenario.name}' on the {result.plant} plant: {settings.solver}"
                      f"{' (compiled)' if settings.compiled else ''}, horizon "
                      f"{settings.horizon} x {settings.interval:g} s")
    fig.tight_layout()
    _save(fig, path)


def _wheel_lines(ax, t, wheels: dict, key: str, scale: float, stride: int) -> None:
    """``key`` per wheel; where the left and right wheels of an axle agree (a straight run on
    uniform ground: symmetric) one line for the axle, labelled so, instead of two lines drawn
    over each other."""
    for axle, ls in (("front", "-"), ("rear", "--")):
        left, right = wheels[f"{axle}_left"][key], wheels[f"{axle}_right"][key]
        if np.allclose(left, right, rtol=1e-9, atol=1e-12, equal_nan=True):
            ax.plot(t[::stride], scale * left[::stride], lw=0.9, ls=ls,
                    label=f"{axle} (left = right)")
            continue
        for side in ("left", "right"):
            ax.plot(t[::stride], scale * wheels[f"{axle}_{side}"][key][::stride], lw=0.8,
                    ls=ls, label=f"{axle}_{side}")


def rover(result, figures: dict, path: Path) -> None:
    """One rover scenario: per axle (or wheel, where left and right differ) over time: slip,
    sinkage, normal force, drawbar pull; the chassis' speed; the slope and towing force, each
    on its own axis; and the scenario's limit beside its prediction: slip against slope (slope
    and descent, the predicted stall or slide slope marked), or the pull-slip curve against
    the four single-wheel curves (pull-test)."""
    t = result.time
    stride = max(len(t) // 4000, 1)  # at most ~4000 points a line
    scenario = figures["scenario"]
    limit_panel = scenario in LIMIT_SCENARIOS
    rows = 7 if limit_panel else 6
    fig, axes = plt.subplots(rows, 1, figsize=(8, 1.9 * rows + 1), sharex=False)
    quantities = (("slip", 1.0, "slip (braking: skid) [1]"), ("sinkage", 1e3, "sinkage [mm]"),
                  ("normal_force", 1.0, "normal force [N]"),
                  ("drawbar_pull", 1.0, "drawbar pull [N]"))
    for ax, (key, scale, label) in zip(axes, quantities, strict=False):
        _wheel_lines(ax, t, result.wheels, key, scale, stride)
        ax.set_ylabel(label)
    axes[0].legend(loc="best", fontsize=8, ncol=2)
    axes[4].plot(t[::stride], 1e3 * result.chassis["speed"][::stride], lw=0.8, color="C2")
    axes[4].set_ylabel("chassis speed [mm/s]")
    ax = axes[5]
    ax.plot(t[::stride], np.degrees(result.inputs["slope"][::stride]), lw=0.8, color="C3")
    ax.set_ylabel("slope [deg]", color="C3")
    twin = ax.twinx()
    twin.plot(t[::stride], result.inputs["towing_force"][::stride], lw=0.8, color="C4")
    twin.set_ylabel("towing force [N]", color="C4")
    for a in axes[:6]:
        a.set_xlabel("time [s]")
        a.grid(True, alpha=0.3)
    if limit_panel:
        ax = axes[6]
        if scenario == "pull-test":
            curve = np.array(figures.get("pull_curve") or np.empty((0, 2)))
            predicted = figures.get("predicted_pull") or []
            if len(curve):
                ax.plot(curve[:, 0], curve[:, 1], "o-", ms=3, lw=0.8,
                        label="rover: towing force held")
                ax.plot(curve[:, 0], predicted, "s--", ms=3, lw=0.8,
                        label="four single-wheel steady pulls at the axle loads")
            stall = figures.get("stall_towing_force")
            if stall is not None:
                ax.axhline(stall, color="k", ls=":", lw=0.8, label=f"stalls at {stall:.2f} N")
            ax.set_xlabel("slip (braking: skid) [1]")
            ax.set_ylabel("pull [N]")
        else:
            ax.plot(np.degrees(result.inputs["slope"][::stride]),
                    result.wheels["front_left"]["slip"][::stride], lw=0.8,
                    label="simulated (front left)")
            key = ("predicted_stall_slope_deg" if scenario == "slope"
                   else "predicted_descent_limit_deg")
            what = ("predicted_stall_limit" if scenario == "slope"
                    else "predicted_descent_limit")
            rows = figures.get("slip_vs_slope") or []
            if rows:
                ax.plot([r["slope_deg"] for r in rows], [r["mean_slip"] for r in rows], "o",
                        ms=3, color="C0", label="four wheels' mean at each whole degree")
                deep = ax.twinx()
                deep.plot([r["slope_deg"] for r in rows],
                          [1e3 * r["mean_sinkage"] for r in rows], "s", ms=3, color="C5")
                deep.set_ylabel("mean sinkage [mm]", color="C5")
            pred = figures.get(key)
            if pred is not None:
                ax.axvline(pred, color="k", ls="--", lw=0.8,
                           label=f"predicted {'stall' if scenario == 'slope' else 'slide'} "
                                 f"{pred:.2f} deg ({figures.get(what)})")
            if figures.get("stall_cause"):
                ax.set_title(f"ended by: {figures['stall_cause']}", fontsize=9)
            ax.set_xlabel("slope [deg]")
            ax.set_ylabel("slip (braking: skid) [1]")
        ax.legend(loc="best", fontsize=8)
        ax.grid(True, alpha=0.3)
    axes[0].set_title(f"rover '{scenario}' ({figures['gravity']}), {figures['engine']}")
    fig.tight_layout()
    _save(fig, path)


def multipass(runs: list[dict], path: Path, title: str,
              compare: tuple[str, list[dict]] | None = None,
              reference: list[dict] | None = None) -> None:
    """Multi-pass on the rig: the traction coefficient per pass (left) and the sinkage from
    the original surface with the rut each pass leaves (right), one line per slip.
    ``compare``: (label, runs) of the same slips with other settings, their traction drawn
    dashed on the left. ``reference``: the SCM reference's runs at the same slips, traction
    and sinkage drawn dotted."""
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    for k, run in enumerate(reference or []):
        rows = run["passes"]
        n = [r["pass"] for r in rows]
        left.plot(n, [r["traction_coefficient"] for r in rows], "x:", color=f"C{k}",
                  label=f"slip {run['slip']:.3g}, SCM reference")
        right.plot(n, [1e3 * r["sinkage"] for r in rows], "x:", color=f"C{k}",
                   label=f"slip {run['slip']:.3g}: SCM reference")
    for k, run in enumerate(compare[1] if compare else []):
        rows = run["passes"]
        left.plot([r["pass"] for r in rows], [r["traction_coefficient"] for r in rows], "^--",
                  color=f"C{k}", alpha=0.7, label=f"slip {run['slip']:.3g}, {compare[0]}")
    for k, run in enumerate(runs):
        rows = run["passes"]
        n = [r["pass"] for r in rows]
        label = f"slip {run['slip']:.3g}"
        left.plot(n, [r["traction_coefficient"] for r in rows], "o-", color=f"C{k}",
                  label=label)
        right.plot(n, [1e3 * r["sinkage"] for r in rows], "o-", color=f"C{k}",
                   label=f"{label}: sinkage")
        right.plot(n, [1e3 * r["rut_left"] for r in rows], "s--", color=f"C{k}", alpha=0.6,
                   label=f"{label}: rut left")
    left.set_ylabel("traction coefficient (drawbar pull / load)")
    right.set_ylabel("depth below the original surface [mm]")
    for ax in (left, right):
        ax.set_xlabel("pass")
        ax.set_xticks(range(1, max(len(r["passes"]) for r in runs) + 1))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="best")
    fig.suptitle(f"Multi-pass on the rig ({title})")
    fig.tight_layout()
    _save(fig, path)


def _tool_against_python(ax, x: str, run: dict, marks: tuple[dict, dict], title: str) -> None:
    """Drawbar pull (left axis) and sinkage (right axis) against ``x``: the Python model as
    lines, the tool's run (``run["tool"]``, named ``run["name"]``) with ``marks`` (pull,
    sinkage) over them."""
    other = ax.twinx()
    py, tool = run["python"], run["tool"]
    tool_x = tool.get(x, py[x])
    ax.plot(py[x], py["drawbar_pull"], "-", color="C0", label="drawbar pull, Python")
    ax.plot(tool_x, tool["drawbar_pull"], label=f"drawbar pull, {run['name']}", **marks[0])
    other.plot(py[x], 1e3 * np.asarray(py["sinkage"]), "-", color="C1", label="sinkage, Python")
    other.plot(tool_x, 1e3 * np.asarray(tool["sinkage"]), label=f"sinkage, {run['name']}",
               **marks[1])
    ax.set_xlabel({"slip": "slip (braking: skid)", "time": "time [s]"}[x])
    ax.set_ylabel("drawbar pull [N]", color="C0")
    other.set_ylabel("sinkage [mm]", color="C1")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    lines, more = ax.get_legend_handles_labels(), other.get_legend_handles_labels()
    ax.legend(lines[0] + more[0], lines[1] + more[1], fontsize=8, loc="lower right")


def modelica_examples(ramp: dict, rig: dict | None, path: Path, rover: dict | None = None
                      ) -> None:
    """The Modelica library's examples run by a Modelica tool against the Python model: the
    quasi-static wheel's slip ramp (drawbar pull and sinkage against slip), where given the
    rover's climb (one wheel's drawbar pull and sinkage against time) and, where run, the rig
    at C2 on MSL components (drawbar pull and sinkage against time).
    ``ramp``/``rig``/``rover``: {"tool": {column: values}, "python": {column: values},
    "name": str}."""
    panels = 1 + (rover is not None) + (rig is not None)
    fig, axes = plt.subplots(1, panels, figsize=(5.5 * panels, 4.2), squeeze=False)
    _tool_against_python(axes[0, 0], "slip", ramp, (
        {"marker": "o", "ls": "none", "color": "C0", "mfc": "none"},
        {"marker": "s", "ls": "none", "color": "C1", "mfc": "none"}),
        "Examples.SlipRamp (no MSL)")
    k = 1
    for run, title in ((rover, "Examples.FMUTwin.RoverSlope: rear-left wheel"),
                       (rig, "Examples.RigC2 (MSL flanges and blocks)")):
        if run:
            _tool_against_python(axes[0, k], "time", run, (
                {"ls": ":", "color": "k", "lw": 1.2}, {"ls": ":", "color": "C3", "lw": 1.2}),
                title)
            k += 1
    fig.suptitle("The generated Modelica library, simulated by rumoca, against the Python model")
    fig.tight_layout()
    _save(fig, path)
