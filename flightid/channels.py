"""Canonical channel names of a flight record, each with its SI unit.

One name per quantity, used by the record, the simulator, the sensor models, the
identification methods and the reports. Body axes (x forward, y right, z down);
angles in rad, rates in rad/s, lengths in m, speeds in m/s, forces in N, masses in kg.
Controls follow the usual flight-mechanics convention (Etkin; Morelli & Klein):
  de > 0  trailing edge down (nose-down pitching moment, Cm_de < 0)
  da > 0  right aileron trailing edge down (left rolling moment, Cl_da < 0)
  dr > 0  trailing edge left (nose-left yawing moment, Cn_dr < 0)
  throttle in [0, 1].
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Channel:
    """One canonical channel: its SI unit and what it measures."""

    name: str
    unit: str
    description: str


_TABLE: tuple[tuple[str, str, str], ...] = (
    # air data and inertial velocities
    ("V", "m/s", "true airspeed"),
    ("alpha", "rad", "angle of attack"),
    ("beta", "rad", "angle of sideslip"),
    ("qbar", "Pa", "dynamic pressure"),
    ("rho", "kg/m^3", "air density"),
    ("p_static", "Pa", "static (ambient) pressure"),
    ("h", "m", "altitude above sea level"),
    ("mach", "-", "Mach number"),
    ("u", "m/s", "body x velocity relative to the air mass"),
    ("v", "m/s", "body y velocity relative to the air mass"),
    ("w", "m/s", "body z velocity relative to the air mass"),
    # attitude and rates
    ("phi", "rad", "roll angle"),
    ("theta", "rad", "pitch angle"),
    ("psi", "rad", "heading angle"),
    ("p", "rad/s", "body roll rate"),
    ("q", "rad/s", "body pitch rate"),
    ("r", "rad/s", "body yaw rate"),
    ("pdot", "rad/s^2", "body roll acceleration"),
    ("qdot", "rad/s^2", "body pitch acceleration"),
    ("rdot", "rad/s^2", "body yaw acceleration"),
    # specific force at the CG (what an ideal accelerometer at the CG reads)
    ("ax", "m/s^2", "body x specific force at the CG"),
    ("ay", "m/s^2", "body y specific force at the CG"),
    ("az", "m/s^2", "body z specific force at the CG"),
    # position
    ("latitude", "rad", "geodetic latitude"),
    ("longitude", "rad", "longitude"),
    ("north", "m", "north position from the start"),
    ("east", "m", "east position from the start"),
    # controls and propulsion
    ("de", "rad", "elevator deflection, trailing edge down positive"),
    ("da", "rad", "aileron deflection, right aileron trailing edge down positive"),
    ("dr", "rad", "rudder deflection, trailing edge left positive"),
    ("df", "rad", "flap deflection"),
    ("throttle", "-", "throttle position, 0 to 1"),
    ("thrust", "N", "total propulsive thrust along body x"),
    ("L_prop", "N m", "rolling moment of the propulsion about the CG (engine model)"),
    ("M_prop", "N m", "pitching moment of the propulsion about the CG (engine model)"),
    ("N_prop", "N m", "yawing moment of the propulsion about the CG (engine model)"),
    ("rpm", "1/min", "engine or propeller rotation speed"),
    # mass properties
    ("mass", "kg", "aircraft mass"),
    ("Ixx", "kg*m^2", "roll moment of inertia"),
    ("Iyy", "kg*m^2", "pitch moment of inertia"),
    ("Izz", "kg*m^2", "yaw moment of inertia"),
    ("Ixz", "kg*m^2", "roll-yaw product of inertia (positive as in Etkin)"),
    # nondimensional coefficients and rates (body axes, about the CG)
    ("CX", "-", "body x force coefficient"),
    ("CY", "-", "body y force coefficient"),
    ("CZ", "-", "body z force coefficient"),
    ("Cl", "-", "rolling moment coefficient about the CG"),
    ("Cm", "-", "pitching moment coefficient about the CG"),
    ("Cn", "-", "yawing moment coefficient about the CG"),
    ("CL", "-", "lift coefficient (stability axes)"),
    ("CD", "-", "drag coefficient (stability axes)"),
    ("phat", "-", "nondimensional roll rate p b / 2V"),
    ("qhat", "-", "nondimensional pitch rate q cbar / 2V"),
    ("rhat", "-", "nondimensional yaw rate r b / 2V"),
    # atmosphere
    ("wind_north", "m/s", "wind velocity, north component"),
    ("wind_east", "m/s", "wind velocity, east component"),
    ("wind_down", "m/s", "wind velocity, down component"),
    ("turb_u", "m/s", "turbulence velocity, body x"),
    ("turb_v", "m/s", "turbulence velocity, body y"),
    ("turb_w", "m/s", "turbulence velocity, body z"),
)

CHANNELS: dict[str, Channel] = {n: Channel(n, u, d) for n, u, d in _TABLE}

CONTROLS: tuple[str, ...] = ("de", "da", "dr", "throttle")
# the surfaces of each axis: elevator; aileron and rudder
LONGITUDINAL_INPUTS: tuple[str, ...] = ("de",)
LATERAL_INPUTS: tuple[str, ...] = ("da", "dr")
# the control surfaces: elevator, aileron, rudder
CONTROL_SURFACES: tuple[str, ...] = (*LONGITUDINAL_INPUTS, *LATERAL_INPUTS)


def unit_of(name: str) -> str:
    """SI unit of a canonical channel.

    Parameters
    ----------
    name : str
        Canonical channel name.

    Returns
    -------
    str
        The channel's SI unit.

    Raises
    ------
    KeyError
        Naming the channel if it is not canonical.
    """
    try:
        return CHANNELS[name].unit
    except KeyError:
        raise KeyError(
            f"unknown channel {name!r}; canonical channels are listed in flightid/channels.py"
        ) from None
