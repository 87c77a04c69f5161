"""What the battery by visibility shows about a detector: the confusion table, the detection
curve per effect (share named right against in-band visibility) and the visibility above
which an effect is found 95 % of the time.

A record is one case as benchmarks/battery.py writes it: a dict with `kind` ("clean",
"single", "pair"), `effects` (hidden names), `visibilities` (each effect's, ratios), `named`
(the causes diagnose named, in order) and `family`; and `distinguishing` (each effect's
distinguishing visibility, distinguishing_visibility; None for an effect that reduces to no
other), `ambiguity` (the answer's "one of A or B" texts) and `alternatives` (each named
cause's stated alternatives, [named, other] pairs), when the battery recorded them.

The strict counts (`right`) credit a hidden effect only where it is named. Beside them,
apart, the counts of what the data proves (`found_or_inseparable`, `extra_causes`): a hidden
effect stated as the alternative of a named cause ("one of A or B") on a log whose
distinguishing visibility between the two is under SEPARABLE counts as found, and such a
named cause does not count as an extra one: no log of that kind can say more.
"""

from __future__ import annotations

import re

import numpy as np
from tabulate import tabulate

from jointbench.bench.campaign.visibility import VISIBILITY_BAND, visibility
from jointbench.identification.effects import EFFECTS, NONE
from jointbench.identification.filtering import lowpass

BINS = (0.03, 0.05, 0.10, 0.20, 0.40)   # visibility bin edges (ratios); the last bin is open
FOUND_SHARE = 0.95                      # "found 95 % of the time"
MIN_CASES = 3                           # cases at or above a visibility to claim the share
PAIR_VISIBLE = 0.10                     # a two-effect case counts when both effects reach it
SEPARABLE = 0.05                        # distinguishing visibility under which a log is not
#                                         counted as able to separate an effect from the one
#                                         it reduces to (the battery's bar for "visible")


def distinguishing_visibility(tau_clean: np.ndarray, tau_effect: np.ndarray,
                              tau_reduced: np.ndarray, f1_hz: float, rate_hz: float) -> float:
    """The in-band visibility (bench.campaign.visibility, a ratio) of the part of an effect's
    change of the noise-free command that the effect it reduces to (registry `reduces_to`)
    cannot take: tau_effect - tau_clean less its least-squares multiple, in band, of
    tau_reduced - tau_clean, the change the reduced effect makes at some strength (its change
    taken as proportional to its strength: an offset's constant load). For an asymmetric
    friction on the bench that is its viscous part a FVm |qm'| less its mean, as the closed
    loop shows it; on a tanh friction law its creep region besides. [N m] commands on the
    same ticks; f1 [Hz], rate [Hz]."""
    a = np.asarray(tau_clean, float)
    da, db = np.asarray(tau_effect, float) - a, np.asarray(tau_reduced, float) - a
    wn, ts = 2 * np.pi * VISIBILITY_BAND * f1_hz, 1.0 / rate_hz
    la, lb = lowpass(da, wn, ts), lowpass(db, wn, ts)
    c = float(la @ lb) / float(lb @ lb) if float(lb @ lb) > 0 else 0.0
    return visibility(a, a + da - c * db, f1_hz, rate_hz)


def first_named(record: dict) -> str:
    return record["named"][0] if record["named"] else NONE


def right(record: dict) -> bool:
    """Clean: nothing named; single: the hidden effect named first; pair: both named."""
    hidden, named = record["effects"], record["named"]
    if record["kind"] == "clean":
        return not named
    if record["kind"] == "single":
        return first_named(record) == hidden[0]
    return set(hidden) <= set(named)


def alternative_stated(record: dict) -> bool:
    """A single-effect miss whose answer states that the log cannot tell the named cause from
    the hidden one (the record's `ambiguity` texts name it): honest, not right."""
    return (record["kind"] == "single" and not right(record)
            and any(record["effects"][0] in a for a in record.get("ambiguity", ())))


