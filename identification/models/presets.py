"""The linear model presets by name ('lateral', 'short_period', 'longitudinal').

``MODELS`` maps a preset name to its builder, ``model_for_record`` builds one at a
record's reference condition, and ``RATE_DERIVATIVES`` names the rate derivatives a
preset leaves out that the identification methods estimate.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from flightid.identification.models.linear import LinearModel, lateral
from flightid.identification.models.longitudinal import longitudinal, short_period
from flightid.identification.models.reference_condition import (
    condition_from_record,
    level_pitch_attitude,
)
from flightid.record import FlightRecord

# the rate derivatives a preset leaves out, which the identification methods estimate
# unless the record holds them a priori (``a_priori``): left at zero they are not absent
# from the aircraft but folded into the others. On the Navion (Cm_alphadot -4.36, Teper
# 1969) output error without it put Cm_q at -14.5 for a truth of -9.96 (52 sigma) on
# navion-doublets; on the Twin Otter (CZ_q -20, NASA TM-4099) without CL_q it put CL_de
# 74 % low (6 sigma) on twinotter-21-elevator. Estimated, they come with bounds that
# carry their correlation with Cm_q and CL_alpha (Morelli & Klein 2016 sec. 6.3). Not in
# the short-period model: its alphadot is a combination of its states and input, so
# Cm_alphadot cannot be told from Cm_alpha and Cm_q (twinotter-21-elevator seed 2:
# Cm_alpha withheld as unidentifiable when Cm_alphadot was free).
RATE_DERIVATIVES: dict[str, tuple[str, ...]] = {
    "longitudinal": ("CL_q", "Cm_alphadot"),
}


MODELS: dict[str, Callable[..., LinearModel]] = {
    "lateral": lateral,
    "short_period": short_period,
    "longitudinal": longitudinal,
}


def preset_for_record(preset: str, record: FlightRecord, derivatives: Sequence[str] | None,
                      method: str) -> LinearModel:
    """The named preset at the record's condition, with ``derivatives`` if given.

    Parameters
    ----------
    preset : str
        'lateral', 'short_period' or 'longitudinal'.
    record : FlightRecord
        The flight, SI channels; gives the reference condition.
    derivatives : sequence of str or None
        Derivatives to include; None or empty takes the preset's default.
    method : str
        Name of the method asking, named in the error.

    Returns
    -------
    LinearModel
        The preset at the record's condition.

    Raises
    ------
    ValueError
        ``preset`` is not a preset.
    """
    if preset not in MODELS:
        raise ValueError(f"{method} needs a model preset ({', '.join(MODELS)}), got {preset!r}")
    structure = {"derivatives": tuple(derivatives)} if derivatives else {}
    return model_for_record(preset, record, **structure)


def model_for_record(kind: str, record: FlightRecord, **kwargs) -> LinearModel:
    """Model ``kind`` ('lateral', 'short_period', 'longitudinal') at the record's condition.

    A record without a pitch attitude channel (a hobby recorder) takes the reference pitch
    attitude from the mean specific force, theta0 = atan2(ax, -az) (unaccelerated flight;
    ``level_pitch_attitude``).

    Parameters
    ----------
    kind : str
        Model name, a key of ``MODELS``.
    record : FlightRecord
        The flight, SI channels.
    **kwargs
        Passed to the model builder (``derivatives``, ``start``, ``biases``, ...).

    Returns
    -------
    LinearModel
        The model at the record's reference condition.

    Raises
    ------
    ValueError
        ``kind`` is not a known model.
    """
    if kind not in MODELS:
        raise ValueError(f"unknown model {kind!r}; known: {', '.join(MODELS)}")
    override = {}
    if "theta" not in record:
        override["theta"] = level_pitch_attitude(record)
    return MODELS[kind](condition_from_record(record, **override), **kwargs)
