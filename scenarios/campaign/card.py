"""Campaign cards: a test-point matrix flown with one flight card's maneuvers.

A campaign card is a TOML file (lengths m, speeds m/s, angles rad or degrees with
``_deg``): the flight card flown at every point, the method and model, the seed, the
report's x axis, the fit's start, ``[[point]]`` tables and/or a ``[matrix]``,
``[[held_out]]`` points, optional ``[[maneuver]]`` and ``[[effect]]`` tables; the fields
are described in docs/campaign.md ("The campaign card").

``load_campaign(path) -> Campaign`` validates everything; a ``CardError`` names the file,
the line and the field. ``point_card(campaign, point)`` is the flight card of one point.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import tomllib
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from flightid.identification.methods import registry
from flightid.identification.methods.nonlinear_6dof.estimation import aerodynamic_parameters
from flightid.scenarios.cards import Card, CardError, card_from_dict, find_card, load_card
from flightid.scenarios.toml_locate import line_index, line_of
from flightid.units import DEG

TOP_FIELDS = ("name", "description", "source", "card", "method", "model", "seed", "x",
              "start", "options", "point", "matrix", "held_out", "maneuver", "effect")
POINT_FIELDS = ("altitude", "speed", "flaps", "flaps_deg", "mass", "cg_x")
X_CHOICES = ("speed", "altitude", "alpha", "flaps", "mass", "cg_x")
START_CHOICES = ("method", "model", "neighbour")
# the methods a point's fit can start from the model's derivatives (start = "model"):
# (model, options) -> the parameters their start mapping takes
MODEL_START = {"oe6dof": aerodynamic_parameters}


@dataclass(frozen=True)
class TestPoint:
    """One test condition: altitude (m), true airspeed (m/s), flaps (rad), mass scale (1)
    and CG shift forward (m)."""

    altitude: float
    speed: float
    flaps: float = 0.0
    mass: float = 1.0
    cg_x: float = 0.0

    def as_dict(self) -> dict[str, float]:
        """The condition as plain floats (the columns of the estimates table)."""
        return asdict(self)


@dataclass(frozen=True)
class Campaign:
    """A validated campaign card: the points, the held-out points, the flight card's data
    with the campaign's maneuvers and effects, and the identification."""

    name: str
    path: str
    card_data: dict[str, Any] = field(hash=False)
    points: tuple[TestPoint, ...]
    held_out: tuple[TestPoint, ...] = ()
    method: str = "oe6dof"
    model: str = "6dof"
    options: dict[str, Any] = field(default_factory=dict, hash=False)
    seed: int = 1
    x: str = "speed"
    description: str = ""
    start: str = "method"  # START_CHOICES: where each point's fit starts

    @property
    def n(self) -> int:
        """The number of test points (the executors' and the store's size)."""
        return len(self.points)

    @property
    def aircraft(self) -> str:
        """The model aircraft (the flight card's, without the campaign's effects)."""
        return str(self.card_data["aircraft"])

    def identity(self) -> dict[str, Any]:
        """What makes two campaigns the same (a stored campaign continues only under it)."""
        text = json.dumps({"card": self.card_data, "points": [p.as_dict() for p in self.points],
                           "method": self.method, "model": self.model,
                           "options": self.options, "seed": self.seed,
                           **({"start": self.start} if self.start != "method" else {})},
                          sort_keys=True, default=str)
        return {"card": self.path, "card_sha256": hashlib.sha256(text.encode()).hexdigest()}

    def as_dict(self) -> dict[str, Any]:
        """The description as plain data (campaign.json)."""
        return {"name": self.name, "card": self.path, "n": self.n, "method": self.method,
                "model": self.model, "options": self.options, "seed": self.seed, "x": self.x,
                "start": self.start,
                "points": [p.as_dict() for p in self.points],
                "held_out": [p.as_dict() for p in self.held_out]}


def _fail(path: str, index: dict, where: tuple, message: str) -> CardError:
    name = ".".join(f"[{p}]" if isinstance(p, int) else str(p) for p in where)
    name = name.replace(".[", "[")
    return CardError(path, line_of(index, where) if index else None, name, message)


