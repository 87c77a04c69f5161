"""The first mode's phase crossing (identification.first_mode._fit) must lie in the window
of bins it was found in: a straight line through noisy phases that crosses the target far
outside it is no resonance (on a lab-rig log whose link never moves it put the motor's
"mode" at a negative frequency, which no filter can be designed for)."""

import numpy as np

from jointbench.identification.first_mode import _fit, _Response

F_PEAK = 6.5   # Hz


def _motor_response(phase_in_window) -> _Response:
    """A flattened motor response q_m / tau_m with its antiresonance dip at 3 Hz and its
    peak at F_PEAK, the phase in the fit's window (0.7-1.4 F_PEAK) given by the callable."""
    f = np.arange(0.0, 20.0, 0.1)
    mag = 1.0 + 1e3 * np.exp(-((f - F_PEAK) / 0.3) ** 2)
    mag[np.argmin(abs(f - 3.0))] = 1e-3
    phase = np.where(f < F_PEAK, np.pi / 2 + 1.0, np.pi / 2 - 1.0)
    win = (f >= 0.7 * F_PEAK) & (f <= 1.4 * F_PEAK)
    phase[win] = phase_in_window(f[win])
    ok = (f > 0.5) & (f < 15.0)
    return _Response(f=f, G=mag * np.exp(1j * phase), sd=np.full(f.shape, 0.1), ok=ok)


def test_a_crossing_inside_the_window_is_kept():
    # a resonance's phase falling through +90 deg at 6.62 Hz
    f1, sd, why = _fit(_motor_response(lambda f: np.pi / 2 - 0.8 * (f - 6.62)), motor=True)
    assert why == ""
    assert abs(f1 - 6.62) < 0.01


def test_a_line_crossing_far_outside_the_window_is_no_resonance():
    # phases 20 deg under the target and nearly flat, one stray bin above it: the line's
    # crossing lies 70 Hz below the peak, at a negative frequency
    def phase(f):
        p = np.pi / 2 - 0.35 - 0.005 * (f - F_PEAK)
        p[-1] = np.pi / 2 + 1.0
        return p

    f1, sd, why = _fit(_motor_response(phase), motor=True)
    assert np.isnan(f1)
    assert "outside the window" in why
