"""Score estimates against truth: a row per derivative, a one-line verdict, JSON.

error = estimate - truth; error/std says how many standard errors (Cramer-Rao bounds,
corrected for colored residuals where the method did so) the estimate is off. An
estimate within ``n_sigma`` (3 by default: 99.7 % for a Gaussian estimator whose bound
is right) counts as consistent with the truth. Unidentifiable parameters are shown as
such, never as numbers; truth values that no estimate covers are "not estimated".
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Mapping
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from flightid.derivatives import is_derivative
from flightid.files import json_safe
from flightid.identification.estimate import Estimate
from flightid.record import FlightRecord

STATUS_ESTIMATED = "estimated"
STATUS_UNIDENTIFIABLE = "unidentifiable"
STATUS_NOT_ESTIMATED = "not estimated"


@dataclass
class ScoreRow:
    """One derivative: truth, estimate, standard error, error and error in standard errors."""

    name: str
    truth: float
    estimate: float | None
    std: float | None
    error: float | None
    sigmas: float | None  # error / std
    status: str
    reason: str = ""


@dataclass
class Score:
    """All rows of a comparison with truth and the one-line verdict."""

    rows: list[ScoreRow]
    n_sigma: float
    verdict: str
    method: str = ""

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready form: {"method", "n_sigma", "verdict", "rows": [...]}."""
        return {
            "method": self.method,
            "n_sigma": self.n_sigma,
            "verdict": self.verdict,
            "rows": [json_safe(asdict(r)) for r in self.rows],
        }

    def __str__(self) -> str:
        """A plain-text table: derivative, truth, estimate, std, error/std; the verdict."""
        lines = [f"{'derivative':<14}{'truth':>11}{'estimate':>11}{'std':>10}{'err/std':>9}"]
        for r in self.rows:
            if r.status == STATUS_ESTIMATED:
                lines.append(f"{r.name:<14}{r.truth:>11.4g}{r.estimate:>11.4g}{r.std:>10.3g}"
                             f"{r.sigmas:>+9.2f}")
            else:
                lines.append(f"{r.name:<14}{r.truth:>11.4g}  {r.status}")
        return "\n".join([*lines, self.verdict])

    def to_json(self, indent: int = 2) -> str:
        """The dict form as JSON text."""
        return json.dumps(self.as_dict(), indent=indent)


SCOPES = ("estimated", "all")
# coefficients at the record's reference condition: they depend on how the reference is
# defined (mean, initial, trim), so they are reported but not scored
REFERENCE_SUFFIX = "_0"


def record_truth(record: FlightRecord) -> dict[str, float]:
    """The exact derivatives a simulated record carries (``meta.extra['truth']``).

    In the body axes of the identification models (CL and CD as in both axes).

    Parameters
    ----------
    record : FlightRecord
        The flight.

    Returns
    -------
    dict of str to float
        {derivative: value}, per rad (rates nondimensional); empty for a record that carries
        none (real flight data).
    """
    table = record.meta.extra.get("truth") or {}
    return {k: float(v) for k, v in (table.get("body") or {}).items()}


def score(
    estimate: Estimate | Iterable[Estimate],
    truth: Mapping[str, float] | FlightRecord,
    n_sigma: float = 3.0,
    scope: str = "estimated",
) -> Score:
    """Compare one or several estimates with the truth.

    Parameters
    ----------
    estimate : Estimate or iterable of Estimate
        What the methods estimated.
    truth : mapping of str to float, or FlightRecord
        {derivative name: value} (per rad, rates nondimensional), or a simulated record
        carrying its truth.
    n_sigma : float
        How many standard errors an estimate may lie from the truth and count as inside.
    scope : str
        'estimated' (default): a row per derivative the estimate estimated or found
        unidentifiable; 'all': a row per truth value, "not estimated" where no estimate
        has it. Coefficients at the reference condition (``C*_0``) are not scored.

    Returns
    -------
    Score
        A row per derivative (truth, estimate, standard error, error, error in standard
        errors) and a one-line verdict.
    """
    if scope not in SCOPES:
        raise ValueError(f"scope must be one of {', '.join(SCOPES)}, got {scope!r}")
    estimates = [estimate] if isinstance(estimate, Estimate) else list(estimate)
    if not estimates:
        raise ValueError("no estimate to score")
    if isinstance(truth, FlightRecord):
        truth = record_truth(truth)
    covered = {n for e in estimates for n in (*e.names, *e.unidentifiable)}
    rows = [_row(name, float(value), estimates) for name, value in truth.items()
            if (scope == "all" or name in covered) and not name.endswith(REFERENCE_SUFFIX)]
    method = ", ".join(sorted({e.method for e in estimates}))
    return Score(rows, n_sigma, verdict(rows, n_sigma), method)


