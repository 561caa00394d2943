"""Automatic tuning of a controller's gains against the requirements over a training set of plants.

The search is CMA-ES (the ``cma`` package) over the logarithms of the gains that
:data:`TUNABLE` names for each controller kind, from the design's values, each within a
factor :data:`SPAN` of them. A candidate is scored on a training set: a verification
(:func:`wetclutch.launch.verify.run`) of :data:`N_TRAIN` samples of the ranges with the
training seed, no corners. The score is a tail measure, not the mean:

    score = (1 - pass rate) + TAIL_WEIGHT x mean of the worst 10 % of the samples' badness

where a sample's badness is its largest requirement violation, each figure over its limit
(steady-state error, settled t95, ripple, creep, overshoot above the nominal's): the pass
rate counts first, and among candidates that pass alike the one whose worst plants fail
least wins (a score of the tail alone prefers a design that fails everywhere mildly to one
that passes most plants).

The best of many noisy training scores is biased low (the winner's curse: with a few dozen
plants, one plant more or less that passes moves the pass rate by some percent, and the search
picks the luckiest candidate). The search therefore ends with a choice among finalists on
plants it has not seen: the start, the best candidate on the training plants and the search
distribution's mean are verified on :data:`VALIDATION_FACTOR` times as many validation plants
(drawn with ``seed + 1``, the same plants for each). A lower validation score alone is not
enough either: a candidate replaces the start only if it also passes significantly more of the
validation plants. The finalists are compared plant by plant (McNemar's exact test): of the
plants on which the two differ, ``b`` pass only with the candidate and ``c`` only with the start,
and under "no better than the start" ``b`` is at most binomial(``b + c``, 1/2); the candidate
qualifies if ``P(X >= b) <`` :data:`SIGNIFICANCE`. The tuned design is the qualifying candidate
with the lowest validation score, else the start. It is then verified on a held-out set drawn
with yet another seed, beside the untuned one (the command line's ``tune``). Both kinds are
tuned the same way, so the comparison with the baseline stays fair.

The search state is saved after every generation (:func:`run` with ``state``), so a long
run can be stopped and resumed.
"""

from __future__ import annotations

import hashlib
import math
import pickle
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import binomtest

from ..errors import WetclutchError
from ..params import Params
from . import metrics, verify
from .design import Design, with_settings
from .ranges import Range
from .ranges import load as load_ranges

#: the gains each kind's tuning searches
TUNABLE = {"launch": ("ki_t", "ki_rise", "kp_p", "ki_p", "kd_p", "tau_ref", "tau_theta"), "baseline": ("kp", "ki")}
#: each gain stays within this factor of the design's value
SPAN = 5.0
N_TRAIN = 40
TAIL = 0.1
TAIL_WEIGHT = 0.03
#: validation plants per training plant (the finalists' choice)
VALIDATION_FACTOR = 2
#: a candidate replaces the start only if it passes more validation plants at this significance (one-sided)
SIGNIFICANCE = 0.05


def badness(r: dict[str, Any]) -> float:
    """A sample's largest requirement violation: each figure over its limit (1 = at the limit)."""
    m = r["metrics"]
    if not m or m.get("steady_state_error_pct") is None:
        return 10.0
    worst = max(m["steady_state_error_pct"] / metrics.REQ_ESS_PCT,
                (m["t95_settled_s"] if m["t95_settled_s"] is not None else 10.0) / metrics.REQ_T95_S,
                (m["ripple_pct"] or 0.0) / metrics.REQ_RIPPLE_PCT,
                (m["creep_Nm"] or 0.0) / metrics.REQ_CREEP_NM,
                (m["overshoot_pct"] or 0.0) / (metrics.ROBUST_OVERSHOOT + 10.0))
    return float(min(worst, 10.0))


def score(result: dict[str, Any]) -> float:
    """The tail score of a verification (lower is better); see the module docstring."""
    b = np.sort([badness(r) for r in result["results"]])[::-1]
    k = max(1, int(math.ceil(TAIL * b.size)))
    return float((1.0 - result["pass_rate"]) + TAIL_WEIGHT * np.mean(b[:k]))


