"""Tests of the bandpass design, eqs. (24)-(29) of Pham, Gautier, Poignet 2001."""

from __future__ import annotations

import math

import numpy as np
import pytest

from jointbench.identification.design import (
    FilterDesign,
    butterworth_magnitude,
    central_difference_magnitude,
    decimation_cutoff_hz,
    design_bandpass,
    distortion,
)

F1_HZ = 3.9  # first mode of the loaded prototype, section 4
AC = math.sqrt(2.0) / 2.0

# ERRATA.md quotes wn and Fs with 2 decimals, so they are exact to +-0.005; a tolerance of
# 0.01 (rad/s, Hz) accepts any value that rounds to the quoted one and nothing further off.
ERRATA_ROWS = [
    # nd, m, wn (rad/s), Fs (Hz)
    (2, 4, 181.04, 205.70),
    (4, 6, 168.91, 289.64),
]
# Section 4 quotes wn to the rad/s and Fs truncated to the Hz (205.70 -> 205, 289.64 -> 289).
PAPER_ROWS = [
    (2, 4, 181, 205),
    (4, 6, 169, 289),
]


@pytest.mark.parametrize(("nd", "m", "wn", "fs"), ERRATA_ROWS)
def test_errata_numbers(nd: int, m: int, wn: float, fs: float) -> None:
    d = design_bandpass(F1_HZ, nd=nd, m=m)
    assert isinstance(d, FilterDesign)
    assert d.wn_rad_s == pytest.approx(wn, abs=0.01)
    assert d.fs_hz == pytest.approx(fs, abs=0.01)
    assert d.ts_s == pytest.approx(1.0 / d.fs_hz, rel=1e-12)
    assert d.wc_rad_s == pytest.approx(12.0 * math.pi * F1_HZ, rel=1e-12)


@pytest.mark.parametrize(("nd", "m", "wn", "fs"), PAPER_ROWS)
def test_paper_rounded_numbers(nd: int, m: int, wn: int, fs: int) -> None:
    d = design_bandpass(F1_HZ, nd=nd, m=m, ac=AC, rc=1.0, ratio=6.0)
    assert round(d.wn_rad_s) == wn
    assert math.floor(d.fs_hz) == fs


@pytest.mark.parametrize(("nd", "m"), [(2, 4), (4, 6), (1, 1), (3, 8)])
def test_distortion_at_wc_is_ac_when_rc_is_1(nd: int, m: int) -> None:
    # By construction of eqs. (28)-(29), A(wc) = sqrt(rc Ac) * sqrt(Ac / rc) = Ac.
    d = design_bandpass(F1_HZ, nd=nd, m=m, rc=1.0)
    a_wc = distortion(d.wc_rad_s, d.wn_rad_s, d.ts_s, m, nd)
    assert float(a_wc) == pytest.approx(AC, rel=1e-10)


@pytest.mark.parametrize("rc", [0.8, 1.0, 1.2])
def test_rc_definition_eq27_holds_at_wc(rc: float) -> None:
    nd, m = 2, 4
    d = design_bandpass(F1_HZ, nd=nd, m=m, rc=rc)
    lowpass = butterworth_magnitude(d.wc_rad_s, d.wn_rad_s, m)
    central = (math.sin(d.wc_rad_s * d.ts_s) / (d.wc_rad_s * d.ts_s)) ** nd
    assert float(lowpass / central) == pytest.approx(rc, rel=1e-10)
    # A(wc) = Ac holds for any rc, not only rc = 1.
    a_wc = distortion(d.wc_rad_s, d.wn_rad_s, d.ts_s, m, nd)
    assert float(a_wc) == pytest.approx(AC, rel=1e-10)


def test_xc_relation_eq29() -> None:
    d = design_bandpass(F1_HZ, nd=2, m=4)
    assert d.xc == pytest.approx(d.wc_rad_s * d.ts_s / math.pi, rel=1e-12)
    assert float(np.sinc(d.xc)) == pytest.approx(AC ** (1.0 / 4.0), rel=1e-12)


def test_decimation_cutoff() -> None:
    # Section 4.1: Fs = 350.87 Hz, Nd = 26 -> 5.4 Hz; ERRATA: 5.40 Hz.
    assert decimation_cutoff_hz(350.87, 26) == pytest.approx(5.40, abs=0.005)


def test_butterworth_half_at_wn() -> None:
    for m in (1, 2, 4, 6):
        assert float(butterworth_magnitude(176.0, 176.0, m)) == pytest.approx(0.5)
    assert float(butterworth_magnitude(0.0, 176.0, 2)) == 1.0


def test_central_difference_magnitude() -> None:
    ts = math.pi / 1.0e3
    w = np.array([0.0, 1.0, 500.0, 1.0e3])
    d = central_difference_magnitude(w, ts)
    assert d[0] == 0.0
    assert d[1] == pytest.approx(1.0, rel=1e-5)  # ideal derivative at low frequency
    assert d[2] == pytest.approx(1.0 / ts, rel=1e-12)  # |sin(pi/2)| / Ts
    assert d[3] == pytest.approx(0.0, abs=1e-9)  # zero at the Nyquist frequency ws/2


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"f1_hz": 0.0}, "f1_hz"),
        ({"f1_hz": -1.0}, "f1_hz"),
        ({"f1_hz": float("nan")}, "f1_hz"),
        ({"nd": 0}, "nd"),
        ({"nd": 2.5}, "nd"),
        ({"m": 0}, "m"),
        ({"ac": 0.0}, "ac"),
        ({"ac": 1.0}, "ac"),
        ({"rc": 0.0}, "rc"),
        ({"rc": 1.5}, "rc"),  # rc * ac >= 1: eq. (28) undefined
        ({"rc": 0.5}, "rc"),  # ac / rc >= 1: eq. (29) has no root in (0, 1)
        ({"ratio": 0.0}, "ratio"),
    ],
)
def test_bad_inputs_raise(kwargs: dict[str, float], name: str) -> None:
    args: dict[str, float] = {"f1_hz": F1_HZ, "nd": 2, "m": 4}
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        design_bandpass(**args)  # type: ignore[arg-type]


def test_bad_inputs_other_functions() -> None:
    with pytest.raises(ValueError, match="wn"):
        butterworth_magnitude(1.0, 0.0, 2)
    with pytest.raises(ValueError, match="ts"):
        central_difference_magnitude(1.0, -1.0)
    with pytest.raises(ValueError, match="nd"):
        distortion(1.0, 100.0, 1e-3, 2, 0)
    with pytest.raises(ValueError, match="nd_decim"):
        decimation_cutoff_hz(350.87, 0)


def test_plot_figure1_writes_png(tmp_path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from jointbench.identification.plots import figure1_setup, plot_figure1

    setup = figure1_setup()
    assert math.pi / setup.ts == pytest.approx(1.0e3)  # ws/2 = 1e3 rad/s
    out = tmp_path / "figure1.png"
    fig = plot_figure1(setup.wn, setup.ts, m=setup.m, path=out)
    try:
        assert out.is_file()
        data = out.read_bytes()
        assert data.startswith(b"\x89PNG\r\n\x1a\n")
        assert len(data) > 1000
        assert fig.axes[0].get_title() == "Figure 1: magnitude of filters (m = 2)"
        assert fig.axes[0].get_xscale() == "log" and fig.axes[0].get_yscale() == "log"
        # Only the PNG is left: the temporary file was renamed, not copied.
        assert [p.name for p in tmp_path.iterdir()] == ["figure1.png"]
    finally:
        plt.close(fig)