def verdict(rows: list[ScoreRow], n_sigma: float = 3.0) -> str:
    """One line: '13 estimated, 13 within 3 sigma, worst Cn_dr at 1.9 sigma'.

    Then the unidentifiable and not-estimated ones by name.

    Parameters
    ----------
    rows : list of ScoreRow
        The scored derivatives.
    n_sigma : float, optional
        The bound counted, in standard errors. Default 3.

    Returns
    -------
    str
        The line.
    """
    done = [r for r in rows if r.status == STATUS_ESTIMATED]
    parts = []
    if done:
        inside = sum(abs(r.sigmas) <= n_sigma for r in done)
        worst = max(done, key=lambda r: abs(r.sigmas))
        parts.append(f"{len(done)} estimated, {inside} within {n_sigma:g} sigma, worst "
                     f"{worst.name} at {abs(worst.sigmas):.1f} sigma")
    else:
        parts.append("nothing estimated")
    for status in (STATUS_UNIDENTIFIABLE, STATUS_NOT_ESTIMATED):
        names = [r.name for r in rows if r.status == status]
        if names:
            parts.append(f"{len(names)} {status} ({', '.join(names)})")
    return "; ".join(parts)


def load_truth(path: str | Path) -> dict[str, float]:
    """Truth values from JSON: {name: value} or {name: {"value": ...}} (also under "truth").

    The output of ``flightid truth --format json`` reads as is; keys that are not
    derivative names (``trim``, ``flags``) are metadata and skipped.

    Parameters
    ----------
    path : str or Path
        The JSON file.

    Returns
    -------
    dict of str to float
        {derivative: value}.

    Raises
    ------
    ValueError
        When the file is not UTF-8 JSON, not an object, or a value is not a number.
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path}: line {exc.lineno}: not valid JSON ({exc.msg})") from exc
    except UnicodeDecodeError:
        raise ValueError(f"{path}: not a JSON text file (its bytes are not UTF-8)") from None
    if isinstance(data, dict) and isinstance(data.get("truth"), dict):
        data = data["truth"]
    if not isinstance(data, dict):
        raise ValueError(f"{path}: expected a JSON object of derivative values")
    out = {}
    for name, value in data.items():
        if not is_derivative(name):
            continue  # metadata of `flightid truth --format json`: "trim", "flags", ...
        if isinstance(value, dict):
            if "value" not in value:
                raise ValueError(f"{path}: field {name!r} has no 'value'")
            value = value["value"]
        if not isinstance(value, int | float) or isinstance(value, bool):
            raise ValueError(f"{path}: field {name!r}: expected a number, got {value!r}")
        out[name] = float(value)
    return out


def _row(name: str, truth: float, estimates: list[Estimate]) -> ScoreRow:
    for est in estimates:
        if name in est.unidentifiable:
            return ScoreRow(name, truth, None, None, None, None, STATUS_UNIDENTIFIABLE,
                            est.unidentifiable[name])
    for est in estimates:
        if name in est.names:
            value, std = est[name], est.std_of(name)
            error = value - truth
            if std > 0:
                sig = error / std
            else:
                sig = 0.0 if error == 0 else math.copysign(math.inf, error)
            return ScoreRow(name, truth, value, std, error, sig, STATUS_ESTIMATED)
    return ScoreRow(name, truth, None, None, None, None, STATUS_NOT_ESTIMATED)
