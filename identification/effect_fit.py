"""Fit an airframe or actuator effect's parameters by flying the augmented JSBSim aircraft.

Output error with JSBSim itself as the model (Jategaonkar 2015, ch. 4; Morelli & Klein
2016, ch. 6): for trial parameter values the catalogue effect is written into a copy of
the aircraft (``sim.augment``), the copy is trimmed at the record's flight condition and
flown with the record's commanded inputs (``sim.flight.simulation``), and the measured outputs are
compared with the flown ones. The project's maximum-likelihood engine
(``identification.engine``: R concentrated out, damped Gauss-Newton, Cramer-Rao bounds)
does the rest; only the output sensitivities are finite differences of whole flights.

- Steps: a fraction of each parameter's default magnitude |default - neutral| from the
  catalogue (``SMOOTH_STEP``), larger and central for the effects whose outputs have kinks
  in the parameter (rate limit, deadband, backlash: ``KINK_STEP``, so the difference sees
  the kink and not one side of it). At a range limit the difference is one-sided.
- Range: trial values outside a parameter's allowed range are flown at the nearest
  allowed value (a lag of -0.01 s is flown as 0), so the fit can end on the limit.
- Cache: every augmented XML is written once per parameter value (``augment_cached``)
  and every flight is kept by its parameter values, so a Newton step's accepted trial is
  not flown again for its sensitivities.
- ``EffectFit.likelihood_ratio``: 2 (J(neutral) - J(fit)), the likelihood-ratio statistic
  of "the effect is absent" (chi-square with one degree of freedom per free parameter,
  Wilks; for a parameter on a range limit the chi-square(1) quantile is conservative).
  It says whether the record shows an effect where a one-sided parameter (a rate limit no
  input reaches, a deadband of width 0) has no usable standard error.

Inputs: the flight core maps surface increments through the aircraft's own actuator, so
``controls`` are the *commanded* increments (rad, throttle fraction) at the record's
times; without them the measured surfaces' increments are used, which is right only
when the effect does not act on the measured surfaces and the aircraft's actuator is fast.
"""

from __future__ import annotations

import dataclasses
import math
import tempfile
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flightid.channels import CONTROLS, LATERAL_INPUTS
from flightid.identification.engine.gauss_newton import maximum_likelihood
from flightid.identification.engine.likelihood import (
    concentrated_cost,
    information_matrix,
    noise_covariance,
)
from flightid.identification.engine.results import estimate_from_fit
from flightid.identification.estimate import Estimate
from flightid.record import FlightRecord
from flightid.sim.augment import augment_cached
from flightid.sim.effects.airframe import AugmentEffect
from flightid.sim.effects.catalogue import CATALOGUE, Parameter
from flightid.sim.flight import simulation as flight
from flightid.sim.jsbsim.model import Model, load
from flightid.sim.jsbsim.trim import Trim, trim

METHOD = "effect_fit"
CACHE = Path(tempfile.gettempdir()) / "flightid-effect-fit"
SMOOTH_STEP = 0.05  # finite-difference step, fraction of the default magnitude
KINK_STEP = 0.1  # the same for effects with kinks (central differences across them)
KINKED = ("rate_limit", "deadband", "backlash")
OFFSET = "offset_"  # a control's constant offset, fitted with the effect (rad, fraction)
OFFSET_STEP = 1e-4  # its finite-difference step (rad: 0.006 deg)
LONGITUDINAL = ("V", "alpha", "q", "theta", "de")
LATERAL = ("beta", "p", "r", "phi", "da", "dr")


@dataclass
class EffectFit:
    """A fitted effect: values and standard errors in the catalogue's units (SI).

    ``names`` are the effect's free parameters; ``values`` and ``std`` hold them and the
    fitted input offsets (``offset_de``, ...). ``effect`` is the effect at the fitted
    values; ``estimate`` the engine's ``Estimate``
    (fit statistics, fitted outputs); ``cost`` and ``neutral_cost`` the ML cost
    N/2 ln det R at the fit and with the effect at its neutral value; ``flights`` how many
    JSBSim flights the fit took; ``at_limit`` the parameters that ended on a range limit.
    """

    effect: AugmentEffect
    names: list[str]
    values: dict[str, float]
    std: dict[str, float]
    estimate: Estimate
    cost: float
    neutral_cost: float
    flights: int
    at_limit: list[str]

    @property
    def likelihood_ratio(self) -> float:
        """2 (J(neutral) - J(fit)): chi-square(len(names)) when the effect is absent."""
        return 2.0 * (self.neutral_cost - self.cost)


