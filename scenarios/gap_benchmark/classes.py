"""Equivalence classes: effects the maneuvers cannot tell apart. Naming any member of the
injected effect's class counts as right (docs/gap_benchmark.md lists them; fixed before
the held-out seed is run).

- pitch stiffness: a cg offset along x, a Cm_alpha delta (a CG shift dx moves Cm_alpha by
  CL_alpha dx / cbar and the other pitching-moment terms by a second-order amount; Etkin &
  Reid 1996 ch. 2);
- pitch damping: Cm_q, Cm_alphadot (alpha and q move together in the short period: only
  their sum is identified from such data; Morelli & Klein 2016 ch. 6);
- aileron, rudder, elevator power: the surface's effectiveness factor, the delta of its
  main moment derivative (Cl_da, Cn_dr, Cm_de: the other terms of the surface are small);
  the elevator's is the horizontal-tail effectiveness class, with tail ice and an elevator
  play (seed-9 rules: the held-out cost tells them apart no better than null flights do);
- lag or rate limit of one surface (seed-9 rules): on the card's two maneuvers per surface,
  of one amplitude, both slow the surface's edges; the held-out cost favours the injected
  one in 12 of 19 flights of seeds 0, 7, 8 where both are fitted, the wrong one by 1-280
  where the right one wins by 26-1178 (docs/gap_benchmark.md);
- lag or delay on one channel: 1/(tau s + 1) and exp(-tau s) agree to first order in
  tau s, and at the maneuvers' 0.3-3 rad/s a 0.05 s tau leaves 1 % between them;
- an inertia about one axis and a scaling of every moment term about it: I x = M x
  scales the same way (Ixz coupling aside), so an inertia scale and a group of deltas of
  every Cl (ixx), Cm (iyy) or Cn (izz) term are the same to the data;
- the trim-level classes (``identification.gap.trim_level.CHECKED``): a constant offset
  of a flow angle or a surface against the model's trim at the measured airspeed,
  altitude and weight, and the model's zero term that moves that trim value the same
  way, are one constant to a record at one condition: alpha bias or CL_0 mismatch (a lift
  offset at the measured weight), beta bias or CY_0 / asymmetry, and a rigging bias of
  the elevator, aileron or rudder or a Cm_0, Cl_0 or Cn_0 mismatch. At one condition the
  trim fixes only the total force and moment there: a weight error (``mass_scale``) is a
  lift offset CL_trim = W / (qbar S), so it is in the alpha class; a thrust-line offset
  (``thrust_moment``: arm x the trim thrust) and a CG offset along x (a Cm offset
  CL dx / cbar at trim) are pitching-moment offsets, so they are in the elevator class
  (the CG offset is in the pitch stiffness class too), and so is a tail of effectiveness k
  (an elevator factor, a Cm_de delta, tail ice; seed-13 rules): it trims at de_model / k.
  A deadband of width w around zero (seed-10 rules) passes a command c as c - sign(c) w/2:
  a surface trimmed off zero sits w/2 from its command, a rigging bias at trim, so the
  aileron's and rudder's deadbands are in their surface's class;
- the kinematic class (``trim_level.KINEMATIC``, seed-11 rules): an IMU block pitched by a
  about body y reads a_x = g sin(theta + a) in steady flight, an a_x bias b reads as b / g:
  ax bias or IMU pitch misalignment.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from flightid.identification.gap.candidates.classes import TAIL_CLASS
from flightid.scenarios.gap_benchmark.cases import CHANNELS, Effect


@dataclass(frozen=True)
class Member:
    """A pattern of effects: the catalogue entry, options that must match, the one
    parameter that is sized (an inertia scale's axis), or a group whose every part is a
    derivative delta of a derivative starting with ``group_prefix``."""

    entry: str
    options: dict[str, str] = field(default_factory=dict)
    parameter: str = ""
    group_prefix: str = ""


def _delta(derivative: str) -> Member:
    return Member("derivative_delta", {"derivative": derivative})


CLASSES: dict[str, tuple[Member, ...]] = {
    "pitch stiffness": (_delta("Cm_alpha"), Member("cg_offset")),
    "pitch damping": (_delta("Cm_q"), _delta("Cm_alphadot")),
    "aileron power": (Member("control_effectiveness", {"surface": "da"}), _delta("Cl_da")),
    "rudder power": (Member("control_effectiveness", {"surface": "dr"}), _delta("Cn_dr")),
    TAIL_CLASS: (Member("control_effectiveness", {"surface": "de"}), _delta("Cm_de"),
                 Member("tail_ice"), Member("backlash", {"surface": "de"})),
    **{f"lag or rate limit of {s}": (Member("actuator_lag", {"surface": s}),
                                      Member("rate_limit", {"surface": s}))
       for s in ("da", "dr", "de")},
    **{f"lag or delay on {c}": (Member("delay", {"channel": c}), Member("lag", {"channel": c}))
       for c in dict.fromkeys(c for cs in CHANNELS.values() for c in cs)},
    "roll inertia": (Member("inertia_scale", parameter="ixx"),
                     Member("group", group_prefix="Cl_")),
    "pitch inertia": (Member("inertia_scale", parameter="iyy"),
                      Member("group", group_prefix="Cm_")),
    "yaw inertia": (Member("inertia_scale", parameter="izz"),
                    Member("group", group_prefix="Cn_")),
    "alpha bias or CL_0 mismatch": (Member("bias", {"channel": "alpha"}), _delta("CL_0"),
                                    Member("mass_scale")),
    "beta bias or CY_0 / asymmetry": (Member("bias", {"channel": "beta"}), _delta("CY_0")),
    "elevator bias, Cm_0 mismatch or tail effectiveness": (
        Member("actuator_bias", {"surface": "de"}), _delta("Cm_0"), Member("thrust_moment"),
        Member("cg_offset"), Member("control_effectiveness", {"surface": "de"}),
        _delta("Cm_de"), Member("tail_ice")),
    "aileron bias or Cl_0 mismatch": (Member("actuator_bias", {"surface": "da"}),
                                      _delta("Cl_0"), Member("deadband", {"surface": "da"})),
    "rudder bias or Cn_0 mismatch": (Member("actuator_bias", {"surface": "dr"}),
                                     _delta("Cn_0"), Member("deadband", {"surface": "dr"})),
    "ax bias or IMU pitch misalignment": (Member("misalignment"),
                                          Member("bias", {"channel": "ax"})),
}


def _sized(entry: str, magnitude: dict[str, float]) -> str:
    """The parameter departing most from neutral (1 for scales)."""
    if not magnitude:
        return ""
    return max(magnitude, key=lambda k: abs(magnitude[k] - (1.0 if entry.endswith("scale")
                                                            else 0.0)))


def _value(p: Any) -> float:
    return float(p["value"]) if isinstance(p, dict) else float(p)


def _effect_matches(m: Member, e: Effect) -> bool:
    if m.group_prefix or m.entry != e.entry:
        return False
    if any(e.options.get(k) != v for k, v in m.options.items()):
        return False
    return not m.parameter or _sized(e.entry, e.magnitude) == m.parameter


def _named_matches(m: Member, ranked: Any) -> bool:
    """``ranked``: a Ranked of the diagnosis (``candidate.entry``, ``.options``, ``.parts``,
    ``parameters`` in catalogue units)."""
    c = ranked.candidate
    if m.group_prefix:
        parts = list(c.parts)
        return len(parts) > 1 and all(
            p.entry == "derivative_delta"
            and str(p.options.get("derivative", "")).startswith(m.group_prefix) for p in parts)
    if c.parts or c.entry != m.entry:
        return False
    if any(c.options.get(k) != v for k, v in m.options.items()):
        return False
    if m.parameter:
        params = {k: _value(v) for k, v in (ranked.parameters or {}).items()}
        return not params or _sized(c.entry, params) == m.parameter
    return True


def class_of(effect: Effect) -> str:
    """The name of the injected effect's class; its own label when it has none.

    Parameters
    ----------
    effect : Effect
        The injected effect.

    Returns
    -------
    str
        Class name.
    """
    for name, members in CLASSES.items():
        if any(_effect_matches(m, effect) for m in members):
            return name
    return effect.label.split(" ")[0]


def classes_of(effect: Effect) -> list[str]:
    """The names of every class the injected effect is a member of.

    Parameters
    ----------
    effect : Effect
        The injected effect.

    Returns
    -------
    list[str]
        Class names, in ``CLASSES`` order.
    """
    return [name for name, members in CLASSES.items()
            if any(_effect_matches(m, effect) for m in members)]


def same(effect: Effect, ranked: Any) -> bool:
    """Whether a named effect (a single Ranked of the diagnosis) is ``effect`` itself (its
    entry and options; the axes of a derivative delta aside) or in its class.

    Parameters
    ----------
    effect : Effect
        The injected effect.
    ranked : Any
        A single ``Ranked`` of the diagnosis.

    Returns
    -------
    bool
        True if it names ``effect`` or its class.
    """
    c = ranked.candidate
    if not c.parts and c.entry == effect.entry and all(
            c.options.get(k) == v for k, v in effect.options.items()
            if k != "axes" and k in c.options):
        if effect.entry != "inertia_scale":
            return True
        params = {k: _value(v) for k, v in (ranked.parameters or {}).items()}
        return not params or _sized(c.entry, params) == _sized(effect.entry, effect.magnitude)
    for members in CLASSES.values():
        if any(_effect_matches(m, effect) for m in members):
            if any(_named_matches(m, ranked) for m in members):
                return True
    return False


def exact(effect: Effect, ranked: Any) -> bool:
    """The named effect is the injected entry with its options (so its parameters can be
    compared with the injected magnitude).

    Parameters
    ----------
    effect : Effect
        The injected effect.
    ranked : Any
        A single ``Ranked`` of the diagnosis.

    Returns
    -------
    bool
        True if it is the injected entry with its options.
    """
    c = ranked.candidate
    return (not c.parts and c.entry == effect.entry
            and all(c.options.get(k) == v for k, v in effect.options.items()))
