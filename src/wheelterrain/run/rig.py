"""``wheelterrain reproduce`` as one call: the paper's C1-C4 on the rig's FMU pair (the fastest
built, or the one asked for), compared with Table III, and its files written as one set."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

from wheelterrain import files, presets
from wheelterrain.cosim import master, ssp
from wheelterrain.parameters import ParameterSet
from wheelterrain.run.rover import Progress


@dataclass
class RigRun:
    """What :func:`reproduce` did."""

    results: list[master.CaseResult]
    rows: list[dict]
    mae: dict
    folder: Path
    flavour: str
    note: str | None
    """Where a faster pair could be used and is not: what to do (None where the fastest is)."""
    workers: int
    elapsed: float
    written: list[Path]
    in_sample_on: list[str] | None
    """The cases the preset was fitted on (its figures on them are in-sample), or None."""


def fast_pair_note(folder: Path, fmu_dir: Path | None, interface: str) -> str | None:
    """What to do to run the native pair where the pythonfmu pair was chosen by default."""
    if fmu_dir is not None or interface != "cs" or Path(folder).name == "native":
        return None
    native = Path(folder) / "native"
    why = ("is older than the pythonfmu pair here (a plain `wheelterrain build` rebuilds only "
           "those)" if (native / "WheelTerrain.fmu").is_file() else "is not built")
    return (f"using the pythonfmu pair, the slow one (~1 min): {native} {why}; "
            "`wheelterrain build --flavor all` (or --flavor native) makes the native pair, "
            "which runs C1-C4 in seconds")


def reproduce(ps: ParameterSet, preset: str, out: Path, fmu_dir: Path | None = None,
              interface: str = "cs", workers: int | None = None, step: float = master.STEP,
              stop: float = master.STOP_TIME, fitted: bool = True,
              progress: Progress | None = None) -> RigRun:
    """C1-C4 through the FMU pair in ``fmu_dir`` (default: the fastest built,
    :func:`wheelterrain.cosim.master.choose_fmus`), the cases in ``workers`` processes; writes
    OUT/<case>.csv, OUT/<case>.png, OUT/means.png and OUT/<case>.ssp as one set. ``fitted``:
    the preset is as shipped (its fitted cases make its figures in-sample)."""
    from wheelterrain import plots

    paper = master.table3()
    folder, flavour = master.choose_fmus(fmu_dir, interface)
    workers = workers or master.default_workers()
    started = time.perf_counter()
    done: list[str] = []
    cases = len(paper["cases"])

    def case_done(case: str) -> None:
        done.append(case)
        if progress is not None:
            progress("co-simulating C1-C4" if interface == "cs" else "integrating C1-C4 (ME)",
                     len(done), cases)

    if progress is not None:  # the bar is drawn from the start
        progress("co-simulating C1-C4" if interface == "cs" else "integrating C1-C4 (ME)", 0,
                 cases)
    results = master.reproduce(folder, ps, step=step, stop=stop, progress=case_done,
                               interface=interface, workers=workers)
    elapsed = time.perf_counter() - started
    rows = master.comparison(results)
    mae = master.mean_absolute_errors(rows)
    fitted_on = presets.read(preset)["provenance"].get("fitted_on") if fitted else None
    experiment = {row["case"]: row["experiment"] for row in paper["cases"]}
    out = Path(out)
    names = []
    with files.one_set(out) as staging:  # all files, or none if interrupted
        for r in results:
            master.write_csv(staging / f"{r.case}.csv", r)
            plots.time_series(r, experiment[r.case], staging / f"{r.case}.png")
            ssp.write(staging / f"{r.case}.ssp", folder, r.case, ps, r.slip_paper,
                      paper["load_N"], paper["wheel_speed_m_per_s"], stop, step)
            names += [f"{r.case}.csv", f"{r.case}.png", f"{r.case}.ssp"]
        plots.means_bar_chart(rows, staging / "means.png", preset, fitted_on)
        names.append("means.png")
    return RigRun(results, rows, mae, folder, flavour, fast_pair_note(folder, fmu_dir, interface),
                  workers, elapsed, [out / n for n in names], fitted_on)
