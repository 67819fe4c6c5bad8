"""The built-in sensor suites: hobby (a MEMS IMU and potentiometer vanes, Telemaster /
Boomerang class), research (an air-data boom and a navigation-grade IMU behind
anti-alias filters, Twin Otter class) and ideal; each number cites its source.
"""

from __future__ import annotations

from flightid.sim.effects.base import Effect
from flightid.sim.effects.mounting import LeverArm, Vanes
from flightid.sim.effects.sensor import (
    Bias,
    Delay,
    Quantization,
    RandomWalk,
    Sample,
    Saturation,
    SecondOrder,
    WhiteNoise,
)
from flightid.sim.effects.vibration import EngineVibration

# the mounting list's effects: mounting (lever arm, vanes) and vibration, from the catalogue
from flightid.sim.sensors.suites import SensorSuite
from flightid.units import DEG, EARTH_RADIUS_M, FT, G0

# recorded exactly: mass properties (from the weight-and-balance sheet), the throttle
# lever position and the engine-model thrust and propulsive moments (the NASA Twin Otter
# record carries thrust computed from an engine model the same way; per-engine thrust
# times its arm gives the moments). A suite with anti-alias filters sends the propulsion
# channels through them instead (research_suite).
_PROPULSION = ("thrust", "L_prop", "M_prop", "N_prop")
_MASS = ("mass", "Ixx", "Iyy", "Izz", "Ixz", "throttle", *_PROPULSION)
SOFYAN = "Sofyan, RMIT thesis (c. 1997)"
MONASH = "Monash Boomerang 60 paper (c. 2008)"
TOTTER = (
    "estimated from the NASA Twin Otter record totter_f1_017 (50 Hz): std of the residual "
    "from an 11-point cubic Savitzky-Golay fit; an upper bound, the fit leaves some signal"
)
TOTTER_Q = "smallest step of the Twin Otter record totter_f1_017"


