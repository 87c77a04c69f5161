"""Is an identified model believable on the log it came from? Warnings that name the likely
cause (no confident wrong answer). Pure numerics on an Identification, no I/O.

- **A log that looks mislabelled.** A physical axis has positive inertias and stiffness.
  - Every inertia negative (J, or Jm and JL): the torque column has the wrong sign (the
    motion is fitted with the force that opposes it).
  - A two-mass fit with K <= 0 or JL <= 0 while Jm > 0: q and q_m are swapped (the torque
    acts on the side logged as the link; the spring then pulls the wrong way).
  - Units (positions in degrees): identification.log.unit_warnings, not repeated here.
- **Data too short (or too narrow-band) to excite the model.** `auto` fell back to the
  rigid model because the flexible one was not excited (too few frequency lines, nothing
  identifiable, too little explained) on a log with q (two position sensors: the axis has a
  transmission between them): the rigid J then lumps Jm + JL and its frictions,
  and nothing in the log tells how far off it is.
- **The model explains too little of the torque.** A model that describes the axis leaves
  the torque noise seen through the band: a white noise of standard deviation sigma per
  sample (the log's `torque_noise_std`) has RMS sigma sqrt(f_c / (Fs / 2)) below the
  decimated cutoff f_c (a clean log's residual sits near that floor; an unmodelled
  backlash, ripple, lag, hardening, offset or asymmetric friction puts it several times
  above, swapped q and q_m far above). A
  residual over NOISE_FACTOR = 3 times the floor holds 9 times the noise power: at least
  89 % of what the model leaves is structure it lacks. A log that states no noise level
  gets the fallback bar: the model explains less than 3/4 of the torque's power (relative
  error over 50 %), where the residual is as large as half the torque itself.
"""

from __future__ import annotations

import math

import numpy as np

NOISE_FACTOR = 3.0           # residual RMS over the in-band torque noise floor
NO_NOISE_MAX_ERROR = 50.0    # %, relative error, when the log states no noise level
# the rejection reasons of `auto` that say the flexible model was not excited
NOT_EXCITED = ("frequency line", "is identifiable", "explains only", "not identified")


def mislabel_reason(physical: dict[str, float]) -> str:
    """Why the estimates say the log is mislabelled ("" when they do not): all inertias
    negative (torque sign), or a non-positive K or JL with a positive Jm (q and q_m swapped)."""
    inertias = [physical[k] for k in ("J", "Jm", "JL") if k in physical]
    if inertias and all(v < 0 for v in inertias):
        vals = ", ".join(f"{k} = {physical[k]:.4g}" for k in ("J", "Jm", "JL") if k in physical)
        return (f"every inertia is negative ({vals}): the torque column looks to have the "
                "wrong sign (tau_m must be the torque that accelerates q_m positively; "
                "docs/log-format.md)")
    if "K" in physical and "Jm" in physical and physical["Jm"] > 0 and \
            (physical["K"] <= 0 or physical.get("JL", 1.0) <= 0):
        return (f"K = {physical['K']:.4g}, JL = {physical.get('JL', math.nan):.4g} with Jm = "
                f"{physical['Jm']:.4g}: a spring cannot push the wrong way; the columns q and "
                "q_m look swapped (q_m is the motor side, where the torque acts)")
    return ""


def noise_floor(result, log) -> float | None:
    """RMS of the log's white torque noise (`torque_noise_std`) below the decimated cutoff,
    or None when the log states no noise level."""
    sigma = log.meta_float("torque_noise_std")
    if sigma is None or not sigma > 0:
        return None
    return sigma * math.sqrt(min(1.0, result.settings.decimated_cutoff_hz
                                 / (0.5 * log.sample_rate_hz)))


def explained_warning(result, log) -> str:
    """The warning for a model that explains too little of the torque ("" when it does not);
    see the module docstring for the bar."""
    rows = result.block == 0
    res = float(np.sqrt(np.mean((result.y[rows] - result.y_pred[rows]) ** 2)))
    err = result.relative_error_pct
    floor = noise_floor(result, log)
    if floor is not None and floor > 0:
        if not res > NOISE_FACTOR * floor:
            return ""
        bar = (f"its residual {res:.4g} is {res / floor:.3g} times the torque noise the log "
               f"states (torque_noise_std), seen through the band ({floor:.3g}): over "
               f"{NOISE_FACTOR:g} times, at least 89 % of what is left is structure the model "
               "lacks")
    elif err > NO_NOISE_MAX_ERROR:
        bar = ("the log states no torque noise level (torque_noise_std) and the error is over "
               f"{NO_NOISE_MAX_ERROR:g} %")
    else:
        return ""
    return (f"the {result.model} model explains too little of the torque for its noise: "
            f"relative error {err:.3g} %; {bar}. Likely causes: an effect the model lacks "
            "(jointbench diagnose names it), a mislabelled log (columns, sign, units), or too "
            "little excitation")


def _short(reason: str, log) -> str:
    """The first clause of a rejection reason, without the file name."""
    head = f"{log.path}: " if log.path else ""
    reason = reason[len(head):] if head and reason.startswith(head) else reason
    return reason.split(": ")[0].split("; ")[0]


def sanity_warnings(result, log) -> list[str]:
    """The warnings of the module docstring for the identification `result` of `log`."""
    where = f"{log.path or '<log>'}: "
    out = []
    why = mislabel_reason(result.physical)
    if not why and result.rejected is not None:
        why = mislabel_reason(result.rejected[1])
        why = why and f"the flexible model was rejected and {why}"
    if why:
        out.append(where + why)
    if log.q is not None and result.rejected is not None and \
            any(k in result.rejected[0] for k in NOT_EXCITED):
        span = float(log.t[-1] - log.t[0])
        out.append(where + f"the data ({len(log)} samples, {span:.3g} s) is too short or too "
                   f"narrow-band to excite the flexible model ({_short(result.rejected[0], log)}): the "
                   "rigid model used lumps Jm + JL into J and cannot say how far off it is; "
                   "record a longer experiment (a chirp through the first mode)")
    text = explained_warning(result, log)
    if text:
        out.append(where + text)
    return out