def default_outputs(effect: AugmentEffect) -> tuple[str, ...]:
    """The outputs compared: lateral for an aileron or rudder effect, else longitudinal.

    Parameters
    ----------
    effect : AugmentEffect
        The catalogue effect; its ``surface`` option (default "de") decides the axis.

    Returns
    -------
    tuple of str
        The record channels compared (``LATERAL`` or ``LONGITUDINAL``).
    """
    surface = effect.options().get("surface", "de")
    return LATERAL if surface in LATERAL_INPUTS else LONGITUDINAL


def parameter_scale(p: Parameter) -> float:
    """The size of a parameter's effect: |default - neutral|, or |default| for an
    infinite neutral value (a rate limit) or a shape parameter.

    Parameters
    ----------
    p : Parameter
        A catalogue parameter.

    Returns
    -------
    float
        The scale, in the parameter's unit; 1.0 when that size is zero.
    """
    if p.neutral is None or math.isinf(p.neutral):
        return abs(p.default) or 1.0
    return abs(p.default - p.neutral) or 1.0


def _limits(p: Parameter) -> tuple[float, float]:
    low = p.low
    if p.low_open and math.isfinite(low):
        low = low + 1e-3 * parameter_scale(p)
    return low, p.high


class _Flights:
    """The augmented aircraft flown at parameter values, each flight kept."""

    def __init__(self, record: FlightRecord, aircraft: str, effect: AugmentEffect,
                 names: Sequence[str], outputs: Sequence[str],
                 controls: Mapping[str, np.ndarray], cache: Path, surfaces: str,
                 flight_rate_hz: float, offsets: Sequence[str],
                 condition: tuple[float, float] | None,
                 initial: Callable[[Trim], Trim] | None = None,
                 base: tuple[AugmentEffect, ...] = ()) -> None:
        self.aircraft, self.effect = aircraft, effect
        self.initial, self.base = initial, base
        self.names = list(names) + [OFFSET + c for c in offsets]
        self.outputs, self.cache, self.surfaces = list(outputs), cache, surfaces
        self.n = record.time.size
        self.rate = 1.0 / record.uniform_step(METHOD, min_samples=10)
        # flown at a whole multiple of the record rate, the inputs interpolated linearly
        self.oversample = max(1, math.ceil(flight_rate_hz / self.rate - 1e-9))
        fine = np.arange((self.n - 1) * self.oversample + 1) / self.oversample
        self.controls = {c: np.interp(fine, np.arange(self.n), u) for c, u in controls.items()}
        c = dict(record.meta.condition or {})
        if condition is not None:
            c["altitude_m"], c["speed_m_s"] = condition
        missing = [k for k in ("altitude_m", "speed_m_s") if k not in c]
        if missing:
            raise ValueError(f"{METHOD}: the record's metadata lacks the flight condition "
                             f"({', '.join(missing)}); it is needed to trim the model")
        self.condition = (float(c["altitude_m"]), float(c["speed_m_s"]),
                          float(c.get("gamma_rad", 0.0)), float(c.get("bank_rad", 0.0)),
                          float(c.get("flaps_rad", 0.0)))
        entry = CATALOGUE.of(effect)
        self.params = {n: entry.parameter(n) for n in names}
        self.params.update({OFFSET + c: _offset_parameter(c) for c in offsets})
        self.memo: dict[tuple[float, ...], np.ndarray] = {}
        self.trimmed: dict[tuple[float, ...], tuple[Model, Trim]] = {}

    def clip(self, values: Mapping[str, float]) -> tuple[float, ...]:
        out = []
        for n in self.names:
            low, high = _limits(self.params[n])
            out.append(float(min(max(values[n], low), high)))
        return tuple(out)

    def fly(self, values: Mapping[str, float]) -> np.ndarray:
        """Outputs (N, ny) of the aircraft with the effect at ``values`` (clipped to range)."""
        key = self.clip(values)
        if key not in self.memo:
            named = dict(zip(self.names, key, strict=True))
            own = {n: v for n, v in named.items() if not n.startswith(OFFSET)}
            model, trimmed = self.trim(own)
            controls = {c: u + named.get(OFFSET + c, 0.0) for c, u in self.controls.items()}
            rec = flight.fly(model, trimmed, controls, duration_s=(self.n - 1) / self.rate,
                             rate_hz=self.rate * self.oversample, surfaces=self.surfaces)
            self.memo[key] = np.column_stack([rec[c][:: self.oversample][: self.n]
                                              for c in self.outputs])
        return self.memo[key]

    def trim(self, own: Mapping[str, float]) -> tuple[Model, Trim]:
        """The aircraft with the effect at ``own`` values, trimmed at the record's condition."""
        key = tuple(own.values())
        if key not in self.trimmed:
            e = dataclasses.replace(self.effect, **own)
            model = load(str(augment_cached(self.aircraft, [*self.base, e], self.cache,
                                            surface_drive=self.surfaces == "driven")))
            trimmed = trim(model, *self.condition)
            self.trimmed[key] = model, (self.initial(trimmed) if self.initial else trimmed)
        return self.trimmed[key]

    def step(self, name: str) -> float:
        p = self.params[name]
        if name.startswith(OFFSET):
            return OFFSET_STEP
        return (KINK_STEP if self.effect.name in KINKED else SMOOTH_STEP) * parameter_scale(p)

    def sensitivities(self, values: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray]:
        """Outputs and their central (one-sided at a limit) finite-difference sensitivities."""
        y = self.fly(values)
        base = dict(zip(self.names, self.clip(values), strict=True))
        sens = np.zeros((*y.shape, len(self.names)))
        for k, n in enumerate(self.names):
            h = self.step(n)
            low, high = _limits(self.params[n])
            up, down = min(base[n] + h, high), max(base[n] - h, low)
            if up == down:
                continue
            sens[:, :, k] = (self.fly({**base, n: up}) - self.fly({**base, n: down})) / (up - down)
        return y, sens


