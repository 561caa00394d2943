"""Small helpers for the reports' sentences: counts with their nouns, headings nested under others."""

from __future__ import annotations

import re


def plural(n: int, singular: str, many: str | None = None) -> str:
    """``n`` and its noun, singular for one: ``plural(1, "clutch", "clutches")`` -> ``"1 clutch"``.

    Parameters
    ----------
    n
        The count.
    singular
        The noun for one.
    many
        The noun for any other count (default: ``singular`` + ``"s"``).

    Returns
    -------
    str
        ``"<n> <noun>"``.
    """
    return f"{n} {singular if n == 1 else (many or singular + 's')}"


def times(n: int) -> str:
    """How often, in words: ``"once"``, ``"twice"``, ``"3 times"``."""
    return {1: "once", 2: "twice"}.get(n, f"{n} times")


def demote(text_md: str, levels: int) -> str:
    """Markdown with every ATX heading ``levels`` deeper (at most ``######``), so that a document embedded under a
    heading of another keeps that one's outline.

    Parameters
    ----------
    text_md
        The embedded document.
    levels
        How many levels deeper its headings go.

    Returns
    -------
    str
        The document with its headings demoted; code spans and other lines untouched.
    """
    def deeper(m: re.Match[str]) -> str:
        return "#" * min(6, len(m.group(1)) + levels) + m.group(2)

    return re.sub(r"^(#{1,6})( |$)", deeper, text_md, flags=re.M)
