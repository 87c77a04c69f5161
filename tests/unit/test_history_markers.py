"""The code says why, never when: package code and docs/ carry no history markers.

Docstrings and comments hold the reason and the equation; dates, issue and session numbers,
seeds of past experiments with their battery case numbers and before -> after figures belong
in CHANGELOG.md or docs/design-notes.md. The pattern is the project's (the same as the
before-stop hook's), plus any `issue N` / `issue #N` and `session N` / `session-N` reference.
Exempt: `def f(...) -> T` lines (a return annotation, not a figure), docs/validation.md (the
measurements, regenerated with their date) and docs/design-notes.md (the history itself).
Inside a Markdown code block (a transcript of what a command prints) a `before % -> after %`
is the program's own output format, so only the other markers count there.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("bench", "identification", "models")
EXEMPT_DOCS = ("validation.md", "design-notes.md")

DATE = r"\b20[0-9]{2}-[01][0-9]-[0-3][0-9]\b"
NUMBERED = r"\b[Ii]ssue [0-9]+|\bsession [0-9]+|seed-[0-9]+ #[0-9]"
BEFORE_AFTER = r"[0-9.]+ ?%? ?-> ?[-+]?[0-9]"
HISTORY = re.compile("|".join((DATE, NUMBERED, BEFORE_AFTER)))
IN_TRANSCRIPT = re.compile("|".join((DATE, NUMBERED)))
REFERENCE = re.compile(r"\bissue #?[0-9]+|\bsession[- ][0-9]+", re.IGNORECASE)
SIGNATURE = re.compile(r"^\s*(async\s+)?def\s.*->")
FENCE = re.compile(r"^\s*(```|~~~)")


def markers(text: str, markdown: bool = False) -> list[tuple[int, str]]:
    """(line number from 1, line) of every line of `text` that carries a history marker."""
    out, fenced = [], False
    for number, line in enumerate(text.splitlines(), start=1):
        if markdown and FENCE.match(line):
            fenced = not fenced
            continue
        if SIGNATURE.match(line):
            continue
        history = IN_TRANSCRIPT if fenced else HISTORY
        if history.search(line) or REFERENCE.search(line):
            out.append((number, line.strip()))
    return out


def scanned_files() -> list[Path]:
    """The package's Python files (bench/, identification/, models/, the top-level
    __init__.py), docs/ Python examples and docs/ Markdown but the exempt pages."""
    files = [ROOT / "__init__.py"]
    for pkg in PACKAGES:
        files += sorted((ROOT / pkg).rglob("*.py"))
    files += sorted((ROOT / "docs").rglob("*.py"))
    files += sorted(p for p in (ROOT / "docs").rglob("*.md") if p.name not in EXEMPT_DOCS)
    return [p for p in files if p.is_file() and "__pycache__" not in p.parts]


def test_the_scanner_finds_every_kind_of_marker():
    text = "\n".join((
        '"""Clean: K from eq. (13)."""',                          # 1 clean
        "# measured 2026-12-02 on the prototype",                 # 2 date
        "x = 1  # issue 17: the bar",                             # 3 issue number
        "# Issue #14 item 4",                                     # 4 issue #N
        "# the seed-7 #84 case",                                   # 5 seed and case
        "# Jm -3.33 -> -0.07 %",                                   # 6 before -> after
        "# K 0.47 % -> 0.2 %",                                     # 7 percentages
        "# written in session 12",                                 # 8 session
        "# see session-9's notes",                                 # 9 session-N
        "def f(x: float) -> float:",                               # 10 annotation: fine
        "    return x  # q -> qm, the motor side",                # 11 mapping: fine
    ))
    assert [n for n, _ in markers(text)] == [2, 3, 4, 5, 6, 7, 8, 9]


def test_a_transcript_keeps_its_output_format_but_not_its_history():
    text = "\n".join((
        "A gain 6.43 % -> 0.30 % in prose is a figure.",          # 1 caught
        "```",
        "gain, inverse view: 6.43 % -> 0.30 % (21.21x)",          # 3 output format: fine
        "K within 0.5 % of the truth (issue 17): 2 of 2 axes",    # 4 caught
        "# drive export, 2026-11-30",                              # 5 caught
        "```",
        "After the block 1.2 -> 3 counts again.",                  # 7 caught
    ))
    assert [n for n, _ in markers(text, markdown=True)] == [1, 4, 5, 7]


def test_the_scan_covers_the_package_and_the_docs():
    names = {p.relative_to(ROOT).as_posix() for p in scanned_files()}
    assert {"__init__.py", "identification/regressors.py", "bench/cli/__init__.py",
            "models/truth.py", "docs/cli.md", "docs/effects.md"} <= names
    assert not names & {"docs/validation.md", "docs/design-notes.md"}


@pytest.mark.parametrize("path", scanned_files(), ids=lambda p: p.relative_to(ROOT).as_posix())
def test_no_history_markers(path: Path):
    found = markers(path.read_text(encoding="utf-8"), markdown=path.suffix == ".md")
    where = path.relative_to(ROOT).as_posix()
    assert not found, ("history in the code or docs (keep the reason, move the history to "
                       "docs/design-notes.md or CHANGELOG.md):\n"
                       + "\n".join(f"{where}:{n}: {line}" for n, line in found))
