"""Candidate effects: entries of the effect catalogue, expressed in the linearised model.

Each candidate (``model.Candidate``) names its catalogue entry
(``flightid.sim.effects.catalogue``) and options, says how it changes the linear model (a
wrapped ``LinearModel`` with the effect's parameters) and which parameters a fit frees;
``Candidate.parameters`` gives them in the catalogue's units. The airframe families here:

- ``derivative_delta`` (airframe): one derivative of the model freed; the delta is the
  fitted value minus the model's (the axis's axes: body lateral, stability longitudinal;
  per rad or per unit nondimensional rate), on both axes;
- ``control_effectiveness`` (airframe): every derivative of one surface scaled by
  ``factor`` (1: the model), on both axes (da, dr lateral; de longitudinal);
- ``tail_ice`` (airframe, longitudinal): ice on the horizontal tail. The tail's lift slope
  and its elevator effectiveness fall together, so the tail's share of every
  pitching-moment derivative falls with them (Etkin & Reid 1996 ch. 2:
  Cm_alpha_tail = -eta V_H a_t (1 - deps/dalpha), Cm_q_tail = -2 eta V_H a_t l_t/cbar,
  Cm_de = -eta V_H a_t tau; Batterson & O'Mara, NASA TM-4099, 1989: loss of elevator
  effectiveness, static stability and pitch damping with a glaze-ice tail). The catalogue
  entry's three factors: ``elevator`` scales Cm_de, ``stability`` Cm_alpha, ``damping``
  Cm_q (and Cm_alphadot); lift and drag are left as they are.

The other families have their own modules: ``sensor`` (scale, delay, lag,
misalignment, lever arm, vanes), ``actuator`` (actuator lag, on records of
commands) and ``mass`` (cg offset, mass, inertia, thrust moment). Entries that
are not candidates for a record are listed with the reason by
``identifiable.not_identifiable``; parameters outside the catalogue's physical range are
named by ``ranges.out_of_range``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

from flightid.identification.gap.candidates.actuator import actuator_candidates
from flightid.identification.gap.candidates.linkage import linkage_candidates
from flightid.identification.gap.candidates.mass import mass_candidates
from flightid.identification.gap.candidates.sensor import sensor_candidates
from flightid.identification.gap.model.edits import Candidate, extended, identity
from flightid.identification.gap.model.linearise import AXIS_DERIVATIVES, AXIS_OUTPUTS, TRIM_TERMS
from flightid.identification.gap.model.surfaces import surfaces_of
from flightid.identification.models.linear import LinearModel
from flightid.record import FlightRecord

SURFACES = ("da", "dr", "de")
OUTPUTS = AXIS_OUTPUTS["lateral"]  # the lateral model's
LONGITUDINAL_OUTPUTS = AXIS_OUTPUTS["longitudinal"]


def _effectiveness(surface: str) -> Callable[[LinearModel], LinearModel]:
    name = f"factor_{surface}"

    def wrap(model: LinearModel) -> LinearModel:
        scaled = [d for d in model.parameters
                  if d.startswith("C") and d.endswith(f"_{surface}")]

        def build(v: Mapping[str, complex]) -> tuple:
            w = dict(v)
            for d in scaled:
                w[d] = v[d] * v[name]
            return model.build(w)

        return extended(model, {name: 1.0}, build)

    return wrap


def _derivative(name: str, axes: str) -> Candidate:
    return Candidate("derivative_delta", {"derivative": name, "axes": axes}, (name,),
                     identity)


def _surface(surface: str) -> Candidate:
    return Candidate("control_effectiveness", {"surface": surface}, (f"factor_{surface}",),
                     _effectiveness(surface))


def catalogue_candidates(model: LinearModel, axes: str = "body", *,
                         surfaces: str | None = None,
                         records: Sequence[FlightRecord] = ()) -> list[Candidate]:
    """Every single-effect candidate for ``model`` (the linearised aircraft, its
    derivatives in ``axes``): derivative deltas and control effectiveness, tail ice (a
    longitudinal model), the sensor and mounting candidates of its outputs, the mass
    properties, and the actuator lags when ``surfaces`` (None: from the ``records``'
    metadata, ``model.surfaces.surfaces_of``) is "command".

    Parameters
    ----------
    model : LinearModel
        The linearised aircraft of one axis.
    axes : str
        Axes of its derivatives ("body" lateral, "stability" longitudinal).
    surfaces : str or None
        "position" or "command" (None: from ``records``).
    records : sequence of FlightRecord
        The records (their metadata says what the surfaces hold).

    Returns
    -------
    list of Candidate
        Every single-effect candidate for the model.
    """
    known = {d for names in AXIS_DERIVATIVES.values() for d in names} - set(TRIM_TERMS)
    out = [_derivative(d, axes) for d in model.parameters if d in known]
    out += [_surface(s) for s in SURFACES if s in model.inputs]
    tail = tail_candidate(model)
    out += [tail] if tail else []
    out += sensor_candidates(model)
    out += mass_candidates(model)
    kind = surfaces_of(records, surfaces)
    return out + actuator_candidates(model, kind) + linkage_candidates(model.inputs, kind)


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

    return extended(model, dict.fromkeys(names, 1.0), build)


def tail_candidate(model: LinearModel) -> Candidate | None:
    """The catalogue's ``tail_ice`` (three factors); None when the model has no elevator
    or no pitching-moment derivatives.

    Parameters
    ----------
    model : LinearModel
        The linearised aircraft of one axis.

    Returns
    -------
    Candidate or None
        Its three factors (elevator, stability, damping; 1: the model).
    """
    if "de" not in model.inputs or not {"Cm_de", "Cm_alpha", "Cm_q"} <= set(model.parameters):
        return None
    return Candidate("tail_ice", {}, tuple(f"tail_{k}" for k in TAIL_ICE), _tail_ice,
                     catalogue=tuple(TAIL_ICE))


def group(entry: str, parts: list[Candidate]) -> Candidate | None:
    """Several effects at once, named ``entry`` (a group among them flattened into its
    parts); None when two free the same parameter.

    Parameters
    ----------
    entry : str
        The group's name ("pair": a pair of effects).
    parts : list of Candidate
        The effects.

    Returns
    -------
    Candidate or None
        The group, freeing every part's parameters.
    """
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
    """Both effects at once; None when they free the same parameter.

    Parameters
    ----------
    a, b : Candidate
        The two effects.

    Returns
    -------
    Candidate or None
        The pair.
    """
    return group("pair", [a, b])
