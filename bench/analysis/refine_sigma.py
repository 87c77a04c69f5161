"""How far the refinement's own sigma can be trusted: the output error's Jacobian
sigma assumes that the replay is the robot. Two checks against the least squares of the same
log widen or withdraw it, each with a note."""

from __future__ import annotations

import math


DISAGREEMENT_Z = 3.0   # refined - LS over their combined sigma beyond which sigma is widened


def widen_on_disagreement(theta: dict[str, float], start: dict[str, float],
                          sigma: dict[str, float], sigma_c: dict[str, float],
                          ls_sigma_c: dict[str, float]
                          ) -> tuple[dict[str, float], dict[str, float], list[str]]:
    """Both estimates come from one log: where the refined value and the least-squares one
    differ by more than 3 of their combined corrected sigma, each estimator sees a model error
    (the nominal axis' friction, the replay's discretisation, the regressor's) that neither
    sigma holds. Such a sigma is widened to include the difference, sqrt(sigma^2 + d^2), and a
    note says so."""
    sigma, sigma_c, notes = dict(sigma), dict(sigma_c), []
    for n in sigma:
        s_ls = ls_sigma_c.get(n, math.nan)
        s_ref = sigma_c.get(n, sigma[n])
        d = abs(theta[n] - start[n])
        both = math.hypot(s_ref, s_ls)
        if not (math.isfinite(both) and both > 0 and d > DISAGREEMENT_Z * both):
            continue
        sigma[n] = math.hypot(sigma[n], d)
        if n in sigma_c:
            sigma_c[n] = math.hypot(sigma_c[n], d)
        notes.append(f"{n}: refined and least squares differ by {d:.4g} ({d / both:.1f} of "
                     "their combined sigma): a model error neither sigma holds; sigma widened "
                     "to include the difference")
    return sigma, sigma_c, notes


def withdraw_when_unmoved(theta: dict[str, float], start: dict[str, float],
                          sigma: dict[str, float], sigma_c: dict[str, float],
                          ls_sigma_c: dict[str, float]
                          ) -> tuple[dict[str, float], dict[str, float], list[str]]:
    """A refinement that ends within one least-squares corrected sigma of its start on every
    parameter has found nothing the least squares did not: its Jacobian sigma (the output
    error's curvature, which assumes the replay is the robot) is then withdrawn for the least
    squares' corrected one, and a note says so."""
    moved = [n for n in sigma if not abs(theta[n] - start[n]) <= ls_sigma_c.get(n, math.nan)]
    if moved:
        return sigma, sigma_c, []
    out = {n: ls_sigma_c[n] for n in sigma}
    return out, dict(out), ["the refinement stayed within one least-squares sigma of its start "
                            "on every parameter: its own sigma (the output error's curvature, "
                            "exact only for an exact replay) is withdrawn; sigma is the least "
                            "squares' corrected one"]
