"""What the failing samples of a verification fail: shared by the acceptance scripts."""

from __future__ import annotations

from collections import Counter
from typing import Any

from wetclutch.launch import metrics, verify


def failing(result: dict[str, Any]) -> list[dict[str, Any]]:
    """The random samples (not the corners) of a ``verify.run`` result that fail on their last launch."""
    return [row for row in result["results"] if not row["corner"] and not row["all_pass"]]


def table(failed: list[dict[str, Any]]) -> str:
    """Per requirement: how many of ``failed`` fail it, how many of those no controller passes
    (``verify.unreachable``), and how many of those passed their first launch (the adaptation lost them)."""
    lines = ["| requirement | samples | of them no controller passes | of them passed their first launch |",
             "|---|---|---|---|"]
    for req in metrics.REQUIREMENTS:
        rows = [row for row in failed if not row["requirements"][req]]
        lines.append(f"| {req} | {len(rows)} | {sum(verify.unreachable(row) for row in rows)} | "
                     f"{sum(row['first_all_pass'] for row in rows)} |")
    return "\n".join(lines)


def kinds(failed: list[dict[str, Any]]) -> str:
    """The combinations of failed requirements among ``failed``, most frequent first, with their counts."""
    counts = Counter(" + ".join(k for k in metrics.REQUIREMENTS if not row["requirements"][k]) for row in failed)
    return "; ".join(f"{k}: {v}" for k, v in counts.most_common()) or "none"