@dataclass
class Tuning:
    """A tuning run: the tuned design and the search history."""

    design: Design
    start: Design
    names: tuple[str, ...]
    history: list[dict[str, Any]] = field(default_factory=list)
    best_score: float = math.inf
    best_rate: float = float("nan")
    #: the best candidate's logarithmic gains (zeros: the start)
    best_x: np.ndarray = field(default_factory=lambda: np.zeros(0))
    start_training: tuple[float, float] = (math.inf, float("nan"))
    #: each finalist's (training score, training pass rate, validation score, validation pass rate)
    finalists: dict[str, tuple[float, float, float, float]] = field(default_factory=dict)
    #: each candidate against the start on the validation plants (:func:`against_start`)
    tests: dict[str, tuple[int, int, float]] = field(default_factory=dict)
    chosen: str = "start"
    #: what the candidates' scores depend on besides the design (:func:`scoring`); a resumed search keeps them
    settings: dict[str, Any] = field(default_factory=dict)

    def __repr__(self) -> str:
        # a notebook shows this: the outcome, not the history of every candidate
        return (f"Tuning({self.design.kind}, {len(self.history)} candidates scored, chosen: {self.chosen}; "
                f"best training score {self.best_score:.4g}, pass rate {self.best_rate:.3g})")


def against_start(candidate: list[bool], start: list[bool]) -> tuple[int, int, float]:
    """McNemar's exact test of a candidate against the start on the same plants (pass or fail on each):
    ``(b, c, p)``, ``b`` the plants only the candidate passes, ``c`` those only the start passes, and ``p`` the
    one-sided probability of ``b`` or more of the ``b + c`` were the candidate no better (binomial, 1/2)."""
    if len(candidate) != len(start):
        raise ValueError("the candidate and the start must be verified on the same plants")
    b = sum(1 for x, y in zip(candidate, start) if x and not y)
    c = sum(1 for x, y in zip(candidate, start) if y and not x)
    p = float(binomtest(b, b + c, 0.5, alternative="greater").pvalue) if b + c > 0 else 1.0
    return b, c, p


def check_options(samples: int, generations: int, popsize: int) -> None:
    """Refuse a bad training-set size, generation count or population size (one line naming the option)."""
    if samples < 1:
        raise WetclutchError(f"--samples must be >= 1 (got {samples})")
    if generations < 1:
        raise WetclutchError(f"--generations must be >= 1 (got {generations})")
    if popsize < 2:
        raise WetclutchError(f"--popsize must be >= 2 (got {popsize})")


def check_state(path: str | Path) -> Path:
    """``path`` as a state file a search can be saved to (one line naming ``--state`` if not): a file or nothing yet,
    in a directory that exists. Checked before the search, not after its first generation."""
    path = Path(path)
    if not str(path).strip():
        raise WetclutchError("--state must not be empty")
    if path.exists() and not path.is_file():
        raise WetclutchError(f"--state '{path}' is not a file")
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise WetclutchError(f"--state '{path}': directory '{parent}' does not exist")
    return path


def _load_state(path: Path, cma: Any) -> tuple[Any, Tuning]:
    """The search (CMA-ES state, :class:`Tuning`) saved in ``path``, or a one-line error: not a state this module
    saved (any other file, pickled or not)."""
    try:
        state = pickle.loads(path.read_bytes())
    except OSError as e:
        raise WetclutchError(f"cannot resume from '{path}': {e.strerror or e}") from None
    except Exception as e:  # noqa: BLE001 - unpickling a foreign file can raise anything
        raise WetclutchError(f"cannot resume from '{path}': not a tuning state ({type(e).__name__})") from None
    if (not isinstance(state, tuple) or len(state) != 2 or not isinstance(state[0], cma.CMAEvolutionStrategy)
            or not isinstance(state[1], Tuning)):
        raise WetclutchError(f"cannot resume from '{path}': not a tuning state (it holds a {type(state).__name__})")
    return state


