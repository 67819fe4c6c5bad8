"""Candidate effects: entries of the effect catalogue, expressed in the linearised model.

Each candidate names its catalogue entry (``flightid.sim.effects.catalogue``) and options,
and says how it changes the linear model (a wrapped ``LinearModel`` with the effect's
parameter) and which parameters a fit frees:

- ``derivative_delta`` (airframe): one derivative of the model freed; the delta is the
  fitted value minus the model's (body axes, per rad or per unit nondimensional rate);
- ``control_effectiveness`` (airframe): every derivative of one surface scaled by
  ``factor`` (1: the model);
- ``scale`` (sensor): one measured output scaled by ``factor`` (1: none);
- ``tail_ice`` (airframe, longitudinal): ice on the horizontal tail. The tail's lift slope
  and its elevator effectiveness fall together, so the tail's share of every
  pitching-moment derivative falls with them (Etkin & Reid 1996 ch. 2:
  Cm_alpha_tail = -eta V_H a_t (1 - deps/dalpha), Cm_q_tail = -2 eta V_H a_t l_t/cbar,
  Cm_de = -eta V_H a_t tau; Batterson & O'Mara, NASA TM-4099, 1989: loss of elevator
  effectiveness, static stability and pitch damping with a glaze-ice tail). The catalogue
  entry's three factors: ``elevator`` scales Cm_de, ``stability`` Cm_alpha, ``damping``
  Cm_q (and Cm_alphadot); lift and drag are left as they are.

Sensor biases are not candidates: the model's output and state biases (nuisance
parameters fitted on every window) absorb them.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from flightid.identification.gap.linearise import AXIS_DERIVATIVES, TRIM_TERMS
from flightid.identification.linear_models import LinearModel

SURFACES = ("da", "dr", "de")
OUTPUTS = ("beta", "p", "r", "phi", "ay")  # the lateral model's
LONGITUDINAL_OUTPUTS = ("V", "alpha", "q", "theta", "az")


@dataclass(frozen=True)
class Candidate:
    """One catalogue effect as the gap fits it."""

    entry: str  # catalogue name ("pair": a group of ``parts``)
    options: dict[str, str]
    free: tuple[str, ...]  # linear-model parameters the fit frees
    wrap: Callable[[LinearModel], LinearModel] = field(compare=False, repr=False)
    parts: tuple[Candidate, ...] = ()  # the single effects of a pair

    @property
    def label(self) -> str:
        if self.parts:
            inner = " + ".join(p.label for p in self.parts)
            return inner if self.entry == "pair" else f"{self.entry}[{inner}]"
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
        if self.entry == "tail_ice":
            return {k: {"value": float(values[f"tail_{k}"]), "std": float(std[f"tail_{k}"])}
                    for k in TAIL_ICE}
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


def _derivative(name: str, axes: str) -> Candidate:
    return Candidate("derivative_delta", {"derivative": name, "axes": axes}, (name,),
                     _identity)


def _surface(surface: str) -> Candidate:
    return Candidate("control_effectiveness", {"surface": surface}, (f"factor_{surface}",),
                     _effectiveness(surface))


def catalogue_candidates(model: LinearModel, axes: str = "body") -> list[Candidate]:
    """Every single-effect candidate for ``model`` (the linearised aircraft, its
    derivatives in ``axes``), and tail ice when the model is longitudinal."""
    known = {d for names in AXIS_DERIVATIVES.values() for d in names} - set(TRIM_TERMS)
    out = [_derivative(d, axes) for d in model.parameters if d in known]
    out += [_surface(s) for s in SURFACES if s in model.inputs]
    out += [Candidate("scale", {"channel": c}, (f"scale_{c}",), _output_scale(c))
            for c in model.outputs]
    tail = tail_candidate(model)
    return out + ([tail] if tail else [])


TAIL_ICE = {"elevator": ("Cm_de",), "stability": ("Cm_alpha",),
            "damping": ("Cm_q", "Cm_alphadot")}  # catalogue parameter -> scaled derivatives


def _tail_ice(model: LinearModel) -> LinearModel:
    scaled = {f"tail_{k}": [d for d in ds if d in model.parameters] for k, ds in TAIL_ICE.items()}
    names = tuple(scaled)

    def build(v: Mapping[str, complex]) -> tuple:
        w = dict(v)
        for factor, derivs in scaled.items():
            for d in derivs:
                w[d] = v[d] * v[factor]
        return model.build(w)

    return LinearModel(model.name, model.states, model.inputs, model.outputs,
                       (*model.parameters, *names), {**model.start, **dict.fromkeys(names, 1.0)},
                       build, model.condition, model.description, dict(model.state_channels))


def tail_candidate(model: LinearModel) -> Candidate | None:
    """The catalogue's ``tail_ice`` (three factors); None when the model has no elevator
    or no pitching-moment derivatives."""
    if "de" not in model.inputs or not {"Cm_de", "Cm_alpha", "Cm_q"} <= set(model.parameters):
        return None
    return Candidate("tail_ice", {}, tuple(f"tail_{k}" for k in TAIL_ICE), _tail_ice)


def group(entry: str, parts: list[Candidate]) -> Candidate | None:
    """Several effects at once, named ``entry`` (a group among them flattened into its
    parts); None when two free the same parameter."""
    parts = [q for p in parts for q in (p.parts or (p,))]
    free = [f for p in parts for f in p.free]
    if len(set(free)) < len(free):
        return None

    def wrap(model: LinearModel) -> LinearModel:
        for p in parts:
            model = p.wrap(model)
        return model

    return Candidate(entry, {}, tuple(free), wrap, tuple(parts))


def pair(a: Candidate, b: Candidate) -> Candidate | None:
    """Both effects at once; None when they free the same parameter."""
    return group("pair", [a, b])
