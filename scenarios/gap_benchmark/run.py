"""One blind case flown, diagnosed without being told, and scored.

Each aircraft flies one card (``card``): its condition (``cases.Flight``), the lateral
inputs (an aileron doublet, a rudder 2-1-1, an aileron doublet, a rudder doublet) then an
elevator doublet and a 3211 (``SCHEDULE``, 64 s at 50 Hz), so both axes have two windows
that can be held out; the research sensor suite with the vane-position and accelerometer
lever-arm effects dropped (air data and accelerations corrected to the CG, as after a
compatibility check: the diagnosis's models do not carry them); light turbulence by
default. On a case with an actuator lag or rate limit the record's surface channels hold the
commands (``commands``: the trim plus the designed inputs, ahead of every actuator); its
mass-property channels hold the plain aircraft's values (the weight-and-balance sheet's),
whatever mass, inertia or CG was injected.

The diagnosis (``identification.gap.diagnose``, both axes) sees the blinded record
(``blind``: what was injected removed from its metadata) and the plain aircraft's name.
Scoring per axis (``scoring.score``): the verdict, whether the first named effect is in the
injected one's class (``classes``), its magnitude error, and the held-out gap above the
null level (the plain model's held-out gap on the plain flight of the same seed: the same
turbulence and sensor noise, ``null_level``).
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Any

import numpy as np

from flightid.channels import CONTROL_SURFACES
from flightid.identification.data.axes import AXIS_INPUTS
from flightid.identification.gap import diagnose
from flightid.identification.gap.model.linearise import AXIS_FRAME, linearise
from flightid.identification.gap.model.surfaces import SURFACES_KEY
from flightid.identification.gap.rank import Folds, Ranker
from flightid.identification.gap.ranked import mean_gap, pooled_fractions
from flightid.identification.gap.segments import segments
from flightid.record import FlightRecord
from flightid.scenarios.cards import AUGMENT_CACHE, Card, card_from_dict, fly_card, sub_seed
from flightid.scenarios.gap_benchmark.cases import (
    AIRCRAFT,
    NULL,
    Case,
    Effect,
)
from flightid.scenarios.gap_benchmark.outside_catalogue import RECORD, cm_alpha_break
from flightid.scenarios.gap_benchmark.scoring import CaseResult, score
from flightid.scenarios.inputs import inputs_from_list, total_signals
from flightid.sim.effects.catalogue import CATALOGUE
from flightid.sim.jsbsim.condition import FlightCondition
from flightid.sim.jsbsim.model import load
from flightid.sim.jsbsim.trim import trim
from flightid.sim.jsbsim.truth import derivatives
from flightid.sim.sensors.suites import measure
from flightid.units import DEG

# (kind, surface, start s): the lateral surfaces twice each, 10 s apart, then the elevator
# twice (an aileron 3211 banked the navion and the twin otter past 40 deg: outside the
# perturbation model; doublets leave 11-15 deg)
SCHEDULE = (("doublet", "da", 2.0), ("211", "dr", 12.0), ("doublet", "da", 22.0),
            ("doublet", "dr", 32.0), ("doublet", "de", 42.0), ("3211", "de", 52.0))
DURATION_S = 64.0
RATE_HZ = 50.0
# effects of the research suite the diagnosis's models do not carry (vane position and
# upwash, accelerometer lever arm): air data and accelerations corrected to the CG first
DROPPED = ("vanes", "lever_arm")
# the record metadata saying its surface channels hold commands, not positions (the key
# the diagnosis reads for actuator candidates; rename here if it lands under another one)
SURFACES_META = (SURFACES_KEY, "command")
# actuator effects the surface positions show (in series after the position's writer,
# ``sim.augment``): a record of commands does not
BEHIND_POSITION = ("actuator_lag", "rate_limit")
# effects on the mass properties, which the record's mass channels must not reveal: a
# research record carries the weight-and-balance sheet's values, those of the model
MASS_EFFECTS = ("mass_scale", "inertia_scale", "cg_offset")
MASS_CHANNELS = ("mass", "Ixx", "Iyy", "Izz", "Ixz")
# the record metadata a blinded record keeps (``blind``)
KEPT = ("inputs", "maneuvers", "measurement", SURFACES_META[0])


def _maneuver(kind: str, surface: str, start: float, name: str) -> dict[str, Any]:
    f = AIRCRAFT[name]
    amplitude = {"da": f.aileron_deg, "dr": f.rudder_deg, "de": f.elevator_deg}[surface]
    base = f.elevator_base_s if surface == "de" else f.base_s
    return {"kind": kind, "surface": surface, "start": start, "base": base,
            "amplitude_deg": amplitude}


def card(aircraft: str, seed: int, effects: list[dict[str, Any]] | None = None,
         turbulence: str = "light", mounting: list[dict[str, Any]] | None = None,
         disturbances: list[dict[str, Any]] | None = None, xml: str | None = None) -> Card:
    """The test card of ``aircraft`` (module note) with airframe or actuator ``effects``
    (``[[effect]]`` tables), a sensor ``mounting`` list, extra ``disturbances``; ``xml``:
    fly this aircraft file instead (an aircraft-level change outside the catalogue).

    Parameters
    ----------
    aircraft : str
        Aircraft name, a key of ``AIRCRAFT``.
    seed : int
        The flight's seed.
    effects : list[dict[str, Any]] or None, optional
        ``[[effect]]`` tables.
    turbulence : str, optional
        ``"calm"``, ``"light"`` or ``"moderate"``. Default ``"light"``.
    mounting : list[dict[str, Any]] or None, optional
        Sensor mounting effects; replaces the suite's list.
    disturbances : list[dict[str, Any]] or None, optional
        Extra ``[[disturbance]]`` tables.
    xml : str or None, optional
        Aircraft XML file to fly instead of ``aircraft``.

    Returns
    -------
    Card
        The validated flight card.
    """
    f = AIRCRAFT[aircraft]
    cond: dict[str, float] = {"altitude": f.altitude_m, "speed": f.speed_m_s}
    if f.flaps_deg:
        cond["flaps_deg"] = f.flaps_deg
    sensors: dict[str, Any] = {"suite": "research", "drop": list(DROPPED)}
    if mounting:  # replaces the suite's mounting list: DROPPED gone all the same
        sensors = {"suite": "research", "mounting": mounting}
    dist = list(disturbances or [])
    if turbulence != "calm":
        dist.append({"kind": "turbulence", "intensity": turbulence})
    data: dict[str, Any] = {
        "name": f"gap-benchmark-{aircraft}", "aircraft": aircraft,
        "duration": DURATION_S, "rate": RATE_HZ, "seed": seed, "condition": cond,
        "maneuver": [_maneuver(k, s, t, aircraft) for k, s, t in SCHEDULE],
        "sensors": sensors}
    if dist:
        data["disturbance"] = dist
    if effects:
        data["effect"] = effects
    flown = card_from_dict(data, f"<gap-benchmark {aircraft}>")
    # a card names a known aircraft; the changed file is swapped in once it is checked
    return replace(flown, aircraft=xml) if xml else flown


def truths(aircraft: tuple[str, ...] = tuple(AIRCRAFT)) -> dict[str, dict[str, float]]:
    """Each aircraft's derivatives at its test condition: lateral ones in body axes,
    longitudinal ones in stability axes (the axes of the diagnosis's models), and
    ``trim_alpha`` (rad).

    Parameters
    ----------
    aircraft : tuple[str, ...], optional
        Aircraft names. Default every one of ``AIRCRAFT``.

    Returns
    -------
    dict[str, dict[str, float]]
        Aircraft -> derivative name -> value (per rad, rates nondimensional), plus
        ``trim_alpha``, rad.
    """
    out = {}
    for name in aircraft:
        f = AIRCRAFT[name]
        model = load(name)
        trimmed = trim(model, FlightCondition(f.altitude_m, f.speed_m_s,
                                              flaps_rad=f.flaps_deg * DEG))
        values: dict[str, float] = {}
        for axis in ("longitudinal", "lateral"):
            truth = derivatives(model, trimmed, axes=AXIS_FRAME[axis])
            values.update(truth.values)
            # a kink at trim (the c172p's Cn_beta: 0.0593 and 0.0604 either side): the
            # mean of the one-sided slopes, as the diagnosis's linearisation takes it
            values.update({k: 0.5 * (kink.minus + kink.plus) for k, kink in truth.flags.items()
                           if k not in truth.values and hasattr(kink, "minus")})
        values["trim_alpha"] = float(trimmed.alpha)
        out[name] = values
    return out


def commands(measured: FlightRecord, truth: FlightRecord, flown: Card) -> FlightRecord:
    """``measured`` marked as holding the surface commands (``SURFACES_META``), each surface
    channel the command (the trim position plus the card's designed inputs, as the flight
    core writes it ahead of the aircraft's own actuators) measured by the card's sensors
    with the same seed: what an actuator lag or rate limit hides from the positions. The
    diagnosis runs a command record through the plain aircraft's own actuators
    (``identification.gap.model.surfaces.actuated``), so the injected lag or rate limit is
    what the model lacks.

    Parameters
    ----------
    measured : FlightRecord
        The measured record of the flight.
    truth : FlightRecord
        Its truth record (the trim positions and the designed inputs).
    flown : Card
        The flown card (its sensors and seed).

    Returns
    -------
    FlightRecord
        The command record.
    """
    designed = total_signals(inputs_from_list(truth.meta.extra["inputs"]), truth.time)
    surfaces = [s for s in CONTROL_SURFACES if s in measured and s in truth]
    commanded = truth.with_channels(**{
        s: truth[s][0] + designed.get(s, np.zeros_like(truth.time)) for s in surfaces})
    again = measure(commanded, flown.sensors, sub_seed(flown.seed, "sensors"))
    out = measured.with_channels(**{s: again[s] for s in surfaces})
    out.meta = replace(out.meta, extra={**out.meta.extra, SURFACES_META[0]: SURFACES_META[1]})
    return out


def blind(record: FlightRecord, aircraft: str) -> FlightRecord:
    """``record`` as a diagnosis of a real record would have it: the plain ``aircraft``'s
    name, the metadata of ``KEPT`` only (the maneuvers and inputs flown, how it was
    measured, what its surface channels hold), the card without its effects and
    disturbances. Gone: what was injected, the augmented aircraft's file and exact truth,
    the turbulence.

    Parameters
    ----------
    record : FlightRecord
        The measured record.
    aircraft : str
        The plain aircraft's name.

    Returns
    -------
    FlightRecord
        A blinded copy.
    """
    extra = {k: v for k, v in record.meta.extra.items() if k in KEPT}
    scenario = dict(record.meta.scenario)
    if "card" in scenario:
        scenario["card"] = {k: v for k, v in scenario["card"].items()
                            if k not in ("effect", "disturbance")} | {"aircraft": aircraft}
    out = record.with_channels()
    out.meta = replace(out.meta, aircraft=aircraft, extra=extra, scenario=scenario)
    return out


def _parameters(effect: Effect) -> dict[str, Any]:
    """The card-table fields of an effect: the sized parameters drawn, the others neutral
    (an entry's class default is its blind-test magnitude, not nothing)."""
    entry = CATALOGUE[effect.entry]
    values: dict[str, Any] = {p.name: p.zero for p in entry.parameters if p.sizes}
    values.update(effect.magnitude)
    return {**values, **effect.options}


def fly_case(case: Case, turbulence: str = "light",
             truth: dict[str, float] | None = None) -> FlightRecord:
    """The measured, blinded record of ``case`` (its effects injected; module note).
    ``truth``: the aircraft's ``truths`` entry (needed by a pitch break).

    Parameters
    ----------
    case : Case
        The benchmark case.
    turbulence : str, optional
        Turbulence intensity, as in :func:`card`.
    truth : dict[str, float] or None, optional
        The aircraft's :func:`truths` entry; None computes it when needed.

    Returns
    -------
    FlightRecord
        The blinded measured record.
    """
    effects, mounting, disturbances, xml = [], [], [], None
    for e in case.effects:
        if e.inject == "card" and e.in_catalogue:
            effects.append({"name": e.entry, **_parameters(e)})
        elif e.inject == "mounting":
            mounting.append({"effect": e.entry, **_parameters(e)})
        elif e.inject == "disturbance":
            disturbances.append({"kind": e.entry, **_parameters(e)})
        elif e.entry == "cm_alpha_break":
            alpha = (truth or truths((case.aircraft,))[case.aircraft])["trim_alpha"]
            xml = cm_alpha_break(case.aircraft, alpha, e.magnitude["above"],
                                 e.magnitude["delta"], AUGMENT_CACHE)
    flown = card(case.aircraft, case.seed, effects, turbulence, mounting, disturbances, xml)
    measured, truth_record = fly_card(flown)
    record = measured
    if any(e.entry in BEHIND_POSITION for e in case.effects):
        record = commands(measured, truth_record, flown)
    if any(e.entry in MASS_EFFECTS for e in case.effects):
        # the weight-and-balance sheet's values: the plain aircraft's
        plain = fly_card(card(case.aircraft, case.seed, turbulence="calm"))[1]
        record = record.with_channels(**{
            c: np.interp(record.time, plain.time, plain[c]) for c in MASS_CHANNELS
            if c in record and c in plain})
    rng = np.random.default_rng([case.seed, 7])
    for e in case.effects:
        if e.inject != "measured":
            continue
        if e.in_catalogue:
            ch = e.options["channel"]
            effect = CATALOGUE[e.entry].build(e.magnitude)
            record = record.with_channels(**{ch: effect.apply(record.time, record[ch], rng)})
        elif e.entry == "structural_mode":
            record = RECORD[e.entry](record, **e.magnitude, axis=e.axis)
        else:
            record = RECORD[e.entry](record, **e.magnitude, **e.options)
    return blind(record, case.aircraft)


def null_level(case: Case, axes: tuple[str, ...], turbulence: str = "light",
               plain: FlightRecord | None = None) -> dict[str, float]:
    """Per axis: the held-out gap of the plain model on the plain flight of ``case``'s
    aircraft and seed (the same turbulence and sensor noise): what no effect can close.

    Parameters
    ----------
    case : Case
        The benchmark case.
    axes : tuple[str, ...]
        Axes to measure.
    turbulence : str, optional
        Turbulence intensity, as in :func:`card`.
    plain : FlightRecord or None, optional
        The plain flight; None flies it.

    Returns
    -------
    dict[str, float]
        Axis -> held-out gap, 1.
    """
    if plain is None:
        plain = fly_case(Case(case.index, case.seed, case.aircraft, NULL), turbulence)
    out = {}
    for axis in axes:
        inputs = AXIS_INPUTS[axis]
        ranker = Ranker(linearise(case.aircraft, [plain], axis),
                        Folds.make(segments([plain], None, inputs), None))
        out[axis] = mean_gap(pooled_fractions(list(ranker.base_held.values())))
    return out


def run_case(case: Case, turbulence: str = "light", truth: dict[str, float] | None = None,
             null: bool = True, **options: Any) -> CaseResult:
    """Fly ``case``, diagnose it (``options`` as for ``diagnose``), score it; with
    ``null``, the null level of the injected effects' axes where something is named too
    (one more flight; a null case needs none: nothing injected, nothing to shrink).

    Parameters
    ----------
    case : Case
        The benchmark case.
    turbulence : str, optional
        Turbulence intensity, as in :func:`card`.
    truth : dict[str, float] or None, optional
        The aircraft's :func:`truths` entry; None computes it when needed.
    null : bool, optional
        Measure the null level. Default True.
    **options : Any
        Options of ``diagnose``.

    Returns
    -------
    CaseResult
        The scored case with its wall and CPU time, s.
    """
    t0, c0 = time.perf_counter(), time.process_time()
    record = fly_case(case, turbulence, truth)
    result = diagnose([record], case.aircraft, **options)
    out = score(case, result)
    if null and out.before:
        out.null = null_level(case, tuple(out.before), turbulence)
    out.seconds, out.cpu_seconds = time.perf_counter() - t0, time.process_time() - c0
    return out