def hobby_suite() -> SensorSuite:
    """Hobby MEMS IMU and potentiometer vanes, Telemaster / Boomerang class (Sofyan; Monash).

    Returns
    -------
    SensorSuite
        The suite, with the source of each number.
    """
    imu = Sample(
        rate=100.0,
        source=f"{MONASH}: O-Navi Phoenix IMU, 100 Hz binary on RS-232; "
        "neither publication mentions an anti-alias filter",
    )
    das = Sample(rate=25.0, source=f"{SOFYAN} ch. 6: 8-bit DAS at 25 Hz, no anti-alias filter")
    gyro_range = Saturation(
        limit=600 * DEG,
        source=f"{MONASH}: gyros 600 deg/s; "
        "the paper does not say whether +-600 or a 600 deg/s span; +-600 assumed",
    )
    acc_range = Saturation(
        limit=10 * G0,
        source=f"{MONASH}: accelerometers +-10 g; "
        "first digit not legible in the source; 10 assumed",
    )

    def gyro() -> list[Effect]:
        return [
            Bias(value=0.5 * DEG, source="assumption: hobby gyro null offset 0.5 deg/s"),
            RandomWalk(
                sigma=0.02 * DEG,
                source=f"assumption, order of MEMS rate random walk; "
                f"{MONASH} measured gyro drift but its values are lost",
            ),
            gyro_range,
            imu,
            WhiteNoise(sigma=1.2 * DEG, source=f"{SOFYAN} Table 8-6: rate noise 1.2 deg/s"),
            Quantization(
                resolution=1200 * DEG / 2**16, source="assumption: 16-bit over 1200 deg/s"
            ),
        ]

    def acc() -> list[Effect]:
        return [
            Bias(value=0.02 * G0, source="assumption: MEMS accelerometer offset 0.02 g"),
            acc_range,
            imu,
            WhiteNoise(
                sigma=0.02 * G0, source=f"{SOFYAN} Table 2-1: accelerometer resolution 0.02 g"
            ),
            Quantization(resolution=20 * G0 / 2**16, source="assumption: 16-bit over 20 g"),
        ]

    def vane() -> list[Effect]:
        return [
            SecondOrder(
                wn=108.0, zeta=0.19, source=f"{SOFYAN} App. 2: vane 108 rad/s, damping 0.19"
            ),
            das,
            WhiteNoise(sigma=0.7 * DEG, source=f"{SOFYAN} Table 8-6: alpha, beta noise 0.7 deg"),
            Quantization(
                resolution=0.4 * DEG, source=f"{SOFYAN} Fig. 6-3: vane resolution 0.4 deg"
            ),
        ]

    def surface(sigma_deg: float) -> list[Effect]:
        return [
            das,
            WhiteNoise(sigma=sigma_deg * DEG, source=f"{SOFYAN} Table 8-6: {sigma_deg} deg"),
            Quantization(resolution=0.25 * DEG, source=f"{SOFYAN} Fig. 6-3: servo pot 0.25 deg"),
        ]

    return SensorSuite(
        name="hobby",
        description="hobby MEMS IMU at 100 Hz without anti-alias filter (Monash Boomerang 60 "
        "paper, c. 2008) and an 8-bit 25 Hz DAS with potentiometer vanes and servo pots "
        "(Sofyan, RMIT thesis, c. 1997)",
        channels={
            "p": gyro(),
            "q": gyro(),
            "r": gyro(),
            "ax": acc(),
            "ay": acc(),
            "az": acc(),
            "alpha": vane(),
            "beta": vane(),
            "de": surface(0.2),
            "da": surface(0.2),
            "dr": surface(0.3),
            "V": [
                Delay(tau=0.003, source=f"{SOFYAN} App. 2: pitot tubing delay 3 ms per metre, 1 m"),
                das,
                WhiteNoise(sigma=0.8, source=f"{SOFYAN} ch. 6: airspeed accuracy +-0.8 m/s"),
            ],
            "qbar": [
                das,
                WhiteNoise(
                    sigma=19.0,
                    source="the airspeed sensor's noise as dynamic pressure: "
                    "rho V sigma_V at 20 m/s (assumption, same sensor as V)",
                ),
            ],
            "rpm": [das, Quantization(resolution=100.0, source=f"{SOFYAN} Fig. 6-3: 100 rpm")],
        },
        mounting=[
            LeverArm(
                x=0.05,
                y=0.0,
                z=0.08,
                source=f"assumption: {SOFYAN} says the IMU is "
                f"'not located exactly on the CG'; {MONASH} box under the fuselage",
            ),
            Vanes(
                alpha_x=1.0,
                beta_x=1.0,
                upwash=0.0136,
                sidewash=0.0136,
                source=f"{SOFYAN} App. 2: vanes 1 m ahead of the CG, boom K = 0.0136",
            ),
            EngineVibration(
                ax=2.0,
                ay=2.0,
                az=3.0,
                p=2 * DEG,
                q=2 * DEG,
                r=1 * DEG,
                harmonics=2.0,
                blades=2.0,
                blade_amplitude=0.5,
                source=f"assumption for amplitudes; {SOFYAN} Figs 7-1, 7-2: vibration buried the "
                f"rate gyros unless at idle; {MONASH}: 16,000 rpm glow engine",
            ),
        ],
        output_rate=100.0,
        passthrough=_MASS,
    )


