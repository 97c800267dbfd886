"""Command-line option helpers shared by the testbench commands."""

from __future__ import annotations


def choose(value: str, allowed: list[str], what: str) -> list[str]:
    """'all' or a comma list of names from `allowed`; ValueError naming the unknown ones."""
    if value == "all":
        return allowed
    names = [v for v in value.split(",") if v]
    bad = [n for n in names if n not in allowed]
    if bad or not names:
        raise ValueError(f"unknown {what} {', '.join(bad) or value!r}: allowed all, "
                         f"{', '.join(allowed)}")
    return names
