"""Sensor suites built from a card's tables (``[sensors]``): a built-in ``base`` with its
channels or mounting list replaced, errors naming the field.
"""

from __future__ import annotations

from typing import Any

from flightid.channels import CHANNELS
from flightid.sim.effects.catalogue import CATALOGUE, effect_from_dict

# the mounting list's effects: mounting (lever arm, vanes) and vibration, from the catalogue
from flightid.sim.sensors.builtin import builtin_suite
from flightid.sim.sensors.suites import SensorSuite


def mounting_from_dict(d: dict[str, Any], context: str = "") -> Any:
    """Build a mounting effect (lever_arm, vanes, engine_vibration) from a table.

    The name is resolved through the effect catalogue (``SECTIONS['mounting']``).

    Parameters
    ----------
    d : dict
        The effect table: its name and parameters.
    context : str, optional
        Where the table is, prefixed to field names in messages.

    Returns
    -------
    NamedEffect
        The mounting effect.
    """
    return CATALOGUE.from_dict(d, "mounting", context)


def suite_from_dict(d: dict[str, Any]) -> SensorSuite:
    """Build a suite from a table; ``base`` starts from a built-in suite.

    With ``base``, a listed channel replaces that channel's chain and a given ``mounting``
    replaces the mounting list. Errors name the field, e.g. ``channels.q[1].sigma``.

    Parameters
    ----------
    d : dict
        Keys: name, description, base, output_rate (Hz), passthrough (list), mounting (list
        of tables), channels (table of channel -> list of effect tables).

    Returns
    -------
    SensorSuite
        The suite.

    Raises
    ------
    ValueError
        Naming the field that is wrong.
    """
    if not isinstance(d, dict):
        raise ValueError(f"suite: expected a table, got {type(d).__name__}")
    allowed = {"name", "description", "base", "output_rate", "passthrough", "mounting", "channels"}
    for key in d:
        if key not in allowed:
            raise ValueError(
                f"field {key!r} is not a suite field; allowed: {', '.join(sorted(allowed))}"
            )
    suite = builtin_suite(d["base"]) if "base" in d else SensorSuite()
    channels = dict(suite.channels)
    raw_channels = d.get("channels", {})
    if not isinstance(raw_channels, dict):
        raise ValueError("field 'channels' must be a table of channel -> list of effects")
    for name, chain in raw_channels.items():
        if name not in CHANNELS:
            raise ValueError(f"field 'channels.{name}': {name!r} is not a canonical channel")
        if not isinstance(chain, list):
            raise ValueError(f"field 'channels.{name}' must be a list of effect tables")
        unit = CHANNELS[name].unit
        channels[name] = [
            effect_from_dict(e, f"channels.{name}[{i}]", unit) for i, e in enumerate(chain)
        ]
    mounting = suite.mounting
    if "mounting" in d:
        if not isinstance(d["mounting"], list):
            raise ValueError("field 'mounting' must be a list of effect tables")
        mounting = [mounting_from_dict(m, f"mounting[{i}]") for i, m in enumerate(d["mounting"])]
    rate = d.get("output_rate", suite.output_rate)
    if isinstance(rate, bool) or not isinstance(rate, int | float):
        raise ValueError(f"field 'output_rate' must be a number (Hz), got {rate!r}")
    passthrough = d.get("passthrough", list(suite.passthrough))
    if not isinstance(passthrough, list | tuple) or not all(
        isinstance(c, str) for c in passthrough
    ):
        raise ValueError(
            f"field 'passthrough' must be a list of channel names, got {passthrough!r}"
        )
    return SensorSuite(
        name=d.get("name", suite.name or "custom"),
        channels=channels,
        mounting=mounting,
        output_rate=float(rate),
        passthrough=tuple(passthrough),
        description=d.get("description", suite.description),
    )


