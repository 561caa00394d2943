"""A tuning written out: the tuned ``controller.toml``, ``tune.json`` and ``tune.md``."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ..launch.settings import to_toml
from ..launch.tune import SIGNIFICANCE, VALIDATION_FACTOR, Tuning
from ..output import atomic_dir, write_json
from .text import plural, times


def write(tuning: Tuning, rates: dict[str, dict[str, float]], out: str | Path, meta: dict[str, Any]) -> None:
    """``rates``: {"training"|"held-out": {"start"|"tuned": pass rate}}; ``meta``: sample counts and seeds."""
    t = tuning
    with atomic_dir(out) as d:
        (d / "controller.toml").write_text(to_toml(t.design))
        write_json(d / "tune.json", {"kind": t.design.kind, "gains": {n: {"start": t.start.settings[n],
                                                                          "tuned": t.design.settings[n]}
                                                                      for n in t.names},
                                     "history": t.history, "pass_rates": rates, "chosen": t.chosen,
                                     "finalists": {k: dict(zip(("training_score", "training_pass_rate",
                                                                "validation_score", "validation_pass_rate"), v))
                                                   | _test(t, k) for k, v in t.finalists.items()}, **meta})
        lines = [f"# Tuning of the {t.design.kind} controller", "",
                 f"CMA-ES over the logarithms of {', '.join(t.names)} (each within a factor 5 of the design), scored on "
                 f"{plural(meta['samples'], 'training plant')} (seed {meta['seed']}; "
                 f"{_launched(meta.get('sequence', 1))}) by (1 - pass rate) + 0.03 x the mean of the "
                 f"worst 10 % of the samples' largest requirement violation. The tuned design is chosen among the "
                 f"finalists (the design, the best candidate on the training plants, the search's mean) on "
                 f"{VALIDATION_FACTOR * meta['samples']} validation plants (seed {meta['seed'] + 1}): the best of many "
                 f"noisy training scores is biased low, so a candidate replaces the design only if it scores lower "
                 f"there and passes significantly more of the validation plants (McNemar's exact test on the plants "
                 f"where the two differ, one-sided p < {SIGNIFICANCE:g}). Verified on {meta['heldout_samples']} "
                 f"held-out plants (seed {meta['heldout_seed']}).", "",
                 "| pass rate, all requirements | designed | tuned |", "|---|---|---|"]
        for split in ("training", "held-out"):
            lines.append(f"| {split} | {100 * rates[split]['start']:.1f} % | {100 * rates[split]['tuned']:.1f} % |")
        lines += ["", "| finalist | training score | training pass rate | validation score | validation pass rate "
                      "| validation plants only it passes / only the design passes | p |",
                  "|---|---|---|---|---|---|---|"]
        lines += [f"| {k}{' (chosen)' if k == t.chosen else ''} | {v[0]:.3f} | {100 * v[1]:.1f} % | {v[2]:.3f} | "
                  f"{100 * v[3]:.1f} % | {_cells(t, k)} |" for k, v in t.finalists.items()]
        lines += ["", "| gain | designed | tuned |", "|---|---|---|"]
        lines += [f"| {n} | {t.start.settings[n]:.4g} | {t.design.settings[n]:.4g} |" for n in t.names]
        lines += ["", "| generation | best score | mean score | best training pass rate |", "|---|---|---|---|"]
        lines += [f"| {h['generation']} | {h['best_score']:.3f} | {h['mean_score']:.3f} | {100 * h['best_pass_rate']:.1f} % |"
                  for h in t.history]
        (d / "tune.md").write_text("\n".join(lines) + "\n")


def _launched(sequence: int) -> str:
    """How each training plant was launched, and which launch is judged."""
    if sequence <= 1:
        return "each launched once"
    return f"each launched {times(sequence)}, the adaptation carried over, judged on the last"


def _test(t: Tuning, name: str) -> dict[str, float | int]:
    """A candidate's test against the start on the validation plants (none for the start)."""
    if name not in t.tests:
        return {}
    b, c, p = t.tests[name]
    return {"validation_only_it_passes": b, "validation_only_the_design_passes": c, "p_value": p}


def _cells(t: Tuning, name: str) -> str:
    if name not in t.tests:
        return "- | -"
    b, c, p = t.tests[name]
    return f"{b} / {c} | {p:.3g}"