def _number(value: Any, path: str, index: dict, where: tuple, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise _fail(path, index, where, f"must be a number, got {value!r}")
    if positive and not value > 0:
        raise _fail(path, index, where, f"must be > 0, got {value!r}")
    return float(value)


def _point(d: Any, path: str, index: dict, where: tuple) -> TestPoint:
    if not isinstance(d, dict):
        raise _fail(path, index, where, "must be a table with altitude and speed")
    for key in d:
        if key not in POINT_FIELDS:
            raise _fail(path, index, (*where, key),
                        f"unknown field; allowed: {', '.join(POINT_FIELDS)}")
    for key in ("altitude", "speed"):
        if key not in d:
            raise _fail(path, index, where, f"field {key!r} is required")
    if "flaps" in d and "flaps_deg" in d:
        raise _fail(path, index, (*where, "flaps_deg"), "given twice (flaps and flaps_deg)")
    altitude = _number(d["altitude"], path, index, (*where, "altitude"))
    if altitude < 0:
        raise _fail(path, index, (*where, "altitude"), f"must be >= 0 m, got {altitude}")
    flaps = (_number(d["flaps_deg"], path, index, (*where, "flaps_deg")) * DEG
             if "flaps_deg" in d else _number(d.get("flaps", 0.0), path, index,
                                              (*where, "flaps")))
    return TestPoint(altitude, _number(d["speed"], path, index, (*where, "speed"), True),
                     flaps, _number(d.get("mass", 1.0), path, index, (*where, "mass"), True),
                     _number(d.get("cg_x", 0.0), path, index, (*where, "cg_x")))


def _matrix(d: Any, path: str, index: dict) -> list[TestPoint]:
    if not isinstance(d, dict):
        raise _fail(path, index, ("matrix",), "must be a table of lists")
    lists = {}
    for key, values in d.items():
        if key not in POINT_FIELDS:
            raise _fail(path, index, ("matrix", key),
                        f"unknown field; allowed: {', '.join(POINT_FIELDS)}")
        if not isinstance(values, list) or not values:
            raise _fail(path, index, ("matrix", key), f"must be a non-empty list, got {values!r}")
        lists[key] = values
    keys = list(lists)
    out = []
    for combo in itertools.product(*lists.values()):
        out.append(_point(dict(zip(keys, combo, strict=True)), path, index, ("matrix",)))
    return out


def campaign_from_dict(data: dict[str, Any], path: str = "<campaign>",
                       text: str | None = None) -> Campaign:
    """A Campaign from a parsed card; CardError names the file, line and field.

    Parameters
    ----------
    data : dict[str, Any]
        The parsed TOML card.
    path : str, optional
        File name used in errors.
    text : str or None, optional
        The card's text, for line numbers in errors; None gives none.

    Returns
    -------
    Campaign
        The validated campaign.
    """
    index = line_index(text) if text else {}
    for key in data:
        if key not in TOP_FIELDS:
            raise _fail(path, index, (key,), f"unknown field; allowed: {', '.join(TOP_FIELDS)}")
    if "card" not in data or not isinstance(data["card"], str):
        raise _fail(path, index, ("card",), "is required: the flight card flown at every point")
    base = _base_card(data["card"], path, index)
    points = [_point(d, path, index, ("point", i))
              for i, d in enumerate(_list(data, "point", path, index))]
    if "matrix" in data:
        points += _matrix(data["matrix"], path, index)
    if not points:
        raise _fail(path, index, ("point",), "no test point: give [[point]] tables or a [matrix]")
    held = tuple(_point(d, path, index, ("held_out", i))
                 for i, d in enumerate(_list(data, "held_out", path, index)))
    method = data.get("method", "oe6dof")
    model = data.get("model", "6dof")
    options = data.get("options", {})
    try:
        spec = registry.get(method)
        model = registry.check_model(method, model)
        if not isinstance(options, dict):
            raise ValueError(f"must be a table of method options, got {options!r}")
        spec.make_options(options)
    except ValueError as exc:
        raise _fail(path, index, ("method",), str(exc)) from None
    seed = data.get("seed", base.seed)
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**32:
        raise _fail(path, index, ("seed",), f"must be a whole number 0..2**32-1, got {seed!r}")
    x = data.get("x", "speed")
    if x not in X_CHOICES:
        raise _fail(path, index, ("x",), f"must be one of {', '.join(X_CHOICES)}, got {x!r}")
    start = data.get("start", "method")
    if start not in START_CHOICES:
        raise _fail(path, index, ("start",),
                    f"must be one of {', '.join(START_CHOICES)}, got {start!r}")
    if start != "method" and method not in MODEL_START:
        raise _fail(path, index, ("start",),
                    f"{start!r} needs a method that takes start values "
                    f"({', '.join(MODEL_START)}), not {method}")
    if start != "method" and "start" in options:
        raise _fail(path, index, ("start",), f"{start!r} and the option start both set the "
                                              "start values: give one")
    card_data = dict(base.data)
    card_data.pop("a_priori", None)
    if "maneuver" in data:
        card_data["maneuver"] = data["maneuver"]
    if "effect" in data:
        card_data["effect"] = [*card_data.get("effect", []), *data["effect"]]
    name = data.get("name", Path(path).stem if path != "<campaign>" else "campaign")
    campaign = Campaign(name=str(name), path=str(path), card_data=card_data,
                        points=tuple(points), held_out=held, method=method, model=model,
                        options=dict(options), seed=int(seed), x=x,
                        description=str(data.get("description", "")), start=str(start))
    for i, p in enumerate(points):  # every point's card must be a valid card
        point_card(campaign, p, f"{path} (point {i})")
    return campaign


def _list(data: dict, key: str, path: str, index: dict) -> list:
    items = data.get(key, [])
    if not isinstance(items, list):
        raise _fail(path, index, (key,), f"must be an array of tables ([[{key}]])")
    return items


def _base_card(name: str, path: str, index: dict) -> Card:
    beside = Path(path).parent / name
    try:
        return load_card(beside if beside.is_file() else find_card(name))
    except CardError as exc:
        raise _fail(path, index, ("card",), f"{name!r}: {exc}") from None


def point_card(campaign: Campaign, point: TestPoint, where: str | None = None,
               with_effects: bool = True) -> Card:
    """The flight card of one test point: the campaign's flight card at the point's
    condition, its mass and CG as ``mass_scale``/``cg_offset`` effects; ``with_effects``
    False leaves out the campaign's other effects (the model aircraft).

    Parameters
    ----------
    campaign : Campaign
        The campaign.
    point : TestPoint
        The test point.
    where : str or None, optional
        Source named in card errors; None names the campaign's file.
    with_effects : bool, optional
        Keep the campaign's effects. Default True.

    Returns
    -------
    Card
        The point's flight card.
    """
    data = json.loads(json.dumps(campaign.card_data))
    condition = {k: v for k, v in data.get("condition", {}).items()
                 if k not in ("altitude", "speed", "flaps", "flaps_deg")}
    data["condition"] = {**condition, "altitude": point.altitude, "speed": point.speed,
                         "flaps": point.flaps}
    effects = list(data.get("effect", [])) if with_effects else []
    if point.mass != 1.0:
        effects.append({"name": "mass_scale", "factor": point.mass})
    if point.cg_x != 0.0:
        effects.append({"name": "cg_offset", "x": point.cg_x})
    data.pop("effect", None)
    if effects:
        data["effect"] = effects
    data["name"] = f"{campaign.name}-{point.altitude:g}m-{point.speed:g}mps"
    return card_from_dict(data, where or f"{campaign.path} (a test point)")


def load_campaign(path: str | Path) -> Campaign:
    """Read and validate a campaign card (a path, or a library name under
    scenarios/library/campaigns/).

    Parameters
    ----------
    path : str or Path
        Campaign card file, or a library campaign name.

    Returns
    -------
    Campaign
        The validated campaign.
    """
    p = Path(path)
    if not p.is_file():
        lib = Path(__file__).resolve().parent.parent / "library" / "campaigns" / f"{p.stem}.toml"
        if str(path) == p.stem and lib.is_file():
            p = lib
        else:
            raise CardError(str(path), None, None, "no such campaign card (a TOML file, or a "
                            "library campaign: " + ", ".join(library_campaigns()) + ")")
    try:
        text = p.read_text(encoding="utf-8")
        data = tomllib.loads(text)
    except (OSError, UnicodeDecodeError) as exc:
        raise CardError(str(p), None, None, f"cannot read the campaign card: {exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise CardError(str(p), None, None, f"TOML syntax error: {exc}") from None
    return campaign_from_dict(data, str(p), text)


def library_campaigns() -> list[str]:
    """The names of the library's campaign cards.

    Returns
    -------
    list[str]
        Campaign names, sorted.
    """
    folder = Path(__file__).resolve().parent.parent / "library" / "campaigns"
    return sorted(p.stem for p in folder.glob("*.toml"))