def _save_state(path: Path, es: Any, tuning: Tuning) -> None:
    """Save the search to ``path`` whole (a temporary file beside it, then a rename), or a one-line error."""
    tmp = path.with_name(f".{path.name}.tmp")
    try:
        tmp.write_bytes(pickle.dumps((es, tuning)))
        tmp.replace(path)
    except OSError as e:
        tmp.unlink(missing_ok=True)
        raise WetclutchError(f"cannot save the search to --state '{path}': {e.strerror or e}") from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def scoring(samples: int, seed: int, popsize: int, sequence: int, plant: Params,
            ranges: list[Range]) -> dict[str, Any]:
    """What a search's scores depend on besides its start, each under the option that sets it.

    Parameters
    ----------
    samples, seed, sequence
        The training plants: their number, their seed and the launches of each.
    popsize
        Candidates per generation.
    plant
        The plant the ranges vary around.
    ranges
        What varies.

    Returns
    -------
    dict
        Option name to a printable value (plant and ranges as a short digest), comparable with ``==``.
    """
    def digest(v: Any) -> str:
        return hashlib.sha256(repr(v).encode()).hexdigest()[:12]

    return {"--samples": samples, "--seed": seed, "--popsize": popsize, "--sequence": sequence,
            "--param-file/--set": f"plant {digest(plant.model_dump())}", "--ranges": f"ranges {digest(ranges)}"}


