"""Cross-wheel validation speed: the nested protocol with and without remembered fits.

    python benchmarks/crosswheel.py [--repeats 3] [--starts 3] [--quick] [--json]

The nested leave-one-dataset-out protocol asks for the same least-squares fit several times
(the fit on "all but A and B" is an inner fold of the rule and of the held-out discrepancy in
outer folds A and B). ``wheelterrain.fit.crosswheel.fit_constants`` remembers fits by their
content; this script measures what that saves.

Times what `wheelterrain validate` runs on the cross-wheel data (every shipped form held out,
the nested protocol, the rule on all data sets). Prints the median of ``--repeats`` runs, each
starting with nothing remembered, and the same with remembering switched off (the baseline,
measured in the same run), their ratio, and how many fits each asked for and ran. Both ways
must give the same rows; the script says whether they did. ``--quick``: one start per fit and
one repeat (about a minute).
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

from wheelterrain.fit import crosswheel as cw
from wheelterrain.fit import datasets


def counted_run(job, remember: bool) -> tuple[float, object, int, int]:
    """(seconds, rows, fits asked, fits run) of one cold run of ``job``."""
    kept, fit = cw.FITS_KEPT, cw._fit
    ran = asked = 0

    def counting_fit(*args):
        nonlocal ran
        ran += 1
        return fit(*args)

    def counting_ask(*args, **kwargs):
        nonlocal asked
        asked += 1 if args[0].free else 0  # a form with nothing free fits nothing
        return ask(*args, **kwargs)

    ask = cw.fit_constants
    cw.FITS_KEPT = kept if remember else 0
    cw._fit, cw.fit_constants = counting_fit, counting_ask
    cw.clear_fits()
    try:
        t = time.perf_counter()
        rows = job()
        return time.perf_counter() - t, rows, asked, ran
    finally:
        cw.FITS_KEPT, cw._fit, cw.fit_constants = kept, fit, ask
        cw.clear_fits()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--starts", type=int, default=3,
                    help="least-squares starts per fit (validate uses 3)")
    ap.add_argument("--quick", action="store_true", help="one start, one repeat")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    if a.quick:
        a.starts, a.repeats = 1, 1
    shipped = datasets.shipped()

    def job():
        return (cw.lodo_rows(shipped, a.starts), cw.nested_rows(shipped, a.starts),
                cw.choose(shipped, a.starts))

    out = {}
    for label, remember in (("remembered", True), ("baseline", False)):
        runs = [counted_run(job, remember) for _ in range(max(a.repeats, 1))]
        out[label] = {"median_s": statistics.median(r[0] for r in runs),
                      "fits_asked": runs[0][2], "fits_run": runs[0][3]}
        out[label + "_rows"] = json.dumps(runs[0][1], sort_keys=True, default=str)
    same = out.pop("remembered_rows") == out.pop("baseline_rows")
    result = {"job": "validate's cross-wheel work",
              "starts": a.starts, "repeats": a.repeats, **out,
              "speedup": out["baseline"]["median_s"] / out["remembered"]["median_s"],
              "same_rows": same}
    if a.json:
        print(json.dumps(result, indent=1))
        return
    print(f"{result['job']}, {a.starts} starts, median of {a.repeats}:")
    for label in ("remembered", "baseline"):
        r = out[label]
        print(f"  {label:10s} {r['median_s']:7.1f} s  fits asked {r['fits_asked']}, "
              f"run {r['fits_run']}")
    print(f"  speed-up {result['speedup']:.2f}x; same rows both ways: {same}")


if __name__ == "__main__":
    main()
