"""The figures say what they show: a unit on every axis, units on the numbers in legends, the
master that ran the co-simulation, and the residuals beside the C1-C4 means."""

from __future__ import annotations

import re

import numpy as np
import pytest

from wheelterrain import plots
from wheelterrain.cosim.master import CaseResult

UNIT = re.compile(r"\[[^\]]+\]")


@pytest.fixture
def figures(monkeypatch):
    """The figures the plot functions make, kept instead of saved."""
    made = []

    def keep(fig, path):
        made.append(fig)

    monkeypatch.setattr(plots, "_save", keep)
    yield made
    for fig in made:
        plots.plt.close(fig)


def _labelled_axes(fig):
    return [ax for ax in fig.axes if ax.has_data()]


def test_time_series_names_the_master_and_every_unit(figures, tmp_path):
    t = np.linspace(0, 30, 301)
    series = {"time": t, "drawbar_pull": 10 + np.sin(t), "normal_force": 62 + 0 * t,
              "sinkage": 0.015 + 0 * t}
    means = {"drawbar_pull": 10.0, "normal_force": 62.0, "sinkage": 0.015}
    result = CaseResult("C2", 0.25, means, (10.0, 30.0), series, 0.1,
                        "wheelterrain master, co-simulation (FMI calls through ctypes), native "
                        "FMUs, step 0.001 s")
    plots.time_series(result, {"drawbar_pull": 10.1, "normal_force": 62.3, "sinkage": 0.0158},
                      tmp_path / "C2.png")
    (fig,) = figures
    for ax in _labelled_axes(fig):
        assert UNIT.search(ax.get_ylabel()), ax.get_ylabel()
        texts = [t.get_text() for t in ax.get_legend().get_texts()]
        assert result.master in texts
        assert all(text.endswith((" N", " mm")) for text in texts if "mean" in text), texts
    assert UNIT.search(fig.axes[-1].get_xlabel())


def test_means_chart_has_a_residual_panel_per_quantity(figures, tmp_path):
    rows = [{"case": f"C{k + 1}", **{f"{key}{suffix}": value + k
                                     for key, value in (("drawbar_pull", 5.0),
                                                        ("normal_force", 60.0),
                                                        ("sinkage", 0.01))
                                     for suffix in ("", "_experiment", "_paper_simulation")}}
            for k in range(4)]
    for r in rows:
        r["drawbar_pull"] += 1.5  # this model 1.5 N off the experiment
    plots.means_bar_chart(rows, tmp_path / "means.png", "rashid-patch")
    plots.means_bar_chart(rows, tmp_path / "fitted.png", "rashid-patch", ["C1", "C2"])
    fig, fitted = figures
    axes = _labelled_axes(fig)
    assert len(axes) == 6
    for ax in axes:
        assert UNIT.search(ax.get_ylabel()), ax.get_ylabel()
    residual = [ax for ax in axes if "- experiment" in ax.get_ylabel()]
    assert len(residual) == 3
    pull = next(ax for ax in residual if ax.get_ylabel().startswith("drawbar pull"))
    texts = [t.get_text() for t in pull.get_legend().get_texts()]
    assert "this model: MAE 1.50 N" in texts
    # a preset fitted on these cases has its MAE labelled in-sample
    pull = next(ax for ax in fitted.axes if ax.get_ylabel().startswith("drawbar pull - "))
    assert "this model: MAE 1.50 N (in-sample)" in [t.get_text()
                                                   for t in pull.get_legend().get_texts()]


def test_sweep_curves_carry_units_on_axes_and_legend(figures, tmp_path):
    rows = [{"slip": s, "load": load, "drawbar_pull": 10 * s, "contact_sinkage": 0.01,
             "status": "ok"} for s in (0.0, 0.5) for load in (30.0, 62.0)]
    plots.sweep_curves(rows, "slip", ["load"], tmp_path / "sweep.png", "sweep")
    (fig,) = figures
    for ax in _labelled_axes(fig):
        assert UNIT.search(ax.get_xlabel()), ax.get_xlabel()
        assert UNIT.search(ax.get_ylabel()), ax.get_ylabel()
    texts = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert texts == ["load = 30 N", "load = 62 N"]
