"""The one parser of `KEY=NUMBER` items shared by command options and effect specifications
(standard library only: the command line imports it before any heavy module)."""

from __future__ import annotations

from typing import Callable, Iterable


def key_numbers(items: Iterable[str], bad_form: Callable[[str], Exception],
                bad_number: Callable[[str, str], Exception]) -> dict[str, float]:
    """`KEY=NUMBER` items as a dict (keys stripped); `bad_form(item)` is raised for an item
    without `=`, `bad_number(key, value)` for a value that is not a number."""
    out = {}
    for item in items:
        if "=" not in item:
            raise bad_form(item)
        key, value = item.split("=", 1)
        try:
            out[key.strip()] = float(value)
        except ValueError:
            raise bad_number(key, value) from None
    return out
