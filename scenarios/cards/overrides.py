"""Command-line overrides of a card (``--set``, ``--turbulence``, ``--sensors``)."""

from __future__ import annotations

import re
import tomllib
from collections.abc import Sequence
from typing import Any

from flightid.scenarios.cards.parse import card_from_dict
from flightid.scenarios.cards.schema import NO_SENSORS, TOP_FIELDS, Card, field_path, plain
from flightid.sim.sensors.builtin import SUITES

TURBULENCE_LEVELS = ("none", "light", "moderate")
# keys of the tables whose fields the card schema fixes (other tables are checked by
# card_from_dict, whose errors list the fields allowed there)
_SCHEMA_KEYS: dict[tuple, tuple[str, ...]] = {
    (): TOP_FIELDS,
    ("condition",): ("altitude", "speed", "gamma", "gamma_deg", "bank", "bank_deg", "flaps",
                     "flaps_deg"),
    ("sensors",): ("suite", "output_rate", "drop", "mounting", "channels", "passthrough",
                   "name", "description"),
}

_LIST_FIELDS = (("sensors", "drop"), ("sensors", "passthrough"))


def _override_value(text: str) -> Any:
    """A --set value as a TOML scalar or array; a bare word stays a string and a
    comma-separated list of them an array (``vanes,lever_arm``)."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        pass
    if "," in text:
        return [_override_value(part.strip()) for part in text.split(",") if part.strip()]
    return text.strip()


def _set_path(data: dict[str, Any], key: str, value: Any) -> None:
    """Set ``value`` at the TOML path ``key`` of ``data`` (tables created as needed)."""
    path = field_path(key)
    if not path or any(p == "" for p in path):
        raise ValueError(f"--set {key}: not a card field path (e.g. condition.speed)")
    node: Any = data
    for depth, part in enumerate(path):
        here = re.sub(r"\.(\d+)", r"[\1]", ".".join(map(str, path[:depth]))) or "the card"
        last = depth == len(path) - 1
        if isinstance(part, int):
            if not isinstance(node, list):
                raise ValueError(f"--set {key}: {here} is not an array")
            if not 0 <= part < len(node):
                raise ValueError(f"--set {key}: {here} has {len(node)} entries "
                                 f"(indices 0 to {len(node) - 1})")
        else:
            if not isinstance(node, dict):
                raise ValueError(f"--set {key}: {here} is not a table")
            allowed = _SCHEMA_KEYS.get(tuple(path[:depth]))
            if allowed is not None and part not in allowed:
                raise ValueError(f"--set {key}: unknown field {part!r} in {here}; valid keys: "
                                 f"{', '.join(allowed)}")
        if last:
            old = node[part] if (isinstance(part, int) or part in node) else None
            if ((isinstance(old, list) or tuple(path) in _LIST_FIELDS)
                    and not isinstance(value, list)):
                value = [value]  # one name where a list is expected: a list of one
            node[part] = value
            return
        if isinstance(part, str) and part not in node:
            if isinstance(path[depth + 1], int):
                raise ValueError(f"--set {key}: the card has no {part} entries to index")
            node[part] = {}
        node = node[part]


def override(card_data: dict[str, Any], assignments: Sequence[str] = (),
             turbulence: str | None = None, sensors: str | None = None) -> dict[str, Any]:
    """A copy of a parsed card with command-line overrides applied.

    Parameters
    ----------
    card_data : dict[str, Any]
        The card as parsed (``Card.data``); not modified.
    assignments : Sequence[str], optional
        ``KEY=VALUE`` strings, KEY a card field by its TOML path (``condition.speed``,
        ``sensors.drop``, ``maneuver[0].amplitude_deg``), VALUE a TOML scalar or array (a
        bare word is a string, ``a,b`` an array of two). Applied after ``turbulence`` and
        ``sensors``.
    turbulence : str or None, optional
        ``none`` removes the card's turbulence, ``light`` or ``moderate`` replaces it by the
        Dryden turbulence of that intensity (other disturbances are kept).
    sensors : str or None, optional
        A built-in suite (``research``, ``hobby``, ``ideal``) replacing the card's whole
        [sensors] table.

    Returns
    -------
    dict[str, Any]
        The changed copy. It still has to pass ``card_from_dict`` (``overridden_card`` does
        both).

    Raises
    ------
    ValueError
        Naming the option and, for an unknown field, the valid keys at that level.
    """
    data = plain(card_data)
    if turbulence is not None:
        if turbulence not in TURBULENCE_LEVELS:
            raise ValueError(f"--turbulence must be one of {', '.join(TURBULENCE_LEVELS)}, "
                             f"got {turbulence!r}")
        kept = [d for d in data.get("disturbance", [])
                if not (isinstance(d, dict) and d.get("kind") == "turbulence")]
        if turbulence != "none":
            kept.append({"kind": "turbulence", "intensity": turbulence})
        data["disturbance"] = kept
        if not kept:
            del data["disturbance"]
    if sensors is not None:
        suites = (*SUITES, NO_SENSORS)
        if sensors not in suites:
            raise ValueError(f"--sensors must be one of {', '.join(suites)}, got {sensors!r}")
        data["sensors"] = {"suite": sensors}
    for assignment in assignments:
        key, sep, text = assignment.partition("=")
        if not sep or not key.strip():
            raise ValueError(f"--set {assignment!r}: expected KEY=VALUE, e.g. condition.speed=60")
        _set_path(data, key.strip(), _override_value(text.strip()))
    return data


def overridden_card(card: Card, assignments: Sequence[str] = (), turbulence: str | None = None,
                    sensors: str | None = None) -> Card:
    """``card`` with ``override``'s changes, validated again by ``card_from_dict`` (every
    card check applies; a CardError names the overridden field). No change: ``card``.

    Parameters
    ----------
    card : Card
        The card.
    assignments : Sequence[str], optional
        ``KEY=VALUE`` overrides, as in :func:`override`.
    turbulence : str or None, optional
        ``none``, ``light`` or ``moderate``, as in :func:`override`.
    sensors : str or None, optional
        A built-in sensor suite, as in :func:`override`.

    Returns
    -------
    Card
        The validated card.
    """
    if not assignments and turbulence is None and sensors is None:
        return card
    data = override(card.data, assignments, turbulence, sensors)
    where = f"{card.path} (with command-line overrides)"
    return card_from_dict(data, where)