def inseparable_stated(record: dict) -> bool:
    """A single-effect miss that states the hidden effect as the alternative (ambiguity) on
    a log that cannot separate it from the effect it reduces to: its distinguishing
    visibility (distinguishing_visibility) under SEPARABLE. Not counted as right."""
    d = (record.get("distinguishing") or [None])[0]
    return alternative_stated(record) and d is not None and d < SEPARABLE


# "A or B: ..." (a parsimony note) and "one of A or B: ..." (a stated alternative)
_PAIR = re.compile(r"^(?:one of )?([a-z_]+) or ([a-z_]+):")


def stated_pairs(record: dict) -> set[frozenset[str]]:
    """The pairs of effects the answer states it cannot tell apart: the record's
    `alternatives` ([named, other] pairs) and the pairs its `ambiguity` texts open with."""
    out = {frozenset(p) for p in record.get("alternatives", ()) if len(set(p)) == 2}
    for text in record.get("ambiguity", ()):
        m = _PAIR.match(text)
        if m and m.group(1) != m.group(2):
            out.add(frozenset(m.groups()))
    return out


def _inseparable(record: dict, hidden: str, named: str) -> bool:
    """The log cannot separate the hidden effect `hidden` from the named cause `named`: the
    distinguishing visibility recorded for the hidden one that reduces to the other (`hidden`
    itself, or `named` when it is hidden too) is under SEPARABLE."""
    effects = list(record["effects"])
    d = list(record.get("distinguishing") or [None] * len(effects))
    for e, other in ((hidden, named), (named, hidden)):
        if e in effects and EFFECTS.get(e) is not None and EFFECTS[e].reduces_to == other:
            v = d[effects.index(e)] if effects.index(e) < len(d) else None
            return v is not None and v < SEPARABLE
    return False


def stated_inseparable(record: dict, hidden: str) -> str:
    """The named cause whose stated alternative is the hidden effect `hidden`, on a log that
    cannot separate the two (_inseparable); "" when there is none."""
    pairs = stated_pairs(record)
    for n in record["named"]:
        if n != hidden and frozenset((n, hidden)) in pairs and _inseparable(record, hidden, n):
            return n
    return ""


def found_or_inseparable(record: dict) -> bool:
    """`right`, counting a hidden effect as found also where it is the stated alternative of
    a named cause the log cannot separate it from (stated_inseparable): clean, nothing named;
    single, the hidden effect named first or the first named cause's inseparable
    alternative; pair, each hidden effect named or such an alternative."""
    hidden, named = record["effects"], record["named"]
    if record["kind"] == "clean":
        return not named
    if record["kind"] == "single":
        return bool(named) and (named[0] == hidden[0]
                                or stated_inseparable(record, hidden[0]) == named[0])
    return all(e in named or stated_inseparable(record, e) for e in hidden)


def extra_causes(record: dict, provable: bool = False) -> list[str]:
    """The named causes not hidden in the log; with `provable`, less those whose stated
    alternative is a hidden effect, not named itself, that the log cannot separate from
    them (stated_inseparable): the cause then stands for it."""
    hidden = set(record["effects"])
    extra = [n for n in record["named"] if n not in hidden]
    if not provable:
        return extra
    kept = {stated_inseparable(record, e) for e in hidden if e not in record["named"]} - {""}
    return [n for n in extra if n not in kept]


def confusion(records: list[dict]) -> tuple[list[str], np.ndarray]:
    """Clean and single-effect cases: rows the hidden effect (none for clean), columns the
    first named cause."""
    labels = [NONE, *EFFECTS]
    M = np.zeros((len(labels), len(labels)), int)
    for r in records:
        if r["kind"] in ("clean", "single"):
            hidden = r["effects"][0] if r["effects"] else NONE
            M[labels.index(hidden), labels.index(first_named(r))] += 1
    return labels, M


