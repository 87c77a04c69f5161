"""Naming is a claim with evidence: a check, over the JSON answer of `diagnose` (one log,
several runs, or --model), that no named cause has a failing test.

- **One log** (`diagnose LOG --json`): every name of `named_causes` has its entry in
  `causes` with a `test` (identification.discrepancy.candidates.HeldOutTest) whose held-out
  share is positive and whose p-value is under its level, the level of the round it entered;
  a cause of a later round explains more than the floor (`floor_pct`) in that test (its
  `acts_pct`, the share over the equations it acts in; `heldout_pct` without it); the
  entry's `t`, `p_heldout`, `heldout_pct` and `alpha` are that test's; `named_cause` is the
  first of them. "One of A or B" is one claim: each of `alternatives` (A named, B the
  effect the log cannot tell from it) is listed in A's entry's `alternatives` and B is not
  named itself, and every entry's alternative is among them.
- **Several runs** (`diagnose A B --json`): each run as one log, and each cause `supported`
  is named, with a passing test, on every run.
- **--model**: each named cause but a link Coulomb friction has its entry in `causes` with a
  passing test; `link_coulomb` named from the log's FS has a significant parameter error FS.

The check recomputes the claim from the numbers (p < alpha, share > 0, t above the bar of
alpha for the units the test is over, its `segments`: identification.discrepancy.heldout.
t_bar) rather than trusting `passes`.
"""

from __future__ import annotations

import math

from jointbench.identification.discrepancy.heldout import t_bar

# numbers printed to JSON and read back: a test exactly at its bar is not a pass
_T_ROUNDING = 1e-9


def failing_claims(doc: dict) -> list[str]:
    """Every named cause of a `diagnose` JSON answer (module docstring) whose test is
    missing or fails, one message each; [] when every named cause passes its test."""
    if "runs" in doc:
        return _runs(doc)
    if "model" in doc and "extended_effects" in doc:
        return _model(doc)
    return _one(doc)


def _number(x) -> float:
    return float(x) if isinstance(x, (int, float)) and x is not None else math.nan


def claim_fails(test: dict | None, floor_pct: float = 0.0) -> str:
    """Why a cause's `test` (its JSON) does not support it ("" when it does): missing, a
    share not above `floor_pct` (0 in the first round), p not under alpha, t under the bar."""
    if not isinstance(test, dict):
        return "no test"
    share, t, p, alpha = (_number(test.get(k)) for k in ("heldout_pct", "t", "p_heldout",
                                                          "alpha"))
    if not (alpha > 0 and math.isfinite(p)):
        return f"no level or p-value (alpha {alpha}, p {p})"
    if not share > 0:
        return f"held out it explains {share:.3g} % of the residual"
    if not p < alpha:
        return f"p = {p:.3g} is not under its level {alpha:.3g} (t = {t:.3g})"
    units = test.get("segments")
    bar = t_bar(alpha, units) if isinstance(units, int) and units >= 3 else t_bar(alpha)
    if not t > bar - _T_ROUNDING * max(1.0, abs(bar)):
        return f"t = {t:.3g} is under its bar t > {bar:.3g}"
    if test.get("passes") is False:
        return "its test says it does not pass"
    own = _number(test.get("acts_pct"))
    own = own if math.isfinite(own) else share
    if not own > floor_pct:
        return (f"held out it explains {own:.3g} % of its equations' residual, not above the "
                f"floor of {floor_pct:g} %")
    return ""


def _one(doc: dict, where: str = "") -> list[str]:
    causes = doc.get("causes") or []
    named = list(doc.get("named_causes") or [])
    out: list[str] = []
    entries = {c.get("effect"): c for c in causes if isinstance(c, dict)}
    if [c.get("effect") for c in causes] != named:
        out.append(f"{where}named_causes {named} and the causes' entries "
                   f"{[c.get('effect') for c in causes]} differ")
    first = doc.get("named_cause")
    if named and first != named[0]:
        out.append(f"{where}named_cause {first!r} is not the first named cause {named[0]!r}")
    if not named and first not in (None, "none"):
        out.append(f"{where}named_cause {first!r} without an entry in causes")
    floor = _number(doc.get("floor_pct"))
    for name in named:
        c = entries.get(name)
        if c is None:
            out.append(f"{where}{name}: named without an entry in causes")
            continue
        test = c.get("test")
        later = _number(c.get("round")) > 1
        why = claim_fails(test, floor if later and math.isfinite(floor) else 0.0)
        if why:
            out.append(f"{where}{name}: {why}")
            continue
        for key in ("heldout_pct", "t", "p_heldout", "alpha"):
            if c.get(key) != test.get(key):
                out.append(f"{where}{name}: its {key} {c.get(key)} is not its test's "
                           f"{test.get(key)}")
    return out + _one_of(doc, entries, named, where)


def _one_of(doc: dict, entries: dict, named: list, where: str) -> list[str]:
    """"One of A or B" stated alike at the top (`alternatives`) and in A's entry."""
    out: list[str] = []
    top = {(a.get("named"), a.get("other")) for a in doc.get("alternatives") or []
           if isinstance(a, dict)}
    listed = {(name, a.get("effect")) for name, c in entries.items()
              for a in c.get("alternatives") or [] if isinstance(a, dict)}
    for a, b in sorted(top - listed, key=str):
        out.append(f"{where}{a}: one of {a} or {b} is stated, but not in {a}'s entry")
    for a, b in sorted(listed - top, key=str):
        out.append(f"{where}{a}: its entry's alternative {b} is not among the alternatives")
    for a, b in sorted(top | listed, key=str):
        if a not in named:
            out.append(f"{where}one of {a} or {b}: {a} is not named")
        if b in named:
            out.append(f"{where}one of {a} or {b}: {b} is named as well")
    return out


def _runs(doc: dict) -> list[str]:
    out: list[str] = []
    named_in: list[set[str]] = []
    for run in doc.get("runs") or []:
        where = f"run {run.get('name', '?')}: "
        out += _one(run, where)
        named_in.append(set(run.get("named_causes") or []))
    for cause in doc.get("supported") or []:
        missing = [r.get("name", "?") for r, names in zip(doc.get("runs") or [], named_in)
                   if cause not in names]
        if missing:
            out.append(f"{cause}: supported but not named on {', '.join(missing)}")
    return out


def _model(doc: dict) -> list[str]:
    out: list[str] = []
    entries = {c.get("effect"): c for c in doc.get("causes") or [] if isinstance(c, dict)}
    floor = _number(doc.get("floor_pct"))
    for name in doc.get("named_causes") or []:
        if name == "link_coulomb" and name not in entries:
            fs = (doc.get("parameter_errors") or {}).get("FS") or {}
            if not fs.get("significant"):
                out.append("link_coulomb: named without a significant parameter error FS")
            continue
        c = entries.get(name)
        if c is None:
            out.append(f"{name}: named without an entry in causes")
            continue
        later = _number(c.get("round")) > 1
        why = claim_fails(c.get("test"), floor if later and math.isfinite(floor) else 0.0)
        if why:
            out.append(f"{name}: {why}")
    return out
