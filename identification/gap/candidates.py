"""Candidate effects: entries of the effect catalogue, expressed in the linearised model.

Each candidate names its catalogue entry (``flightid.sim.effects.catalogue``) and options,
and says how it changes the linear model (a wrapped ``LinearModel`` with the effect's
parameter) and which parameters a fit frees:

- ``derivative_delta`` (airframe): one derivative of the model freed; the delta is the
  fitted value minus the model's (body axes, per rad or per unit nondimensional rate);
- ``control_effectiveness`` (airframe): every derivative of one surface scaled by
  ``factor`` (1: the model);
- ``scale`` (sensor): one measured output scaled by ``factor`` (1: none).

Sensor biases are not candidates: the model's output and state biases (nuisance
parameters fitted on every window) absorb them.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from flightid.identification.gap.linearise import DERIVATIVES
from flightid.identification.linear_models import LinearModel

SURFACES = ("da", "dr")
OUTPUTS = ("beta", "p", "r", "phi", "ay")


@dataclass(frozen=True)
class Candidate:
    """One catalogue effect as the gap fits it."""

    entry: str  # catalogue name
    options: dict[str, str]
    free: tuple[str, ...]  # linear-model parameters the fit frees
    wrap: Callable[[LinearModel], LinearModel] = field(compare=False, repr=False)
    parts: tuple[Candidate, ...] = ()  # the single effects of a pair

    @property
    def label(self) -> str:
        if self.parts:
            return " + ".join(p.label for p in self.parts)
        opts = ",".join(f"{v}" for v in self.options.values())
        return f"{self.entry}({opts})"

    def parameters(self, values: Mapping[str, float], std: Mapping[str, float],
                   base: LinearModel) -> dict[str, dict[str, float]]:
        """The effect's parameters in catalogue units: {name: {"value", "std"}}."""
        if self.parts:
            out: dict[str, dict[str, float]] = {}
            for p in self.parts:
                for k, v in p.parameters(values, std, base).items():
                    out[f"{p.label}.{k}"] = v
            return out
        (name,) = self.free
        value, s = float(values[name]), float(std[name])
        if self.entry == "derivative_delta":
            return {"delta": {"value": value - base.start[name], "std": s}}
        return {"factor": {"value": value, "std": s}}


def _identity(model: LinearModel) -> LinearModel:
    return model


def _extended(model: LinearModel, name: str, start: float,
              build: Callable[[Mapping[str, complex]], tuple]) -> LinearModel:
    return LinearModel(model.name, model.states, model.inputs, model.outputs,
                       (*model.parameters, name), {**model.start, name: start}, build,
                       model.condition, model.description, dict(model.state_channels))


def _effectiveness(surface: str) -> Callable[[LinearModel], LinearModel]:
    name = f"factor_{surface}"

    def wrap(model: LinearModel) -> LinearModel:
        scaled = [d for d in model.parameters if d.endswith(f"_{surface}")]

        def build(v: Mapping[str, complex]) -> tuple:
            w = dict(v)
            for d in scaled:
                w[d] = v[d] * v[name]
            return model.build(w)

        return _extended(model, name, 1.0, build)

    return wrap


def _output_scale(channel: str) -> Callable[[LinearModel], LinearModel]:
    name = f"scale_{channel}"

    def wrap(model: LinearModel) -> LinearModel:
        row = model.outputs.index(channel)

        def build(v: Mapping[str, complex]) -> tuple:
            A, B, C, D = model.build(v)
            k = v[name]
            dtype = np.result_type(C.dtype, type(k))
            C, D = C.astype(dtype), D.astype(dtype)
            C[row] *= k
            D[row, :-1] *= k
            return A, B, C, D

        return _extended(model, name, 1.0, build)

    return wrap


def catalogue_candidates(model: LinearModel) -> list[Candidate]:
    """Every single-effect candidate for ``model`` (the linearised aircraft)."""
    out = [Candidate("derivative_delta", {"derivative": d, "axes": "body"}, (d,), _identity)
           for d in DERIVATIVES if d in model.parameters]
    out += [Candidate("control_effectiveness", {"surface": s}, (f"factor_{s}",),
                      _effectiveness(s)) for s in SURFACES if s in model.inputs]
    out += [Candidate("scale", {"channel": c}, (f"scale_{c}",), _output_scale(c))
            for c in OUTPUTS if c in model.outputs]
    return out


def pair(a: Candidate, b: Candidate) -> Candidate | None:
    """Both effects at once; None when they free the same parameter."""
    if set(a.free) & set(b.free):
        return None

    def wrap(model: LinearModel) -> LinearModel:
        return b.wrap(a.wrap(model))

    return Candidate("pair", {}, (*a.free, *b.free), wrap, (a, b))
