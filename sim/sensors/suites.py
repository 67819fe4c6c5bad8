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

from flightid.record import FlightRecord
from flightid.sim.effects.base import Effect
from flightid.sim.effects.catalogue import CATALOGUE, ActsOn
from flightid.sim.effects.mounting import LeverArm, Vanes
from flightid.sim.effects.sensor import (
    Sample,
)
from flightid.sim.effects.vibration import AXES, EngineVibration

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
    """Apply ``chain`` in order to ``x`` on times ``t``.

    Parameters
    ----------
    t : numpy.ndarray
        Sample times, s.
    x : numpy.ndarray
        Channel values, SI; same shape as ``t``.
    chain : list of Effect
        The effects, in order; a Sample effect changes the time grid.
    rng : numpy.random.Generator
        Random source.

    Returns
    -------
    tuple of numpy.ndarray
        The final (t, x): times (s) and values (SI).
    """
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

    Mounting effects act on the truth at its fast rate; with an engine vibration every
    channel is evaluated on a finer grid (``_vibration_grid``) so that lines above the
    sensor's Nyquist frequency alias correctly and every channel's filters act alike (the
    IMU channels on the fine grid and the air data on the truth's would differ by the
    discrete filters' delays). Channels sampled slower than the output rate are
    held (zero-order hold, the latest sample, as a recorder logs it); unsampled channels
    are linearly interpolated. ``meta.extra['measurement']`` records how.

    Parameters
    ----------
    truth : FlightRecord
        The true flight, SI channels, at least two samples.
    suite : SensorSuite
        The sensors.
    seed : int, optional
        Random seed. Default 0.

    Returns
    -------
    FlightRecord
        The measured record.

    Raises
    ------
    ValueError
        When the truth lacks a channel the suite measures.
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
        if vib is not None:  # every channel on the fine grid: its filters act alike on all
            f_max = vib.max_frequency(ch["rpm"])
            tc = _vibration_grid(t, rate or fast_rate, f_max)
            fine = tc.size != t.size or not np.allclose(tc, t)
            if fine:
                x = np.interp(tc, t, x)
            if name in AXES and getattr(vib, name) != 0:
                rpm = np.interp(tc, t, ch["rpm"]) if fine else ch["rpm"]
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
    """Where the suite's sensors sit, as a record's ``meta.extra['sensor_positions']``.

    See docs/record.md.

    Parameters
    ----------
    suite : SensorSuite
        The sensors.

    Returns
    -------
    dict of str to list of float
        ``accelerometers`` [x, y, z] m from the CG in body axes (x forward, y right, z down;
        [0, 0, 0] without a lever arm), and ``alpha_vane`` / ``beta_vane`` [x, y, z] m when
        the flow angles come from vanes (absent: the channel is the flow angle at the CG).
    """
    out: dict[str, list[float]] = {"accelerometers": [0.0, 0.0, 0.0]}
    for m in suite.mounting:
        if isinstance(m, LeverArm):
            out["accelerometers"] = [float(m.x), float(m.y), float(m.z)]
        elif isinstance(m, Vanes):
            out["alpha_vane"] = [float(m.alpha_x), float(m.alpha_y), float(m.alpha_z)]
            out["beta_vane"] = [float(m.beta_x), float(m.beta_y), float(m.beta_z)]
    return out
