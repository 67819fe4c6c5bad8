"""The common form of every injectable effect: a named dataclass of float parameters (SI).

``NamedEffect`` is the base of sensor errors, mounting effects, engine vibration and
disturbances; ``Effect`` adds ``apply`` for the per-channel effects of the sensor chain.
Which effects exist, what they act on and what their parameters mean is declared once,
in ``flightid.sim.effects.catalogue``.
"""

from __future__ import annotations

import dataclasses
import importlib
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np


@dataclass(kw_only=True)
class NamedEffect:
    """A named, parametrised effect: the common form of sensor errors, mounting effects and
    disturbances, so the simulator can inject any of them and a diagnosis fit it back.

    ``parameters()`` are the float fields (SI), what can be fitted; string fields choose a
    form (e.g. a turbulence model); ``source`` says where the values come from.
    """

    name: ClassVar[str] = ""
    key: ClassVar[str] = "effect"  # the card-table key that names the effect
    source: str = dataclasses.field(default="", compare=False)

    def parameters(self) -> dict[str, float]:
        """Float parameters by name (SI units)."""
        return {
            f.name: float(value)
            for f in dataclasses.fields(self)
            if f.name != "source"
            and isinstance(value := getattr(self, f.name), int | float)
            and not isinstance(value, bool)
        }

    def to_dict(self) -> dict[str, Any]:
        """``{key: name, **fields}`` plus the source if any (inverse of the from-dict builders)."""
        d: dict[str, Any] = {self.key: self.name}
        d.update({f.name: getattr(self, f.name) for f in dataclasses.fields(self)
                  if f.name != "source"})
        if self.source:
            d["source"] = self.source
        return d


@dataclass(kw_only=True)
class Effect(NamedEffect):
    """Base of the per-channel effects."""

    def apply(self, t: np.ndarray, x: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """The measured signal on times ``t`` (s) given the input signal ``x``."""
        raise NotImplementedError


def positive(value: float, field: str, name: str, strict: bool = True) -> None:
    """Raise naming ``field`` of effect ``name`` unless value > 0 (>= 0 if not strict).

    Parameters
    ----------
    value : float
        The value to check; NaN is refused.
    field : str
        The field's name, for the message.
    name : str
        The effect's name, for the message.
    strict : bool, optional
        Require > 0 (default) rather than >= 0.

    Raises
    ------
    ValueError
        Naming the effect and field.
    """
    ok = value > 0 if strict else value >= 0
    if not ok or np.isnan(value):
        raise ValueError(
            f"{name}: field {field!r} must be {'>' if strict else '>='} 0, got {value}"
        )


@dataclass(frozen=True)
class ExternalImplementation:
    """An implementation outside the effects package, named instead of imported.

    ``target`` is ``"module:attribute"``; ``fields`` maps each catalogue parameter to the
    target's own field (the parameter mapping); ``how`` says in a line how the target
    takes them. Used for the bridge's link faults and recorder clocks: the bridge sits on
    top of the measurement chain, and importing it here would load MAVLink into every
    simulation and tie the catalogue to the bridge's layout.
    """

    target: str
    fields: tuple[tuple[str, str], ...]
    how: str = ""

    def resolve(self) -> Any:
        """The target object (imported on demand by its dotted name)."""
        module, _, attribute = self.target.partition(":")
        return getattr(importlib.import_module(module), attribute)

    def mapping(self) -> dict[str, str]:
        """Catalogue parameter -> the target's field."""
        return dict(self.fields)

    def kwargs(self, values: Mapping[str, float]) -> dict[str, float]:
        """The target's keyword arguments for catalogue parameter ``values``."""
        mapping = self.mapping()
        unknown = [k for k in values if k not in mapping]
        if unknown:
            raise ValueError(f"{self.target}: no parameter {', '.join(unknown)}; "
                             f"known: {', '.join(mapping)}")
        return {mapping[k]: float(v) for k, v in values.items()}
