"""The reference condition of a linear perturbation model: the trim flight condition, mass
properties and reference geometry (SI units, rad), taken from a record's channel means
(the flight condition over the trim before the first listed maneuver, when there is one)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flightid.record import FlightRecord
from flightid.units import G0


@dataclass(frozen=True)
class ReferenceCondition:
    """Reference condition and mass properties of a perturbation model (SI units, rad).

    V true airspeed (m/s), qbar dynamic pressure (Pa), alpha and theta trim angle of attack
    and pitch angle (rad), mass (kg), inertias (kg m^2, Ixz positive as in Etkin), area
    (m^2), span and chord (m), g (m/s^2), thrust (N, along body x; 0 when unknown).
    """

    V: float
    qbar: float
    alpha: float
    theta: float
    mass: float
    Ixx: float
    Iyy: float
    Izz: float
    Ixz: float
    area: float
    span: float
    chord: float
    g: float = G0
    thrust: float = 0.0

    def __post_init__(self) -> None:
        for name in ("V", "qbar", "mass", "Ixx", "Iyy", "Izz", "area", "span", "chord", "g"):
            value = getattr(self, name)
            if not np.isfinite(value) or value <= 0:
                raise ValueError(
                    f"flight condition {name} must be positive and finite, got {value}"
                )
        if not np.isfinite(self.thrust):
            raise ValueError(f"flight condition thrust must be finite (N), got {self.thrust}")


CONDITION_CHANNELS = ("V", "qbar", "alpha", "theta", "mass", "Ixx", "Iyy", "Izz", "Ixz")


# the flight condition a perturbation model is linearised about: the trim before the
# maneuver, when the record says where its maneuvers start. The record's mean was 1.4 %
# above the trim dynamic pressure on twinotter-21-elevator (the phugoid after the
# doublet), and Cm_de came out 1-2 % small in magnitude, 6-14 bounds (docs/validation.md)
TRIM_CHANNELS = ("V", "qbar", "alpha", "theta")
MIN_TRIM_S = 0.5  # s of trim before the first maneuver needed to take the condition from it


def trim_lead(record: FlightRecord) -> np.ndarray | None:
    """Boolean mask of the samples before the record's first listed maneuver.

    Parameters
    ----------
    record : FlightRecord
        The flight; its maneuvers are ``meta.extra['maneuvers']`` (each with a ``start``, s).

    Returns
    -------
    numpy.ndarray or None
        Mask, shape (n,), True before the first maneuver's start; None when the record lists
        no maneuver or the lead spans less than ``MIN_TRIM_S`` s.
    """
    listed = record.meta.extra.get("maneuvers") or []
    if not listed:
        return None
    first = min(float(m["start"]) for m in listed)
    t = np.asarray(record.time, dtype=float)
    mask = t < first
    if not mask.any() or first - t[0] < MIN_TRIM_S:
        return None
    return mask


def condition_from_record(record: FlightRecord, **override: float) -> ReferenceCondition:
    """Reference condition of a record: channel means (SI) and meta.reference geometry.

    V, qbar, alpha and theta are the means over the trim before the record's first listed
    maneuver (``trim_lead``) when it lists them, else over the whole record. The mean
    thrust (N) is taken when the record has a ``thrust`` channel.

    Parameters
    ----------
    record : FlightRecord
        The flight, with channels V (m/s), qbar (Pa), alpha, theta (rad), mass (kg), Ixx,
        Iyy, Izz, Ixz (kg m^2) and ``meta.reference`` (area m^2, span and chord m).
    **override : float
        Any field of ReferenceCondition, in SI units, overriding the record (needed when the
        record lacks a channel, e.g. ``Ixz=0.0`` or ``mass=...`` for a simulation).

    Returns
    -------
    ReferenceCondition
        The reference condition.

    Raises
    ------
    ValueError
        A condition channel or the reference geometry is missing and not overridden, or a
        value is not positive and finite.
    """
    values: dict[str, float] = {}
    for name in CONDITION_CHANNELS:
        if name in override:
            continue
        if name not in record:
            raise ValueError(
                f"record has no channel {name!r} for the reference condition; pass "
                f"{name}=<value in SI units> to condition_from_record"
            )
        values[name] = float(np.mean(record[name]))
    lead = trim_lead(record)
    if lead is not None:
        for name in TRIM_CHANNELS:
            if name in values:
                values[name] = float(np.mean(np.asarray(record[name])[lead]))
    ref = record.meta.reference
    if ref is None and not {"area", "span", "chord"} <= set(override):
        raise ValueError(
            "record has no meta.reference (area, span, chord); set it or pass area=, span=, chord="
        )
    if ref is not None:
        values.update(area=ref.area, span=ref.span, chord=ref.chord)
    if "thrust" in record:
        values["thrust"] = float(np.mean(record["thrust"]))
    values.update(override)
    return ReferenceCondition(**values)


def level_pitch_attitude(record: FlightRecord) -> float:
    """The pitch attitude of unaccelerated flight from the record's mean specific forces.

    theta0 = atan2(ax, -az) (the accelerometers read -g sin(theta), g cos(theta) in steady
    wings-level flight, Morelli & Klein 2016 eq. 10.13).

    Parameters
    ----------
    record : FlightRecord
        The flight, with channels ax and az (m/s^2).

    Returns
    -------
    float
        theta0, rad.

    Raises
    ------
    ValueError
        The record has no ax or az channel.
    """
    missing = [c for c in ("ax", "az") if c not in record]
    if missing:
        raise ValueError(f"record has no channel theta for the reference condition, nor "
                         f"{', '.join(missing)} to take the pitch attitude from")
    return float(np.arctan2(np.mean(record["ax"]), -np.mean(record["az"])))
