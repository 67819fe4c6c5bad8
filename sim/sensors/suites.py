"""Sensor suites: from a truth FlightRecord (fast internal rate) to the measured record.

A ``SensorSuite`` maps each measured channel to an ordered list of effects (catalogue
``sensor`` entries, ``flightid.sim.effects.sensor``), plus mounting effects that act on the
whole record before the per-channel chains: ``LeverArm`` (IMU away from the CG), ``Vanes``
(alpha/beta vanes on a boom, with upwash/sidewash) (``flightid.sim.effects.mounting``) and
``EngineVibration`` (``flightid.sim.effects.vibration``). Effect names in suite tables are
resolved through the effect catalogue (``flightid.sim.effects.catalogue.CATALOGUE``).
``measure(truth, suite, seed)`` runs them and resamples every channel to one output rate.
Built-in suites ``hobby`` and ``research`` carry the source of each value in its
``source`` field; ``suite_from_dict`` builds a suite from a card table.

Random streams are independent per channel and per mounting effect (seeded from
``seed`` and the channel name), so adding a channel leaves the others' noise unchanged.
"""

from __future__ import annotations

import dataclasses
import zlib
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from flightid.channels import CHANNELS
from flightid.record import FlightRecord
from flightid.sim.effects.base import Effect
from flightid.sim.effects.catalogue import CATALOGUE, ActsOn, effect_from_dict
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
from flightid.sim.effects.vibration import AXES, EngineVibration
from flightid.units import DEG, EARTH_RADIUS_M, FT, G0

# the mounting list's effects: mounting (lever arm, vanes) and vibration, from the catalogue
MOUNTING: dict[str, type] = CATALOGUE.classes(ActsOn.MOUNTING, ActsOn.VIBRATION)


# -- the suite ---------------------------------------------------------------------


@dataclass
class SensorSuite:
    """Measured channels with their ordered effects, mounting effects and output rate (Hz).

    ``output_rate`` 0 means the highest channel rate; ``passthrough`` channels are copied
    from the truth (e.g. mass properties known from weighing), interpolated to the output.
    """

    name: str = ""
    channels: dict[str, list[Effect]] = field(default_factory=dict)
    mounting: list[Any] = field(default_factory=list)
    output_rate: float = 0.0
    passthrough: tuple[str, ...] = ()
    description: str = ""

    def __post_init__(self) -> None:
        for ch, chain in self.channels.items():
            n = sum(isinstance(e, Sample) for e in chain)
            if n > 1:
                raise ValueError(f"channels.{ch}: {n} 'sample' effects; a channel is sampled once")
        if sum(isinstance(m, EngineVibration) for m in self.mounting) > 1:
            raise ValueError("mounting: at most one engine_vibration effect")
        if self.output_rate < 0:
            raise ValueError(f"field 'output_rate' must be >= 0 Hz, got {self.output_rate}")

    def sample_rate(self, channel: str) -> float | None:
        """The rate (Hz) at which ``channel`` is sampled, None if it is not."""
        for e in self.channels[channel]:
            if isinstance(e, Sample):
                return None if np.isinf(e.rate) else e.rate  # inf: continuous, not sampled
        return None

    def to_dict(self) -> dict[str, Any]:
        """The suite as a plain dict (inverse of ``suite_from_dict``)."""
        return {
            "name": self.name,
            "description": self.description,
            "output_rate": self.output_rate,
            "passthrough": list(self.passthrough),
            "mounting": [m.to_dict() for m in self.mounting],
            "channels": {c: [e.to_dict() for e in chain] for c, chain in self.channels.items()},
        }


def _rng(seed: int, key: str) -> np.random.Generator:
    return np.random.default_rng([int(seed), zlib.crc32(key.encode())])