def curve(records: list[dict], effect: str) -> list[tuple[float, float, int, int]]:
    """The single-effect cases of `effect` by visibility bin: (low, high, named right, cases)
    per bin of BINS (high inf for the last)."""
    cases = [(r["visibilities"][0], right(r)) for r in records
             if r["kind"] == "single" and r["effects"][0] == effect and r["visibilities"]]
    edges = list(BINS) + [np.inf]
    out = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        inside = [ok for v, ok in cases if lo <= v < hi]
        out.append((lo, hi, sum(inside), len(inside)))
    below = [ok for v, ok in cases if v < BINS[0]]
    if below:
        out.insert(0, (0.0, BINS[0], sum(below), len(below)))
    return out


def found_above(records: list[dict], effect: str) -> float | None:
    """The smallest visibility v of a single-effect case of `effect` such that the cases at
    or above v are named right at least FOUND_SHARE of the time, with at least MIN_CASES of
    them; None when no such v ("not reached")."""
    cases = sorted((r["visibilities"][0], right(r)) for r in records
                   if r["kind"] == "single" and r["effects"][0] == effect and r["visibilities"])
    for k, (v, _) in enumerate(cases):
        tail = [ok for _, ok in cases[k:]]
        if len(tail) >= MIN_CASES and sum(tail) >= FOUND_SHARE * len(tail):
            return v
    return None


