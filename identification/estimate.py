"""The one result type every identification method returns.

Values are nondimensional derivatives named as in ``flightid.derivatives`` (plus any
nuisance parameters such as biases, named ``bias_<channel>`` in the channel's SI unit).
Standard errors are Cramer-Rao bounds, corrected for colored residuals where the method
does so (``Estimate.std_kind`` says which). A parameter the data cannot determine is not
given a value: it is listed in ``unidentifiable`` with the reason.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

import numpy as np
import scipy.linalg


class StdKind(StrEnum):
    """What the standard errors of an estimate are."""

    CRAMER_RAO = "cramer-rao"
    """Cramer-Rao bounds sqrt(diag M^-1) assuming white residuals (Morelli & Klein 2016
    eq. 6.50; for least squares s^2 (X^T X)^-1, eq. 5.22)."""
    CRAMER_RAO_COLORED = "cramer-rao-colored"
    """Cramer-Rao bounds corrected for colored residuals (Morelli & Klein 2016 eq. 5.71
    for least squares, eq. 6.54 for output error)."""
    NONE = "none"
    """No standard errors (nothing estimated)."""

    @classmethod
    def parse(cls, text: str | StdKind) -> StdKind:
        """The kind named by ``text``: an enum value, or a method's older description
        ('OLS', 'corrected', 'cramer-rao corrected for colored residuals', ...)."""
        if isinstance(text, StdKind):
            return text
        low = str(text).lower()
        if low in {k.value for k in cls}:
            return cls(low)
        if low == "none":
            return cls.NONE
        if "colored" in low or "corrected" in low:
            return cls.CRAMER_RAO_COLORED
        return cls.CRAMER_RAO


@dataclass
class Estimate:
    """Parameter values, their standard errors and the fit statistics of one method."""

    method: str
    names: list[str]
    values: np.ndarray
    std: np.ndarray
    covariance: np.ndarray | None = None
    fit: dict[str, Any] = field(default_factory=dict)
    unidentifiable: dict[str, str] = field(default_factory=dict)
    # fitted and measured responses for reports, per output channel: time histories
    # {"measured", "model", "residual"} on ``time`` (SI units), or frequency responses
    # {"frequency" (Hz), "measured", "model"} (complex) for frequency-domain methods
    outputs: dict[str, dict[str, np.ndarray]] = field(default_factory=dict)
    time: np.ndarray | None = None
    std_kind: StdKind = StdKind.CRAMER_RAO

    def __post_init__(self) -> None:
        self.values = np.asarray(self.values, dtype=float)
        self.std = np.asarray(self.std, dtype=float)
        if "std_kind" in self.fit:  # methods that still describe their bounds in ``fit``
            self.std_kind = StdKind.parse(self.fit.pop("std_kind"))
        else:
            self.std_kind = StdKind.parse(self.std_kind)
        if not (len(self.names) == self.values.size == self.std.size):
            raise ValueError(
                f"{len(self.names)} names, {self.values.size} values and {self.std.size} "
                "standard errors: they must match"
            )

    def __getitem__(self, name: str) -> float:
        if name in self.unidentifiable:
            raise KeyError(f"{name} is unidentifiable: {self.unidentifiable[name]}")
        try:
            return float(self.values[self.names.index(name)])
        except ValueError:
            raise KeyError(
                f"{name} was not estimated; estimated: {', '.join(self.names)}") from None

    def __contains__(self, name: str) -> bool:
        return name in self.names

    def std_of(self, name: str) -> float:
        """Standard error of one parameter (same units as the value)."""
        return float(self.std[self.names.index(name)])

    def as_dict(self) -> dict[str, Any]:
        """JSON form: {"method", "std_kind", "estimates": {name: {"value", "std"}}, "fit",
        "unidentifiable"}."""
        return {
            "method": self.method,
            "std_kind": self.std_kind.value,
            "estimates": {
                n: {"value": float(v), "std": float(s)}
                for n, v, s in zip(self.names, self.values, self.std, strict=True)
            },
            "fit": {k: _jsonable(v) for k, v in self.fit.items()},
            "unidentifiable": dict(self.unidentifiable),
        }


def _jsonable(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, dict):
        return {k: _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    return value


def merge(method: str, parts: Sequence[Estimate]) -> Estimate:
    """One Estimate from independent per-coefficient fits (equation error, stepwise,
    frequency-domain equation error).

    Names are concatenated, the covariance is block diagonal, and each part's fit statistics
    go under ``fit['coefficients'][<coefficient>]``.

    Parameters
    ----------
    method : str
        The method name of the merged estimate.
    parts : sequence of Estimate
        The per-coefficient estimates; their parameter names must not overlap.

    Returns
    -------
    Estimate
        The merged estimate.

    Raises
    ------
    ValueError
        When ``parts`` is empty or two parts share a parameter.
    """
    if not parts:
        raise ValueError("no estimate to merge")
    names = [n for p in parts for n in p.names]
    if len(set(names)) != len(names):
        raise ValueError(f"estimates to merge share parameters: {names}")
    blocks = [p.covariance if p.covariance is not None else np.diag(p.std ** 2)
              for p in parts]
    kinds = {p.std_kind for p in parts}
    coefficients = {str(p.fit.get("coefficient", i)): dict(p.fit) for i, p in enumerate(parts)}
    outputs: dict[str, dict[str, np.ndarray]] = {}
    for p in parts:
        outputs.update(p.outputs)
    return Estimate(
        method=method, names=names,
        values=np.concatenate([p.values for p in parts]),
        std=np.concatenate([p.std for p in parts]),
        covariance=scipy.linalg.block_diag(*blocks) if names else np.zeros((0, 0)),
        fit={"coefficients": coefficients},
        unidentifiable={k: v for p in parts for k, v in p.unidentifiable.items()},
        outputs=outputs, time=parts[0].time,
        std_kind=kinds.pop() if len(kinds) == 1 else StdKind.CRAMER_RAO,
    )
