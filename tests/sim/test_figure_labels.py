"""The figures of `diagnose --out` and of the identification (issue 18): units on every axis,
titles that say what is plotted, forward.png's error traces and zoom, structure.png without
the panels that do not apply."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import jointbench.bench.analysis.diagnose.figures as figures
from jointbench.bench.analysis.diagnose import diagnose
from jointbench.identification.log import read_log
from jointbench.identification.plots import plot_figure1, plot_frf, plot_validation

EMPS = Path(__file__).parents[1] / "data" / "emps" / "emps_estimation.csv"
UNITS = ("[rad]", "[N m]", "[Hz]", "[s]", "[m]", "[N]", "samples", "/Hz]", "(N m)", "(s)",
         "(Hz)", "(deg)", "(rad/s)", "1/s", "(N)", "(rad /", "(m /")


@pytest.fixture
def captured(monkeypatch):
    """The figures the module would save, kept open for inspection."""
    figs = {}

    def keep(fig, path):
        figs[Path(path).name] = fig
        return Path(path)
    monkeypatch.setattr(figures, "save_figure_atomic", keep)
    return figs


def _labels(fig) -> list[tuple[str, str, str]]:
    return [(ax.get_title(), ax.get_xlabel(), ax.get_ylabel()) for ax in fig.axes]


def _all_axes_have_units(fig) -> None:
    for title, x, y in _labels(fig):
        assert title, "an axes without a title"
        for label in (x, y):
            if label:
                assert any(u in label for u in UNITS), label
        assert y, f"no y label on '{title}'"


@pytest.fixture(scope="module")
def backlash_diagnosis(bench_log):
    from jointbench.bench.effects import HiddenEffect

    return diagnose(bench_log("prototype", duration=20.0, seed=1,
                              effect=HiddenEffect("backlash", 0.002)))


def test_flexible_axis_figures(backlash_diagnosis, captured, tmp_path):
    d = backlash_diagnosis
    for plot in (figures.plot_structure, figures.plot_spectrum, figures.plot_inverse,
                 figures.plot_forward, figures.plot_forward_frf):
        plot(d, tmp_path / f"{plot.__name__}.png")
    for name, fig in captured.items():
        _all_axes_have_units(fig)
    inverse = _labels(captured["plot_inverse.png"])
    assert "measured and predicted motor torque" in inverse[0][0] and "%" not in inverse[0][0]
    assert inverse[0][2] == "tau_m [N m]"
    forward = captured["plot_forward.png"]
    assert len(forward.axes) == 6  # q_m, q, tau_m: error trace | zoom
    titles = [a.get_title() for a in forward.axes]
    assert titles[0] == "q_m: replay - measured" and "largest torque error" in titles[1]
    zoom = forward.axes[5]
    lo, hi = zoom.get_xlim()
    assert hi - lo < 1.5  # a window of about 1 s, not the 20 s overlay
    err = d.forward_nominal.tau_m - d.log.tau_m
    t_peak = d.forward_nominal.t[int(np.argmax(np.abs(err)))]
    assert lo < t_peak < hi
    structure = captured["plot_structure.png"]
    assert len(structure.axes) == 4
    assert any("chirp" in t for t, _, _ in _labels(structure))


def test_rigid_measured_axis_leaves_out_what_does_not_apply(captured, tmp_path):
    """EMPS: no link position, not a chirp, prismatic."""
    d = diagnose(read_log(EMPS), forward=False)
    figures.plot_structure(d, tmp_path / "s.png")
    figures.plot_spectrum(d, tmp_path / "p.png")
    figures.plot_inverse(d, tmp_path / "i.png")
    structure = captured["s.png"]
    assert len(structure.axes) == 3  # no deflection panel drawn empty
    labels = _labels(structure)
    assert not any("chirp" in t for t, _, _ in labels)
    assert ("motor equation residual against the motor position qm", "qm [m]",
            "residual [N]") in labels
    for fig in captured.values():
        _all_axes_have_units(fig)
    assert figures.plot_forward(d, tmp_path / "f.png") is None


def test_identification_plots_have_units():
    import matplotlib.pyplot as plt

    t = np.linspace(0, 1, 50)
    for fig in (plot_figure1(100.0, np.pi / 1e3),
                plot_validation(t, np.sin(t), np.sin(t) + 0.01, 1.0, unit="N"),
                plot_frf(np.linspace(0, 10, 20), np.ones(20, complex), {"model": np.ones(20)},
                         units=("m", "N"))):
        for _, x, y in _labels(fig):
            assert y and any(u in y for u in UNITS + ("magnitude",)), y
        plt.close(fig)
    fig = plot_validation(t, np.sin(t), np.sin(t), 1.0, unit="N")
    assert fig.axes[0].get_ylabel() == "motor torque tau_m (N)"
    assert "measured and predicted motor torque" in fig.axes[0].get_title()
    plt.close(fig)