@contextmanager
def _quiet_cma() -> Iterator[None]:
    """Hide the warnings of the ``cma`` calls inside (e.g. that it enlarges a small population): the search
    reports through its result, and its remarks are no business of the command line's user."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield


def _candidate(start: Design, names: tuple[str, ...], x: np.ndarray) -> Design:
    x = np.clip(x, -math.log(SPAN), math.log(SPAN))
    return with_settings(start, **{n: start.settings[n] * math.exp(v) for n, v in zip(names, x)})


def run(start: Design, plant: Params | None = None, ranges: list[Range] | None = None, samples: int = N_TRAIN,
        seed: int = 0, generations: int = 8, popsize: int = 8, workers: int | None = None,
        state: str | Path | None = None, on_generation: Callable[[int, float, float], None] | None = None,
        sequence: int = 1) -> Tuning:
    """Tune ``start``'s gains (:data:`TUNABLE`) on ``samples`` training plants drawn with ``seed``.

    ``sequence``: launches per training plant, the adaptation carried over, judged on the last (as ``verify``).

    ``state``: a file the search is saved to after each generation and resumed from if it
    exists; a state of another start or other scoring settings (:func:`scoring`) is refused, and so is
    ``generations`` below the generations it has run. ``on_generation(generation, best score, best pass rate)``
    reports progress.

    The tuned design is the finalist (start, best on training, the search's mean) that scores best on
    :data:`VALIDATION_FACTOR` ``* samples`` validation plants drawn with ``seed + 1``; ``best_score``
    and ``best_rate`` are its training figures.
    """
    import cma

    check_options(samples, generations, popsize)
    if start.kind not in TUNABLE:
        raise WetclutchError(f"no tuning for controller '{start.kind}'")
    names = TUNABLE[start.kind]
    path = Path(state) if state is not None else None
    settings = scoring(samples, seed, popsize, sequence, plant if plant is not None else start.plant,
                       ranges if ranges is not None else load_ranges())

    def verified(design: Design, n: int, s: int) -> dict[str, Any]:
        return verify.run(design, plant, n, s, workers, ranges, corners=False, progress=False, sequence=sequence)

    if path is not None:
        check_state(path)
    if path is not None and path.is_file():
        es, tuning = _load_state(path, cma)
        if tuning.start.key() != start.key():
            raise WetclutchError(f"'{path}' is the state of another tuning (other design); remove it to start anew")
        saved = getattr(tuning, "settings", None) or {}
        for option, value in settings.items():
            if saved.get(option) != value:
                was = saved.get(option, "not recorded")
                raise WetclutchError(f"'{path}' is the state of another tuning ({option}: {was} in the state, "
                                     f"{value} now); give the same options or remove it to start anew")
        if len(tuning.history) > generations:
            raise WetclutchError(f"--generations {generations} is fewer than the {len(tuning.history)} generations "
                                 f"'{path}' has already run")
    else:
        with _quiet_cma():
            es = cma.CMAEvolutionStrategy(np.zeros(len(names)), 0.3,
                                          {"popsize": popsize, "seed": seed + 1, "verbose": -9,
                                           "bounds": [-math.log(SPAN), math.log(SPAN)]})
        tuning = Tuning(start, start, names, best_x=np.zeros(len(names)), settings=settings)
        first = verified(start, samples, seed)
        # the start is the candidate to beat: a search that finds nothing better keeps it
        tuning.start_training = tuning.best_score, tuning.best_rate = score(first), first["pass_rate"]
    while len(tuning.history) < generations:
        with _quiet_cma():
            xs = es.ask()
        scores, rates = [], []
        for x in xs:
            res = verified(_candidate(start, names, np.asarray(x)), samples, seed)
            scores.append(score(res))
            rates.append(res["pass_rate"])
        with _quiet_cma():
            es.tell(xs, scores)
        i = int(np.argmin(scores))
        if scores[i] < tuning.best_score:
            tuning.best_score, tuning.best_rate = scores[i], rates[i]
            tuning.best_x = np.asarray(xs[i], dtype=float)
        tuning.history.append({"generation": len(tuning.history) + 1, "best_score": float(min(scores)),
                               "mean_score": float(np.mean(scores)), "best_pass_rate": float(rates[i])})
        if path is not None:
            _save_state(path, es, tuning)
        if on_generation is not None:
            on_generation(len(tuning.history), tuning.best_score, tuning.best_rate)
    with _quiet_cma():
        mean = np.asarray(es.result.xfavorite, dtype=float)
    _choose(tuning, mean, verified, samples, seed)
    chosen = tuning.design
    if tuning.chosen == "start":
        return tuning
    b, c, pv = tuning.tests[tuning.chosen]
    source = (f"tuned: CMA-ES on {samples} training plants (seed {seed}, {sequence} launches each), chosen on "
              f"{VALIDATION_FACTOR * samples} validation plants (seed {seed + 1}), validation score "
              f"{tuning.finalists[tuning.chosen][2]:.3f} against the start's {tuning.finalists['start'][2]:.3f}, "
              f"passing {b} plants the start fails and failing {c} it passes (p = {pv:.3g})")
    sources = dict.fromkeys(names, source)
    tuning.design = Design(chosen.kind, chosen.plant, chosen.settings, chosen.sources | sources, chosen.temps_C,
                           chosen.pressures_Pa, chosen.input_V, chosen.fill_s)
    return tuning


def _choose(tuning: Tuning, mean: np.ndarray, verified: Callable[[Design, int, int], dict[str, Any]], samples: int,
            seed: int) -> None:
    """Choose among the finalists (start, best on training, the search's mean) on the validation plants: the
    candidate with the lowest validation score among those that pass significantly more of them than the start
    (:func:`against_start`), else the start."""
    start, names = tuning.start, tuning.names
    xs = {"start": np.zeros(len(names)), "best on training": tuning.best_x, "search mean": mean}
    finalists: dict[str, tuple[float, float, float, float]] = {}
    passes: dict[str, dict[int, bool]] = {}
    seen: list[np.ndarray] = []
    for name, x in xs.items():
        if any(np.array_equal(x, y) for y in seen):
            continue
        seen.append(x)
        design = _candidate(start, names, x)
        if name == "start":
            train = tuning.start_training
        elif name == "best on training":
            train = (tuning.best_score, tuning.best_rate)
        else:
            res = verified(design, samples, seed)
            train = (score(res), res["pass_rate"])
        val = verified(design, VALIDATION_FACTOR * samples, seed + 1)
        finalists[name] = (*train, score(val), val["pass_rate"])
        passes[name] = {r["index"]: bool(r["all_pass"]) for r in val["results"]}
    plants = sorted(passes["start"])
    tuning.tests = {k: against_start([passes[k][i] for i in plants], [passes["start"][i] for i in plants])
                    for k in finalists if k != "start"}
    qualified = [k for k, (_, _, p) in tuning.tests.items()
                 if p < SIGNIFICANCE and finalists[k][2] < finalists["start"][2]]
    tuning.chosen = min(qualified, key=lambda k: finalists[k][2]) if qualified else "start"
    tuning.finalists = finalists
    tuning.design = _candidate(start, names, xs[tuning.chosen]) if tuning.chosen != "start" else start
    tuning.best_score, tuning.best_rate = finalists[tuning.chosen][:2]