def _offset_parameter(control: str) -> Parameter:
    return Parameter(OFFSET + control, "rad" if control != "throttle" else "fraction",
                     f"constant offset of the {control} input from the model's trim", 0.0)


def commanded_from_record(record: FlightRecord) -> dict[str, np.ndarray]:
    """The measured surfaces' and throttle's increments on their first sample.

    A stand-in for the commanded inputs when they are not known (see the module note).

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.

    Returns
    -------
    dict of str to numpy.ndarray
        Per control the record holds, its increment per sample (rad; throttle as a fraction);
        shape (n,).
    """
    return {c: record[c] - record[c][0] for c in CONTROLS if c in record}


def fit_effect(record: FlightRecord, aircraft: str, effect: AugmentEffect,
               free: Sequence[str] | None = None, *,
               controls: Mapping[str, np.ndarray] | None = None,
               outputs: Sequence[str] | None = None, start: Mapping[str, float] | None = None,
               max_iterations: int = 12, colored: bool = False,
               cache: str | Path | None = None, surfaces: str = "commanded",
               flight_rate_hz: float = 0.0, offsets: Sequence[str] = (),
               condition: tuple[float, float] | None = None,
               initial: Callable[[Trim], Trim] | None = None,
               base: Sequence[AugmentEffect] = ()) -> EffectFit:
    """Fit ``effect``'s ``free`` parameters (default: all that size it) to ``record``.

    The effect is written into the aircraft and flown in JSBSim; the parameters are fitted by
    output-error maximum likelihood.

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels.
    aircraft : str
        The model the effect is added to (a name or an XML path).
    effect : AugmentEffect
        The catalogue effect, its options (surface, derivative) fixed and its other
        parameters held at their values.
    free : sequence of str, optional
        The parameters fitted. Default: all that size the effect.
    controls : mapping of str to numpy.ndarray, optional
        Commanded increments at the record's times (rad; throttle a fraction), shape (n,).
        Default ``commanded_from_record``.
    outputs : sequence of str, optional
        The record channels compared. Default ``default_outputs``.
    start : mapping of str to float, optional
        The first values. Default: the effect's own.
    max_iterations : int, optional
        Iterations of the maximum-likelihood fit. Default 12.
    colored : bool, optional
        Bounds corrected for colored residuals (M&K eq. 6.54). Default False.
    cache : str or Path, optional
        Folder for the written aircraft. Default the module's cache folder.
    surfaces : str, optional
        "commanded" (``controls`` pass the aircraft's actuator) or "driven" (they are surface
        positions written past it: right for a record's measured surfaces, which have passed
        the real actuator). Default "commanded".
    flight_rate_hz : float, optional
        Fly at the smallest whole multiple of the record rate at least this fast, Hz, the
        inputs interpolated linearly between the record's samples (a held 20 Hz surface lags
        its record by half a sample). Default 0 (the record rate).
    offsets : sequence of str, optional
        Controls whose constant offset from the model's trim is fitted with the effect
        (nuisance parameters ``offset_<control>`` in ``values`` and ``std``): a record's trim
        surface is known only to its noise and quantization, and a constant surface error of
        0.005 deg drifts the speed of a 30 s record enough to bias the fit.
    condition : tuple of float, optional
        (altitude m, airspeed m/s) to trim at, instead of the record metadata's.
    initial : callable, optional
        Maps the trim to the flight's start state (e.g. a window's measured sideslip, bank and
        rates, ``gap.jsbsim.refly.start_state``). Default: the trim itself.
    base : sequence of AugmentEffect, optional
        Effects written into the aircraft with ``effect`` and held as they are (other named
        corrections, an even term removed).

    Returns
    -------
    EffectFit
        The fitted values and standard errors (catalogue units, SI), the costs with and
        without the effect, the flights taken and the parameters at a range limit.

    Raises
    ------
    ValueError
        When ``effect`` is not a catalogue augment effect, a free parameter, output channel or
        offset control is unknown, or a control's shape differs from the record's.
    """
    if not isinstance(effect, AugmentEffect):
        raise ValueError(f"{METHOD}: {type(effect).__name__} is not an airframe or actuator "
                         "effect of the catalogue (those are written into the aircraft)")
    entry = CATALOGUE.of(effect)
    names = list(free) if free is not None else [p.name for p in entry.parameters if p.sizes]
    unknown = [n for n in names if n not in effect.parameters()]
    if unknown or not names:
        raise ValueError(f"{METHOD}: {effect.name} has no parameter(s) {', '.join(unknown)}; "
                         f"free parameters are among {', '.join(effect.parameters())}")
    outputs = list(outputs or default_outputs(effect))
    missing = [c for c in outputs if c not in record]
    if missing:
        raise ValueError(f"{METHOD}: the record lacks output channel(s) {', '.join(missing)}")
    n = record.time.size
    controls = dict(controls) if controls is not None else commanded_from_record(record)
    for c, u in controls.items():
        if np.asarray(u).shape != (n,):
            raise ValueError(f"{METHOD}: control {c!r} has shape {np.shape(u)}; the record "
                             f"has {n} samples")
    unknown = [c for c in offsets if c not in controls]
    if unknown:
        raise ValueError(f"{METHOD}: offset of {', '.join(unknown)} asked for, but the "
                         f"controls are {', '.join(controls) or 'none'}")
    flights = _Flights(record, aircraft, effect, names, outputs, controls,
                       Path(cache) if cache else CACHE, surfaces, flight_rate_hz, offsets,
                       condition, initial, tuple(base))
    all_names = flights.names  # the effect's parameters, then the offsets
    z = np.column_stack([record[c] for c in outputs])
    floor = np.maximum(1e-12 * np.var(z, axis=0), 1e-16)
    own_values = effect.parameters()
    values = {nm: float((start or {}).get(nm, own_values.get(nm, 0.0))) for nm in all_names}
    ml = maximum_likelihood(z, floor, flights.sensitivities, flights.fly, all_names, values,
                            max_iterations, False, step_tol=0.2, cost_tol=0.05)
    fitted = dict(zip(all_names, flights.clip(ml.values), strict=True))
    y, sens = flights.sensitivities(fitted)  # at the clipped values (kept flights)
    ml.values, ml.y, ml.sens, ml.residuals = fitted, y, sens, z - y
    ml.noise = noise_covariance(z - y, False, floor)
    ml.information = information_matrix(sens, np.linalg.inv(ml.noise))
    blind = np.diag(ml.information) == 0  # the effect is invisible there (no bound)
    ml.information[blind, blind] = 1.0
    est = estimate_from_fit(ml, method=METHOD, model=f"{aircraft} + {effect.name}",
                            time=record.time, measured=z, output_names=outputs, fixed={},
                            unidentifiable={}, colored=colored, full_noise_covariance=False)
    # "the effect absent": its parameters neutral, the offsets where the fit put them
    neutral = {**fitted, **{nm: entry.parameter(nm).zero for nm in names}}
    neutral_cost = concentrated_cost(z - flights.fly(neutral), False, floor)
    cost = concentrated_cost(z - y, False, floor)
    at_limit = [nm for nm in all_names if fitted[nm] in _limits(flights.params[nm])]
    std = {nm: math.inf if blind[k] else float(s)
           for k, (nm, s) in enumerate(zip(all_names, est.std, strict=True))}
    own = {nm: fitted[nm] for nm in names}
    return EffectFit(dataclasses.replace(effect, **own), names, fitted, std, est, cost,
                     neutral_cost, len(flights.memo), at_limit)