def run_chain(
    t: np.ndarray, x: np.ndarray, chain: list[Effect], rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Apply ``chain`` in order to ``x`` on times ``t`` (s); returns the final (t, x)."""
    x = np.asarray(x, float)
    for e in chain:
        if isinstance(e, Sample):
            t_new = e.output_time(t)
            x = e.apply(t, x, rng)
            t = t_new
        else:
            x = e.apply(t, x, rng)
    return t, x


def _vibration_grid(t: np.ndarray, rate: float, f_max: float) -> np.ndarray:
    """A uniform grid from t[0] to t[-1] fine enough for lines up to ``f_max`` (Hz).

    At least 10 samples per cycle of the highest line and the truth's own rate, and an
    integer multiple of the sensor ``rate`` so its sample instants fall on the grid.
    """
    fast = (t.size - 1) / (t[-1] - t[0])
    fine = rate * np.ceil(max(10.0 * f_max, fast) / rate - 1e-9)
    n = int(np.floor((t[-1] - t[0]) * fine + 1e-9)) + 1
    return t[0] + np.arange(n) / fine


WRAPPED_ANGLES = ("psi",)  # channels that jump by 2 pi; measured continuous, rewrapped


def measure(truth: FlightRecord, suite: SensorSuite, seed: int = 0) -> FlightRecord:
    """The record as measured by ``suite``: channels in SI at the suite's output rate.

    Mounting effects act on the truth at its fast rate; vibrating IMU channels are
    evaluated on a finer grid (``_vibration_grid``) so that lines above the sensor's
    Nyquist frequency alias correctly. Channels sampled slower than the output rate are
    held (zero-order hold, the latest sample, as a recorder logs it); unsampled channels
    are linearly interpolated. ``meta.extra['measurement']`` records how.
    """
    t = truth.time
    if t.size < 2:
        raise ValueError("measure needs a truth record with at least two samples")
    missing = [c for c in (*suite.channels, *suite.passthrough) if c not in truth]
    if missing:
        raise ValueError(
            f"suite {suite.name!r} measures {', '.join(missing)}, which the truth record "
            f"lacks; it has {', '.join(sorted(truth.channels))}"
        )
    ch = dict(truth.channels)
    vib = None
    for i, m in enumerate(suite.mounting):
        if isinstance(m, EngineVibration):
            vib = m
            continue
        ch.update(m.apply_record(t, ch, _rng(seed, f"mounting:{i}:{m.name}")))
    phases = None
    if vib is not None:
        if "rpm" not in ch:
            raise ValueError(
                f"suite {suite.name!r}: engine_vibration needs the truth channel 'rpm' "
                "(engine speed, 1/min), which the record lacks"
            )
        phases = vib.phases(_rng(seed, "mounting:engine_vibration"))

    fast_rate = (t.size - 1) / (t[-1] - t[0])
    measured: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    rates: dict[str, float] = {}
    for name, chain in suite.channels.items():
        x, tc = ch[name], t
        rate = suite.sample_rate(name)
        if vib is not None and name in AXES and getattr(vib, name) != 0:
            f_max = vib.max_frequency(ch["rpm"])
            tc = _vibration_grid(t, rate or fast_rate, f_max)
            if tc.size != t.size or not np.allclose(tc, t):
                x = np.interp(tc, t, x)
                rpm = np.interp(tc, t, ch["rpm"])
            else:
                rpm = ch["rpm"]
            x = x + vib.signal(tc, rpm, name, phases)
        wrapped = name in WRAPPED_ANGLES
        if wrapped:  # filter the continuous angle, not the jump at +-pi
            x = np.unwrap(x)
        try:
            y = run_chain(tc, x, chain, _rng(seed, f"channel:{name}"))
        except ValueError as exc:
            raise ValueError(f"channel {name!r}: {exc}") from None
        if wrapped:
            tc_out, x_out = y
            y = (tc_out, np.angle(np.exp(1j * x_out)))
        measured[name] = y
        rates[name] = rate if rate is not None else fast_rate

    out_rate = suite.output_rate or max(rates.values(), default=fast_rate)
    n = int(np.floor((t[-1] - t[0]) * out_rate + 1e-9)) + 1
    t_out = t[0] + np.arange(n) / out_rate
    out: dict[str, np.ndarray] = {}
    how: dict[str, str] = {}
    for name, (tc, x) in measured.items():
        if tc.size == t_out.size and np.allclose(tc, t_out, rtol=0, atol=1e-9):
            out[name], how[name] = x, "as sampled"
        elif suite.sample_rate(name) is not None:
            idx = np.searchsorted(tc, t_out + 1e-9, side="right") - 1
            out[name], how[name] = x[np.clip(idx, 0, None)], "zero-order hold of the latest sample"
        else:
            out[name], how[name] = np.interp(t_out, tc, x), "linear interpolation (unsampled)"
    for name in suite.passthrough:
        out[name], how[name] = np.interp(t_out, t, truth[name]), "truth, linear interpolation"

    units = {c: truth.meta.units[c] for c in out if c in truth.meta.units}
    extra = dict(truth.meta.extra)
    extra["measurement"] = {
        "suite": suite.name,
        "seed": int(seed),
        "output_rate_hz": out_rate,
        "channel_rates_hz": rates,
        "resampling": how,
        "definition": suite.to_dict(),
    }
    extra["sensor_positions"] = sensor_positions(suite)
    provenance = f"{truth.meta.provenance}; measured by sensor suite {suite.name!r} seed {seed}"
    meta = dataclasses.replace(
        truth.meta, sample_rate=out_rate, units=units, extra=extra, provenance=provenance
    )
    return FlightRecord(t_out, out, meta)


def sensor_positions(suite: SensorSuite) -> dict[str, list[float]]:
    """Where the suite's sensors sit, as a record's ``meta.extra['sensor_positions']``
    (docs/record.md): ``accelerometers`` [x, y, z] m from the CG in body axes (x forward,
    y right, z down; [0, 0, 0] without a lever arm), and ``alpha_vane`` / ``beta_vane``
    [x, y, z] m when the flow angles come from vanes (absent: the channel is the flow
    angle at the CG)."""
    out: dict[str, list[float]] = {"accelerometers": [0.0, 0.0, 0.0]}
    for m in suite.mounting:
        if isinstance(m, LeverArm):
            out["accelerometers"] = [float(m.x), float(m.y), float(m.z)]
        elif isinstance(m, Vanes):
            out["alpha_vane"] = [float(m.alpha_x), float(m.alpha_y), float(m.alpha_z)]
            out["beta_vane"] = [float(m.beta_x), float(m.beta_y), float(m.beta_z)]
    return out


# -- building suites from dicts --------------------------------------------------------


def mounting_from_dict(d: dict[str, Any], context: str = "") -> Any:
    """Build a mounting effect (lever_arm, vanes, engine_vibration) from a table.

    The name is resolved through the effect catalogue (``SECTIONS['mounting']``).
    """
    return CATALOGUE.from_dict(d, "mounting", context)


def suite_from_dict(d: dict[str, Any]) -> SensorSuite:
    """Build a suite from a table; ``base`` starts from a built-in suite.

    Keys: name, description, base, output_rate (Hz), passthrough (list), mounting (list
    of tables), channels (table of channel -> list of effect tables). With ``base``, a
    listed channel replaces that channel's chain and a given ``mounting`` replaces the
    mounting list. Errors name the field, e.g. ``channels.q[1].sigma``.
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


# -- built-in suites ---------------------------------------------------------------------

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
    """Hobby MEMS IMU and potentiometer vanes, Telemaster / Boomerang class (Sofyan; Monash)."""
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
    """Research instrumentation, Twin Otter / Navion class: 50 Hz, anti-aliased, low noise."""
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
    """Perfect sensors sampled at ``rate`` (Hz): the truth at a recorder's rate."""
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
    """A built-in suite by name (``SUITES``)."""
    try:
        return SUITES[name]()
    except KeyError:
        raise ValueError(
            f"field 'base': unknown suite {name!r}; built-in: {', '.join(SUITES)}"
        ) from None