def research_suite() -> SensorSuite:
    """Research instrumentation, Twin Otter / Navion class: 50 Hz, anti-aliased, low noise.

    Returns
    -------
    SensorSuite
        The suite, with the source of each number.
    """
    aa = Sample(
        rate=50.0,
        antialias=10.0,
        order=4.0,
        source="50 Hz as the NASA Twin Otter record; 4-pole Butterworth at 40 % of "
        f"Nyquist (literature rule quoted in {SOFYAN} ch. 2)",
    )

    gps = [
        Sample(rate=5.0, source="assumption: research GPS receiver, 5 Hz"),
        WhiteNoise(sigma=2.5 / EARTH_RADIUS_M, source="assumption: 2.5 m position noise"),
    ]

    def chan(sigma: float, q: float) -> list[Effect]:
        return [
            aa,
            WhiteNoise(sigma=sigma, source=TOTTER),
            Quantization(resolution=q, source=TOTTER_Q),
        ]

    return SensorSuite(
        name="research",
        description="research flight-test instrumentation, Twin Otter class: 50 Hz with "
        "anti-alias filters, noise levels estimated from the NASA Twin Otter record",
        channels={
            "V": chan(0.034 * FT, 0.0),
            "alpha": chan(0.0048 * DEG, 1e-6 * DEG),
            "beta": chan(0.0046 * DEG, 1e-6 * DEG),
            "p": chan(0.033 * DEG, 0.001 * DEG),
            "q": chan(0.0061 * DEG, 0.001 * DEG),
            "r": chan(0.0086 * DEG, 0.001 * DEG),
            "phi": chan(0.0066 * DEG, 0.01 * DEG),
            "theta": chan(0.0044 * DEG, 0.01 * DEG),
            "ax": chan(0.00032 * G0, 0.0001 * G0),
            "ay": chan(0.00075 * G0, 0.0001 * G0),
            "az": chan(0.00075 * G0, 0.0001 * G0),
            "de": chan(0.0048 * DEG, 0.01 * DEG),
            "da": chan(0.030 * DEG, 0.005 * DEG),
            "dr": chan(0.0064 * DEG, 0.01 * DEG),
            "h": chan(0.41 * FT, 0.5 * FT),
            # the airspeed noise as dynamic pressure, rho V sigma_V at 54 m/s (same sensor)
            "qbar": chan(0.7, 0.01),
            # GPS position: the model's local gravity needs the latitude (G0 instead of
            # the local 9.80 m/s^2 at 1890 m biased the Twin Otter's roll derivatives 1 %)
            "latitude": gps,
            "longitude": gps,
            # the engine model's thrust and moments come from engine channels that go through
            # the same anti-alias filters; copied unfiltered they lead the other channels by
            # the filter's 0.04 s and biased the Twin Otter's Cn_beta, Cn_r, Cn_dr by +0.1 to
            # +0.2 % (noise-free 6-DOF fit; 0.01 % with them filtered)
            **{c: [aa] for c in _PROPULSION},
        },
        mounting=[
            LeverArm(x=0.3, y=0.0, z=0.2, source="assumption: IMU near the CG of a Twin Otter"),
            Vanes(
                alpha_x=4.5,
                beta_x=4.5,
                upwash=0.06,
                sidewash=0.10,
                source="Cooper, Drobik & Martin (ARL Flight Mechanics Report 187, 1990): "
                "nose-boom vanes, K_alpha 1.06, K_beta 1.06-1.20; FPR default vane position 4.5 m",
            ),
        ],
        output_rate=50.0,
        passthrough=tuple(c for c in _MASS if c not in _PROPULSION),
    )


def ideal_suite(rate: float = 100.0) -> SensorSuite:
    """Perfect sensors sampled at ``rate``: the truth at a recorder's rate.

    Parameters
    ----------
    rate : float, optional
        Sample and output rate, Hz. Default 100.

    Returns
    -------
    SensorSuite
        The suite.
    """
    names = (
        "V",
        "alpha",
        "beta",
        "p",
        "q",
        "r",
        "phi",
        "theta",
        "psi",
        "ax",
        "ay",
        "az",
        "de",
        "da",
        "dr",
        "h",
        "qbar",
        "latitude",
        "longitude",
    )
    return SensorSuite(
        name="ideal",
        channels={c: [Sample(rate=rate)] for c in names},
        output_rate=rate,
        passthrough=_MASS,
        description="no sensor errors",
    )


SUITES = {"hobby": hobby_suite, "research": research_suite, "ideal": ideal_suite}


def builtin_suite(name: str) -> SensorSuite:
    """A built-in suite by name (``SUITES``).

    Parameters
    ----------
    name : str
        Suite name.

    Returns
    -------
    SensorSuite
        The suite.

    Raises
    ------
    ValueError
        For an unknown name, naming the built-in ones.
    """
    try:
        return SUITES[name]()
    except KeyError:
        raise ValueError(
            f"field 'base': unknown suite {name!r}; built-in: {', '.join(SUITES)}"
        ) from None