def summary_lines(records: list[dict]) -> list[str]:
    """The battery's findings as text lines: counts, confusion table, detection curve and
    95 % visibility per effect, clean and two-effect results."""
    lines = []
    # the counts of what the data proves need the distinguishing visibilities recorded
    proves = any("distinguishing" in r for r in records)
    labels, M = confusion(records)
    lines.append("confusion (rows: hidden, columns: first named; clean and single-effect cases)")
    short = [lab[:8] for lab in labels]
    lines += tabulate([[lab, *row] for lab, row in zip(labels, M.tolist())], ["", *short],
                      tablefmt="plain", colalign=("left", *("right",) * len(short)),
                      disable_numparse=True).splitlines()
    singles = [r for r in records if r["kind"] == "single"]
    effects = [e for e in EFFECTS if any(r["effects"][0] == e for r in singles)]
    heads = [f"{lo * 100:g}-{hi * 100:g} %" if np.isfinite(hi) else f">= {lo * 100:g} %"
             for lo, hi in zip([0.0, *BINS], [*BINS, np.inf])]
    rows = []
    for e in effects:
        cells = {(lo, hi): f"{k}/{n}" for lo, hi, k, n in curve(records, e) if n}
        v = found_above(records, e)
        rows.append([e, *(cells.get(b, "-") for b in zip([0.0, *BINS], [*BINS, np.inf])),
                     "not reached" if v is None else f"{100 * v:.1f} %"])
    lines += ["", "detection curve: named right / cases, by in-band visibility",
              *tabulate(rows, ["effect", *heads, "found 95 % above"], tablefmt="plain",
                        colalign=("left", *("right",) * len(heads), "left"),
                        disable_numparse=True).splitlines()]
    for kind, what in (("single", "single-effect cases named right"),
                       ("clean", "clean logs with nothing named"),
                       ("pair", "two-effect cases with both named")):
        rs = [r for r in records if r["kind"] == kind]
        if rs:
            k = sum(right(r) for r in rs)
            lines.append(f"{what}: {k}/{len(rs)} ({100 * k / len(rs):.0f} %)")
    at5 = [r for r in singles if r["visibilities"] and r["visibilities"][0] >= 0.05]
    if at5:
        k = sum(right(r) for r in at5)
        lines.append(f"single-effect cases at visibility >= 5 % named right: {k}/{len(at5)} "
                     f"({100 * k / len(at5):.0f} %)")
        amb = sum(alternative_stated(r) for r in at5)
        lines.append(f"  of the misses, answered with the hidden effect as the stated "
                     f"alternative (ambiguity): {amb}")
        if any("distinguishing" in r for r in at5):
            apart = sum(inseparable_stated(r) for r in at5)
            lines.append(f"single-effect cases at visibility >= 5 %: {k} named right, {apart} "
                         f"stated ambiguity between two effects the log cannot separate "
                         f"(distinguishing visibility < {100 * SEPARABLE:g} %), of {len(at5)} "
                         f"({100 * (k + apart) / len(at5):.0f} % together)")
        if proves:
            k2 = sum(found_or_inseparable(r) for r in at5)
            lines.append(f"  counting what the data proves (named, or stated as the "
                         f"alternative of the named cause where the distinguishing visibility "
                         f"is < {100 * SEPARABLE:g} %): {k2}/{len(at5)} "
                         f"({100 * k2 / len(at5):.0f} %)")
        clipped = [r for r in at5 if r.get("clipped_pct", 0.0) > 0]
        if clipped:
            lines.append("  of these, logs with torque at its limit (clipped samples): "
                         + ", ".join(f"#{r['index']} {r['clipped_pct']:.2g} % "
                                     f"({'right' if right(r) else 'missed'})" for r in clipped))
    ok = [r for r in records if not r.get("error")]
    extra = [len(extra_causes(r)) for r in ok]
    if extra:
        lines.append(f"logs naming a cause not hidden in them: {sum(k > 0 for k in extra)}/"
                     f"{len(extra)} ({100 * sum(k > 0 for k in extra) / len(extra):.1f} %); "
                     f"more than one such cause: {sum(k > 1 for k in extra)}")
        if proves:
            apart = [len(extra_causes(r, provable=True)) for r in ok]
            lines.append(f"  counting what the data proves (a named cause whose stated "
                         f"alternative is a hidden effect the log cannot separate from it is "
                         f"not extra): {sum(k > 0 for k in apart)}/{len(apart)} "
                         f"({100 * sum(k > 0 for k in apart) / len(apart):.1f} %); more than "
                         f"one such cause: {sum(k > 1 for k in apart)}")
    failing = [r for r in records if r.get("failing_claims")]
    lines.append(f"named causes without a passing test (claims.failing_claims over each "
                 f"case's JSON): {sum(len(r['failing_claims']) for r in failing)} in "
                 f"{len(failing)} logs")
    lines.append(f"axis families: {len({r.get('family') for r in records})}")
    reached = [r for r in records if any(r.get("saturated", ()))]
    if reached:
        lines.append("cases whose target visibility is out of reach (the visibility stopped "
                     "growing; counted at the visibility reached): " + ", ".join(
                         f"#{r.get('index', '?')} " + ",".join(
                             f"{e} {100 * v:.1f} % of {100 * t:.0f} %"
                             for e, v, t, x in zip(r["effects"], r["visibilities"],
                                                   r["targets"], r["saturated"]) if x)
                         for r in reached))
    pairs = [r for r in records if r["kind"] == "pair"]
    if pairs:
        one = sum(bool(set(r["effects"]) & set(r["named"])) for r in pairs)
        lines.append(f"two-effect cases with at least one named: {one}/{len(pairs)}")
        visible = [r for r in pairs if min(r["visibilities"], default=0.0) >= PAIR_VISIBLE]
        k = sum(right(r) for r in visible)
        lines.append(f"two-effect cases with both visibilities >= {100 * PAIR_VISIBLE:g} %: "
                     f"{len(visible)}, both named in {k}, over "
                     f"{len({r['family'] for r in visible})} axis families")
        if visible and proves:
            k2 = sum(found_or_inseparable(r) for r in visible)
            lines.append(f"  counting what the data proves (each named, or stated as the "
                         f"alternative of a named cause where the distinguishing visibility "
                         f"is < {100 * SEPARABLE:g} %): both found in {k2}/{len(visible)} "
                         f"({100 * k2 / len(visible):.0f} %)")
    return lines
