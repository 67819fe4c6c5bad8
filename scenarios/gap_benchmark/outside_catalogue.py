"""Effects the catalogue cannot express: the blind check's test of "unexplained".

Applied to the measured record (``RECORD``):

- ``structural_mode``: a lightly damped structural mode (3-6 Hz, damping 0.02-0.05) excited
  by the surfaces of its axis, seen by the gyros and accelerometers near it:
  H(s) = g w s / (s^2 + 2 zeta w s + w^2) from the surfaces' increments in rad. Lateral:
  from da + dr, added to p (rad/s), 0.3 of it to r, 2 m/s^2 per rad/s of it to ay.
  Longitudinal: from de, added to q, 2 m/s^2 per rad/s of it to az. A step of the surfaces
  rings with an amplitude of about g times the step.
- ``vane_nonlinearity``: a sideslip vane whose calibration is quadratic,
  beta_m = beta + k beta |beta| (k per rad); a linear scale cannot express it.
- ``vane_hysteresis``: a flow-angle vane with play: the reading follows the true angle
  only once it has moved half the ``width`` (rad) past the reading (a backlash operator,
  the vane's pivot friction); the catalogue's backlash acts on a surface, not on a sensor.

Written into the aircraft (``cm_alpha_break``): a pitch break. Above the trim alpha plus
``above`` (rad; drawn 0.3-0.7 deg), the pitching moment gains ``delta`` per rad of alpha
beyond it (drawn 50-80 % of the aircraft's abs(Cm_alpha)),
dCm = delta max(alpha - alpha_b, 0) (a tail that starts to stall: static stability lost
above a kink); below, the aircraft is the plain one, so its trim is unchanged and the
elevator maneuvers cross the kink. An aircraft-level change, flown in JSBSim: no
catalogue derivative delta (constant over alpha) expresses it.
"""

from __future__ import annotations

import hashlib
import json
import math
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from scipy import signal

from flightid.channels import LATERAL_INPUTS, LONGITUDINAL_INPUTS
from flightid.record import FlightRecord
from flightid.sim.augment import augment, publish
from flightid.sim.effects.airframe import DerivativeDelta

STRUCTURE = {"lateral": (LATERAL_INPUTS, {"p": 1.0, "r": 0.3, "ay": 2.0}),
             "longitudinal": (LONGITUDINAL_INPUTS, {"q": 1.0, "az": 2.0})}


def structural_mode(record: FlightRecord, frequency_hz: float, damping: float, gain: float,
                    axis: str = "lateral") -> FlightRecord:
    """``record`` with the mode's response added to the gyros and accelerometers of
    ``axis`` (module note).

    Parameters
    ----------
    record : FlightRecord
        The measured record.
    frequency_hz : float
        The mode's natural frequency, Hz.
    damping : float
        Its damping ratio, 1.
    gain : float
        Gain from the surface increments (rad) to the mode's response.
    axis : str, optional
        ``"lateral"`` or ``"longitudinal"``: which surfaces drive it and which sensors see it.

    Returns
    -------
    FlightRecord
        A copy with the changed channels.
    """
    surfaces, seen = STRUCTURE[axis]
    w = 2 * math.pi * frequency_hz
    u = np.zeros(len(record.time))
    for s in surfaces:
        if s in record:
            u = u + (record[s] - record[s][0])
    _, y, _ = signal.lsim(([gain * w, 0.0], [1.0, 2 * damping * w, w * w]), u, record.time)
    return record.with_channels(**{c: record[c] + k * y for c, k in seen.items() if c in record})


def vane_nonlinearity(record: FlightRecord, k: float, channel: str = "beta") -> FlightRecord:
    """``record`` with ``channel`` (rad) read through beta + k beta |beta|.

    Parameters
    ----------
    record : FlightRecord
        The measured record.
    k : float
        Coefficient of the quadratic term, 1/rad.
    channel : str, optional
        Vane channel. Default ``"beta"``.

    Returns
    -------
    FlightRecord
        A copy with the changed channel.
    """
    b = record[channel]
    return record.with_channels(**{channel: b + k * b * np.abs(b)})


def vane_hysteresis(record: FlightRecord, width: float, channel: str = "alpha") -> FlightRecord:
    """``record`` with ``channel`` (rad) read through a play of full ``width`` (rad).

    Parameters
    ----------
    record : FlightRecord
        The measured record.
    width : float
        Full width of the play, rad.
    channel : str, optional
        Vane channel. Default ``"alpha"``.

    Returns
    -------
    FlightRecord
        A copy with the changed channel.
    """
    x = np.asarray(record[channel], float)
    half = 0.5 * width
    y = np.empty_like(x)
    y[0] = x[0]
    for i in range(1, len(x)):
        y[i] = min(max(y[i - 1], x[i] - half), x[i] + half)
    return record.with_channels(**{channel: y})


RECORD = {"structural_mode": structural_mode, "vane_nonlinearity": vane_nonlinearity,
          "vane_hysteresis": vane_hysteresis}


def cm_alpha_break(aircraft: str, trim_alpha: float, above: float, delta: float,
                   cache: Path) -> str:
    """The XML path of ``aircraft`` with a pitch break (module note) at ``trim_alpha`` +
    ``above`` (rad), ``delta`` per rad beyond it; written once under ``cache``.

    Parameters
    ----------
    aircraft : str
        Aircraft name.
    trim_alpha : float
        Trim angle of attack, rad.
    above : float
        Break point above the trim, rad.
    delta : float
        Change of Cm_alpha beyond the break, 1/rad.
    cache : Path
        Cache folder.

    Returns
    -------
    str
        Path of the aircraft XML.
    """
    key = json.dumps([aircraft, round(trim_alpha, 9), round(above, 9), round(delta, 9)])
    folder = cache / f"cm-break-{hashlib.sha256(key.encode()).hexdigest()[:16]}"
    name = f"{aircraft}-cm-break"
    xml = folder / "aircraft" / name / f"{name}.xml"
    if xml.is_file():
        return str(xml)
    cache.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix="writing-", dir=cache))
    # a Cm_alpha delta written by the augment, then its alpha made max(alpha - alpha_b, 0)
    path = augment(aircraft, [DerivativeDelta(delta=delta, derivative="Cm_alpha",
                                              axes="stability")], tmp, name=name)
    tree = ET.parse(path)
    kinked = 0
    for fn in tree.getroot().iter("function"):
        if not (fn.get("name") or "").startswith("aero/augment/Cm_alpha"):
            continue
        product = fn.find("product")
        for i, el in enumerate(list(product)):
            if el.tag == "property" and (el.text or "").strip() == "aero/alpha-rad":
                product.remove(el)
                product.insert(i, _kink(trim_alpha + above))
                kinked += 1
    if kinked != 1:
        raise RuntimeError(f"cm_alpha_break: found {kinked} alpha terms in the Cm_alpha "
                           f"delta of {aircraft}, expected 1")
    tree.write(path, encoding="utf-8", xml_declaration=True)
    publish(tmp, folder)
    return str(xml)


def _kink(alpha_b: float) -> ET.Element:
    """max(alpha - alpha_b, 0) as a JSBSim function element."""
    mx = ET.Element("max")
    diff = ET.SubElement(mx, "difference")
    ET.SubElement(diff, "property").text = "aero/alpha-rad"
    ET.SubElement(diff, "value").text = repr(float(alpha_b))
    ET.SubElement(mx, "value").text = "0.0"
    return mx
