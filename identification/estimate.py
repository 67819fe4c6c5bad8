"""The one result type every identification method returns.

Values are nondimensional derivatives named as in ``flightid.derivatives`` (plus any
nuisance parameters such as biases, named ``bias_<channel>`` in the channel's SI unit).
Standard errors are Cramer-Rao bounds, corrected for colored residuals where the method
does so (``fit['std_kind']`` says which). A parameter the data cannot determine is not
given a value: it is listed in ``unidentifiable`` with the reason.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


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
    # time histories for reports: measured and modelled outputs, residuals (SI units)
    outputs: dict[str, dict[str, np.ndarray]] = field(default_factory=dict)
    time: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.values = np.asarray(self.values, dtype=float)
        self.std = np.asarray(self.std, dtype=float)
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
        """JSON form: {"estimates": {name: {"value", "std"}}, "fit": {...}, "unidentifiable"}."""
        return {
            "method": self.method,
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
