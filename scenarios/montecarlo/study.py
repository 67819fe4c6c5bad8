"""What a Monte Carlo study is, and one realization of it.

A study flies one card ``n`` times, each realization with its own seed (derived from the
study's base seed with ``flightid.scenarios.cards.sub_seed``), identifies each flight with
one method and model, and scores every estimated derivative against the exact truth.
``run_realization(description, index)`` is a pure function of its arguments: a worker
process (local or on a Dask cluster) needs nothing else.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
from threadpoolctl import threadpool_limits

from flightid.identification.data.reduction import standard_reduction
from flightid.identification.evaluation.scoring import record_truth, score
from flightid.identification.identify import identify
from flightid.identification.methods import registry
from flightid.scenarios.cards import Card, fly_card, load_card, sub_seed, trim_card
from flightid.scenarios.montecarlo.disperse import COLUMN_PREFIX, dispersed_card, draw, parse_all
from flightid.sim.flight.simulation import DepartureError
from flightid.sim.jsbsim.model import quiet
from flightid.sim.jsbsim.trim import TrimError

# the columns of a result row, in order
COLUMNS = ("index", "seed", "name", "truth", "estimate", "std", "error", "sigmas",
           "status", "reason")
FLOAT_COLUMNS = ("truth", "estimate", "std", "error", "sigmas")
STATUS_FAILED = "failed"
# what makes one realization fail (recorded as a failure row); anything else is a bug
# and stops the study
REALIZATION_ERRORS = (DepartureError, TrimError, ValueError, np.linalg.LinAlgError)


@dataclass(frozen=True)
class Study:
    """A Monte Carlo study: fly ``card`` (library name or TOML path) ``n`` times, identify
    each flight as ``flightid identify`` does, with ``method`` and ``model`` (``options``
    as for ``identify``) after the standard data reduction (``raw``: without it, as
    ``--raw``); seeds derived from the base ``seed`` (None: the card's seed)."""

    card: str
    n: int
    method: str = "oe"
    model: str = "lat"
    options: dict[str, Any] = field(default_factory=dict)
    seed: int | None = None
    disperse: tuple[str, ...] = ()
    raw: bool = False

    def base_seed(self, card: Card | None = None) -> int:
        """The base seed: the study's, else the card's."""
        if self.seed is not None:
            return int(self.seed)
        return int((card or load_card(self.card)).seed)

    def realization_seed(self, index: int, card: Card | None = None) -> int:
        """The seed of realization ``index`` (independent of n and of the other ones)."""
        return sub_seed(self.base_seed(card), f"montecarlo:{int(index)}")

    def identity(self) -> dict[str, Any]:
        """Everything that makes two studies the same except their size n (JSON-able);
        a stored study continues only under the same identity."""
        card = load_card(self.card)
        text = json.dumps(card.to_dict(), sort_keys=True, default=str)
        extra = {"disperse": [d.text() for d in parse_all(self.disperse)]} \
            if self.disperse else {}  # absent without dispersions: older studies continue
        return {**extra,
            "card": self.card,
            "card_sha256": hashlib.sha256(text.encode()).hexdigest(),
            "method": self.method,
            "model": self.model,
            "options": {k: _plain(v) for k, v in sorted(self.options.items())},
            "seed": self.base_seed(card),
            "data_reduction": "raw" if self.raw else "standard",
        }

    def as_dict(self) -> dict[str, Any]:
        """The description as plain data (options JSON-able)."""
        out = asdict(self)
        out["options"] = {k: _plain(v) for k, v in self.options.items()}
        out["disperse"] = list(self.disperse)
        return out


MAX_SEED = 2**32 - 1


def dry_run(description: Study) -> Card:
    """Check a study before any realization flies, and return its card: n at least 1, the
    seed in 0..2**32-1, the method, model and options (``registry``), the dispersions,
    and one realization's trim (the card with every dispersion at its neutral value at the
    card's condition). Raises ValueError (CardError) for a bad description, TrimError when
    the card cannot be trimmed: nothing of the study is written before.

    Parameters
    ----------
    description : Study
        The study.

    Returns
    -------
    Card
        The study's card.
    """
    if isinstance(description.n, bool) or int(description.n) < 1:
        raise ValueError(f"n must be at least 1, got {description.n}")
    if description.seed is not None and not 0 <= int(description.seed) <= MAX_SEED:
        raise ValueError(f"seed must be 0..{MAX_SEED}, got {description.seed}")
    spec = registry.get(description.method)
    registry.check_model(description.method, description.model)
    spec.make_options(dict(description.options))
    card = load_card(description.card)
    dispersions = parse_all(description.disperse)
    # JSBSim's console notes (on the process's stdout and through Python's) would mix into
    # a --format json output
    with quiet(), contextlib.redirect_stdout(io.StringIO()):
        trim_card(dispersed_card(card, dispersions, {d.key: d.neutral for d in dispersions}))
    return card


def _plain(value: Any) -> Any:
    if isinstance(value, str | int | float | bool) or value is None:
        return value
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    return str(value)


def run_realization(description: Study, index: int) -> list[dict[str, Any]]:
    """Fly, identify and score realization ``index``: one row per scored derivative
    (columns ``COLUMNS``), or one row with status 'failed' and the reason (the flight
    departed or could not be trimmed, the method refused the record, the fit did not
    converge). Never empty.

    Parameters
    ----------
    description : Study
        The study.
    index : int
        Realization index.

    Returns
    -------
    list[dict[str, Any]]
        The rows.
    """
    with threadpool_limits(1):  # one BLAS thread: the parallelism is the realizations
        return _realization(description, index)


def _realization(description: Study, index: int) -> list[dict[str, Any]]:
    card = load_card(description.card)
    seed = description.realization_seed(index, card)
    base: dict[str, Any] = {"index": int(index), "seed": int(seed)}
    dispersions = parse_all(description.disperse)
    if dispersions:  # the drawn values go into every row of the realization
        values = draw(dispersions, seed)
        card = dispersed_card(card, dispersions, values)
        base.update({COLUMN_PREFIX + k: v for k, v in values.items()})
    try:
        measured, truth_record = fly_card(card, seed)
        record = standard_reduction(measured, description.raw).record  # as identify does
        est = identify(record, description.method, description.model,
                       **dict(description.options))
    except REALIZATION_ERRORS as exc:
        return [_failure(base, f"{type(exc).__name__}: {exc}")]
    if est.fit.get("converged") is False:
        why = est.fit.get("message") or est.fit.get("reason") or ""
        return [_failure(base, f"not converged{': ' + str(why) if why else ''}")]
    scored = score(est, record_truth(truth_record))
    rows = []
    for r in scored.rows:
        rows.append({**base, "name": r.name, "truth": _num(r.truth),
                     "estimate": _num(r.estimate), "std": _num(r.std),
                     "error": _num(r.error), "sigmas": _num(r.sigmas),
                     "status": r.status, "reason": r.reason or ""})
    if not rows:
        return [_failure(base, "the estimate scored no derivative")]
    return rows


def _num(x: Any) -> float:
    return float("nan") if x is None else float(x)


def _failure(base: dict[str, Any], reason: str) -> dict[str, Any]:
    row: dict[str, Any] = {**base, "name": "", "status": STATUS_FAILED, "reason": reason}
    row.update({c: float("nan") for c in FLOAT_COLUMNS})
    return row
