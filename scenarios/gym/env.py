"""``ExcitationEnv``: a gymnasium environment for excitation-policy research.

An episode starts at a trim and lets a policy move the elevator, aileron and rudder
(normalised commands, Box(-1, 1, (3,)) = (de, da, dr), 0 at trim) at the decision rate;
the observation is ``OBS_CHANNELS`` in SI units plus the sensor suite's white noise. The
reward is the gain in information about the target derivatives (D-optimality; Morelli &
Klein 2016, ch. 9) gathered inside the linear range of the regression, with termination
when the flight leaves a safe envelope (``LIMITS``). ``record()`` flies the episode again
from its actions and gives it as a measured FlightRecord, so that any identification
method (``flightid.identify``) runs on it. The per-decision work after the flight core's
read is one compiled call (``kernels.decide``).

Spaces, rewards (``valid-information``, ``information``, ``accuracy``), the ``info`` keys,
termination and measured throughput: docs/gym.md. Every option and reset argument is
checked before anything changes; a bad one raises a ValueError naming it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces

from flightid.record import FlightRecord
from flightid.scenarios.cards import Card, augmented_aircraft, load_card, sub_seed
from flightid.scenarios.gym.information import Information, regression_designs
from flightid.scenarios.gym.kernels import decide, pack
from flightid.scenarios.gym.options import (
    ACCURACY_SCALE,
    CONTROLS,
    LIGHT,
    LIMITS,
    LINEAR_RANGE,
    MAX_DECISIONS,
    MAX_RATE_HZ,
    OBS_BOUNDS,
    OBS_CHANNELS,
    OBS_SCALES,
    OBSERVATIONS,
    PENALTY,
    REWARDS,
    SIGMA,
    TURBULENCE,
    check_condition,
    check_one_of,
    check_positive,
    check_targets,
)
from flightid.scenarios.gym.render import render_episode
from flightid.sim.effects.catalogue import CATALOGUE
from flightid.sim.effects.sensor import WhiteNoise
from flightid.sim.flight.simulation import Atmosphere, DepartureError, Simulation
from flightid.sim.jsbsim.condition import FlightCondition
from flightid.sim.jsbsim.model import Model, load
from flightid.sim.jsbsim.trim import Trim, trim
from flightid.sim.jsbsim.truth import derivatives
from flightid.sim.sensors.builtin import SUITES, builtin_suite
from flightid.sim.sensors.suites import SensorSuite, measure
from flightid.units import G0

_CACHE: dict[tuple, tuple[Model, Trim, dict[str, float]]] = {}


def _setup(aircraft: str, condition: FlightCondition) -> tuple[Model, Trim, dict[str, float]]:
    """(model, trim, body-axis truth derivatives), cached per aircraft and condition."""
    key = (aircraft, condition)
    if key not in _CACHE:
        model = load(aircraft)
        trimmed = trim(model, condition)
        _CACHE[key] = (model, trimmed, dict(derivatives(model, trimmed, axes="body").values))
    return _CACHE[key]


def _noise_sigma(suite: SensorSuite | None, channel: str) -> float:
    if suite is None or channel not in suite.channels:
        return 0.0
    return float(sum(e.sigma for e in suite.channels[channel] if isinstance(e, WhiteNoise)))


class ExcitationEnv(gymnasium.Env):
    """Excite an aircraft for identification; see the module docstring for the spaces,
    reward and termination."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}

    def __init__(self, aircraft: str = "navion", condition: Sequence[float] | None = None,
                 card: str | Card | None = None, targets: str | Sequence[str] = "lateral",
                 episode_s: float = 20.0, decision_hz: float = 50.0, sim_hz: float | None = None,
                 sensors: str = "research", turbulence: str = "none",
                 effects: Sequence[Mapping[str, Any]] = (),
                 penalty: float = PENALTY, reward: str = "valid-information",
                 observation: str = "si", render_mode: str | None = None) -> None:
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        check_one_of("turbulence", turbulence, TURBULENCE)
        check_one_of("reward", reward, REWARDS)
        self.reward = reward
        check_one_of("observation", observation, OBSERVATIONS)
        self.observation = observation
        if isinstance(effects, (str, Mapping)) or not isinstance(effects, Sequence) or not all(
                isinstance(d, Mapping) for d in effects):
            raise ValueError("effects must be a list of effect tables (dicts), e.g. "
                             "[{'name': 'rate_limit', 'surface': 'de', 'rate_deg': 20}]; "
                             f"got {effects!r}")
        self.episode_s = check_positive("episode_s", episode_s)
        self.decision_hz = check_positive("decision_hz", decision_hz, MAX_RATE_HZ)
        sim_hz = (self.decision_hz if sim_hz is None
                  else check_positive("sim_hz", sim_hz, MAX_RATE_HZ))
        self.sim_per_decision = int(round(sim_hz / self.decision_hz))
        if self.sim_per_decision < 1 or abs(self.sim_per_decision * self.decision_hz
                                            - sim_hz) > 1e-9:
            raise ValueError(f"sim_hz {sim_hz} must be an integer multiple of decision_hz "
                             f"{self.decision_hz}")
        self.n_decisions = int(round(self.episode_s * self.decision_hz))
        if not 1 <= self.n_decisions <= MAX_DECISIONS:
            raise ValueError(f"episode_s * decision_hz = {self.episode_s:g} s x "
                             f"{self.decision_hz:g} Hz = {self.n_decisions} decisions; it must "
                             f"be 1 to {MAX_DECISIONS:,} (an episode's noise is drawn at reset)")
        self.penalty = check_positive("penalty", penalty, zero=True)
        suite: SensorSuite | None
        augmentation = tuple(CATALOGUE.from_dict(d, "effect", f"effects[{i}]")
                             for i, d in enumerate(effects))
        if card is not None:
            if not isinstance(card, (str, Card)):
                raise ValueError(f"card must be a card name, a path or a Card, got {card!r}")
            c = card if isinstance(card, Card) else load_card(card)
            aircraft, cond, suite = c.aircraft, c.condition, c.sensors
            augmentation = (*c.augmentation, *augmentation)
        else:
            if not isinstance(aircraft, str) or not aircraft:
                raise ValueError(f"aircraft must be an aircraft name, got {aircraft!r}")
            cond = check_condition(condition)
            check_one_of("sensors", sensors, ("none", *SUITES))
            suite = None if sensors in ("none", "ideal") else builtin_suite(sensors)
        self.render_mode = render_mode
        self.aircraft, self.condition, self.suite = aircraft, cond, suite
        self.effects = augmentation  # airframe and actuator effects flown (and in the truth)
        self.targets = check_targets(targets)
        flown = augmented_aircraft(aircraft, augmentation) if augmentation else aircraft
        model, self.trim, self.truth = _setup(flown, cond)
        self._atmosphere = Atmosphere(**LIGHT) if turbulence == "light" else Atmosphere()
        self.sim = Simulation(model, rate_hz=sim_hz, atmosphere=self._atmosphere)
        self.reference = self.sim.model.reference
        at_trim = self.sim.reset(self.trim)  # and the command maps: each surface's travel
        tp = {"de": self.trim.elevator, "da": self.trim.aileron, "dr": self.trim.rudder}
        self._span: list[tuple[float, float]] = []
        for c in CONTROLS:
            low, high = self.sim.travel(c) or (tp[c], tp[c])
            self._span.append((tp[c] - low, high - tp[c]))  # (down, up) travel
        # targets -> regression groups
        groups: dict[str, list[str]] = {}
        for name in self.targets:
            coef, _, var = name.partition("_")
            groups.setdefault(coef, []).append(var)
        self._group_spec = [(c, tuple(v)) for c, v in groups.items()]
        width = max(len(v) for v in groups.values())
        design, designs = regression_designs(self._group_spec)  # coefficient -> its design
        coefs = [c for c, _ in self._group_spec]
        self._coefs = coefs
        # what a step reads from the flight core: the observed channels, then the
        # coefficients; with the time in front (+ noise) it is the measured vector, whose
        # first len(OBS_CHANNELS) entries are the observation and the rest y
        self._read = (*OBS_CHANNELS[1:], *coefs)
        self._at = {c: 1 + i for i, c in enumerate(self._read)}
        self._n_obs = len(OBS_CHANNELS)
        self._sigma_y = np.array([SIGMA[c] for c in coefs])
        # target i -> (design, slot) of its variance in M^-1, (coefficient, slot) of its
        # estimate (slot 0 is the bias)
        where = [(coefs.index(n.partition("_")[0]),
                  1 + groups[n.partition("_")[0]].index(n.partition("_")[2]))
                 for n in self.targets]
        self._places = np.array([(design[g], j, g) for g, j in where])
        self._est_at = tuple(np.array(where).T)
        # regressor slots of each design: (measured entry, scaling at V = 1 m/s, scaling
        # over V): 1 for angles and surfaces, b/2 or c/2 over V for the rates (phat, qhat,
        # rhat); a padding slot reads the time with scaling 0
        span, chord = self.reference.span, self.reference.chord
        half = {"p": span / 2, "q": chord / 2, "r": span / 2}
        self._slots = [[(self._at[v], float(v not in half), half.get(v, 0.0)) for v in vs]
                       + [(0, 0.0, 0.0)] * (width - len(vs)) for vs, _ in designs]
        at = self._at
        self._i_alpha, self._i_phi, self._i_az, self._i_v, self._i_h = (
            at[c] - 1 for c in ("alpha", "phi", "az", "V", "h"))
        # the linear range: (truth entry, 1 / range in SI), the trim values set at reset
        lr = LINEAR_RANGE
        self._range = [(at[c] - 1, 1.0 / math.radians(lr[k])) for c, k in (
            ("alpha", "alpha_deg"), ("beta", "beta_deg"), ("p", "p_deg_s"), ("q", "q_deg_s"),
            ("r", "r_deg_s"))]
        self._range.append((self._i_v, 1.0 / (lr["speed_ratio"] * self.trim.speed_m_s)))
        self._slot_idx = np.array([[i for i, _, _ in row] for row in self._slots],
                                  dtype=np.int64)
        self._range_idx = np.array([i for i, _ in self._range], dtype=np.int64)
        self._truth_vec = [self.truth.get(n, math.nan) for n in self.targets]
        self._truth = np.array(self._truth_vec)
        if reward == "accuracy" and not all(math.isfinite(t) and t != 0.0
                                            for t in self._truth_vec):
            raise ValueError("reward 'accuracy' needs a finite, nonzero truth for every target "
                             "(its error is relative); targets has " + ", ".join(
                                 f"{n} = {t:g}"
                                 for n, t in zip(self.targets, self._truth_vec, strict=True)
                                 if not (math.isfinite(t) and t != 0.0)))
        self._sigma_obs = np.array([0.0] + [_noise_sigma(suite, c) for c in OBS_CHANNELS[1:]])
        self.action_space = spaces.Box(-1.0, 1.0, (3,), dtype=np.float32)
        high = np.array([self.episode_s + 1.0, *OBS_BOUNDS.values()])
        low = np.array([0.0, *(-b for b in OBS_BOUNDS.values())])
        low[OBS_CHANNELS.index("V")] = 0.0
        derived = {"t": self.episode_s, "V": LINEAR_RANGE["speed_ratio"] * self.trim.speed_m_s,
                   **{c: max(s) for c, s in zip(CONTROLS, self._span, strict=True)}}
        self.obs_scale = np.array([OBS_SCALES[c] or derived[c] for c in OBS_CHANNELS])
        self.obs_center = np.array([0.0, *(at_trim[c] for c in OBS_CHANNELS[1:])])
        self._scaled = observation == "scaled"
        if self._scaled:
            low, high = (low - self.obs_center) / self.obs_scale, (high - self.obs_center) / (
                self.obs_scale)
        self.observation_space = spaces.Box(low, high, dtype=np.float64)
        self._replay: Simulation | None = None  # flies the episode again for record()
        self._n_sim = 0
        self._obs_hist: list[np.ndarray] = []
        self._seed = 0

    # -- gymnasium ------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[np.ndarray, dict[str, Any]]:
        # checked before any state changes: a refused reset leaves the environment as it was
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer))
                                 or seed < 0):
            raise ValueError(f"reset: seed must be None or an integer >= 0; got {seed!r}")
        if options is not None and (not isinstance(options, Mapping) or options):
            raise ValueError(f"reset: options takes no keys (None or {{}}); got {options!r}")
        super().reset(seed=None if seed is None else int(seed))
        self._seed = int(self.np_random.integers(2**31))
        if self._atmosphere.turbulence != "none":
            self.sim.atmosphere = replace(self._atmosphere, seed=sub_seed(self._seed, "jsbsim"))
        sample = self.sim.reset(self.trim)
        self._advance = self.sim.stepper(self._read)
        self._info_state = Information(self._group_spec)
        n = self.n_decisions + 1
        obs_noise = self._sigma_obs * self.np_random.standard_normal((n, self._n_obs))
        y_noise = self._sigma_y * self.np_random.standard_normal((n, len(self._coefs)))
        # measured = [t, *read] + noise - (0 for the observation, y at trim for y)
        self._y0 = np.array([sample[c] for c in self._coefs])
        self._noise = np.hstack([obs_noise, y_noise - self._y0])
        self._logdet = 0.0
        self._score = 0.0  # the return so far before penalties
        self._k = 0
        self._h0 = sample["h"]
        trim_measured = [0.0, *(sample[c] for c in self._read)]
        # each slot as (entry, trim value, scaling, scaling over V)
        slot_par = np.array([[(trim_measured[i], f, pv) for i, f, pv in row]
                             for row in self._slots])
        self._values = [sample[c] for c in self._read]
        range_par = np.array([(self._values[i], inv) for i, inv in self._range])
        inf = self._info_state
        m = len(trim_measured)
        self._layout, self._par = pack(
            inf.design, self._slot_idx, self._range_idx, self._places, inf.w, inf.count,
            inf.w_coef, slot_par, range_par, m, self._at["V"], self._n_obs,
            self.reward == "valid-information")
        nt = len(self.targets)
        # the compiled step's output: measured, crb, estimate, weight, log det
        self._crb_slice, self._est_slice = slice(m, m + nt), slice(m + nt, m + 2 * nt)
        self._out_size = m + 2 * nt + 2
        self._weight = 1.0
        self._out: np.ndarray | None = None
        obs = np.add(self._noise[0][:self._n_obs], trim_measured[:self._n_obs])
        self._obs_hist = [obs]
        if self._scaled:
            obs = (obs - self.obs_center) / self.obs_scale
        self._actions = [[0.0, 0.0, 0.0]]
        self._n_sim = 0
        return obs, self._info(None)

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        values = np.asarray(action, dtype=float).tolist()
        if not isinstance(values, list) or len(values) != len(CONTROLS) or any(
                v != v for v in values):
            raise ValueError(f"action must be {len(CONTROLS)} numbers (de, da, dr) in [-1, 1], "
                             f"not NaN; got {action!r}")
        a = [(v if v < 1.0 else 1.0) if v > -1.0 else -1.0 for v in values]
        inc = [ai * (up if ai > 0 else down) for ai, (down, up) in zip(a, self._span, strict=True)]
        self._k += 1
        departure = None
        try:
            for _ in range(self.sim_per_decision):
                self._values = self._advance(inc)
                self._n_sim += 1
        except DepartureError as exc:
            departure = exc.reason
        values = self._values
        self._actions.append(a)
        k = self._k
        # (past the episode's end, as a caller may step on, the last noise row repeats)
        noise = self._noise[min(k, self.n_decisions)]
        reward = 0.0
        if departure is None:
            out = np.empty(self._out_size)
            decide(np.array(values), noise, k / self.decision_hz, self._layout, self._par,
                   self._info_state.state, out)
            self._weight, self._logdet = float(out[-2]), float(out[-1])
            self._out = out
            obs = out[:self._n_obs]
            score = self._accuracy() if self.reward == "accuracy" else self._logdet
            reward = score - self._score
            self._score = score
            departure = self._envelope(values)
        else:  # the values of the last interval flown
            self._out = None
            obs = np.add((k / self.decision_hz, *values[:self._n_obs - 1]),
                         noise[:self._n_obs])
        self._obs_hist.append(obs)
        if self._scaled:
            obs = (obs - self.obs_center) / self.obs_scale
        terminated = departure is not None
        if terminated:
            # "valid-information", "accuracy": a flight that left the envelope delivers no
            # data, so what it gathered is forfeit with the penalty (it returns -penalty)
            reward -= self.penalty + (self._score if self.reward != "information" else 0.0)
        truncated = not terminated and k >= self.n_decisions
        return obs, float(reward), terminated, truncated, self._info(departure)

    def render(self) -> np.ndarray | None:
        if self.render_mode != "rgb_array":
            return None
        return render_episode(np.array(self._obs_hist), np.array(self._actions), self.aircraft,
                              self._logdet)

    # -- the episode as a record ------------------------------------------------------
    def record(self, measured: bool = True) -> FlightRecord:
        """The episode so far: the truth through the sensor suite (``measured``) or the
        truth itself, at the simulation rate, with the truth derivatives in its metadata.

        A step reads only what it observes; the record is the episode flown again from
        its actions (JSBSim restarts bit-identically: the same flight, every channel).
        """
        n = self._n_sim
        if n == 0:
            raise ValueError("record(): the episode has no flown interval yet (no step since "
                             "reset, or it departed within its first)")
        if self._replay is None:
            self._replay = Simulation(self.sim.model, rate_hz=self.sim.rate_hz,
                                      atmosphere=self.sim.atmosphere)
        self._replay.atmosphere = self.sim.atmosphere
        # each decision's increments (the clipped actions on the travel), held over its
        # record intervals: the same products the steps took
        a = np.array(self._actions[1:])
        down, up = np.array(self._span).T
        decided = a * np.where(a > 0, up, down)
        inc = np.zeros((n + 1, len(CONTROLS)))
        inc[1:] = np.repeat(decided, self.sim_per_decision, axis=0)[:n]
        scenario = {"name": "gym:flightid/Excitation-v0", "seed": self._seed}
        try:
            truth = self._replay.fly(self.trim, dict(zip(CONTROLS, inc.T, strict=True)),
                                     n / self.sim.rate_hz, scenario=scenario)
        except DepartureError as exc:  # every interval flown had passed the checks
            raise RuntimeError(f"record(): the episode flown again departed ({exc}) where "
                               "the stepped one did not; JSBSim did not restart "
                               "bit-identically") from exc
        last = [float(truth[c][-1]) for c in self._read]
        if not all(a == b or (a != a and b != b) for a, b in zip(last, self._values,
                                                                   strict=True)):
            raise RuntimeError("record(): the episode flown again ends elsewhere than the "
                               "stepped one; JSBSim did not restart bit-identically")
        meta = truth.meta
        meta.extra["truth"] = {"trim": self.trim.condition, "body": dict(self.truth)}
        if self.effects:
            meta.extra["injected"] = {"aircraft": self.aircraft, "augmented": self.sim.model.name,
                                      "effects": [e.to_dict() for e in self.effects]}
        if not measured or self.suite is None:
            return truth
        return measure(truth, self.suite, sub_seed(self._seed, "sensors"))

    # -- internals ------------------------------------------------------------------------
    def _envelope(self, values: Sequence[float]) -> str | None:
        """Why the truth ``values`` (the flight core's, in ``self._read`` order) left the
        safe envelope ``LIMITS``, or None."""
        lim = LIMITS
        alpha = math.degrees(values[self._i_alpha])
        if not lim["alpha_deg"][0] <= alpha <= lim["alpha_deg"][1]:
            return f"alpha {alpha:.1f} deg outside {lim['alpha_deg']}"
        bank = math.degrees(values[self._i_phi])
        if abs(bank) > lim["bank_deg"]:
            return f"bank {bank:.1f} deg beyond {lim['bank_deg']}"
        n = -values[self._i_az] / G0
        if not lim["load_factor"][0] <= n <= lim["load_factor"][1]:
            return f"load factor {n:.2f} outside {lim['load_factor']}"
        speed = values[self._i_v]
        ratio = speed / self.trim.speed_m_s
        if not lim["speed_ratio"][0] <= ratio <= lim["speed_ratio"][1]:
            return f"airspeed {speed:.1f} m/s outside {lim['speed_ratio']} x trim"
        loss = self._h0 - values[self._i_h]
        if loss > lim["altitude_loss_m"]:
            return f"altitude loss {loss:.0f} m > {lim['altitude_loss_m']} m"
        return None

    def _accuracy(self) -> float:
        """ACCURACY_SCALE x (1 - the mean over the targets of min(|estimate - truth| /
        |truth|, 1)): 0 for the prior's estimate (0), ACCURACY_SCALE for the truth."""
        est = self._info_state.theta[self._est_at]
        rel = np.minimum(np.abs(est - self._truth) / np.abs(self._truth), 1.0)
        return float(ACCURACY_SCALE * (1.0 - np.mean(rel)))

    def _info(self, departure: str | None) -> dict[str, Any]:
        inf = self._info_state
        # S^-1 is the derivative block of M^-1 (the bias a nuisance parameter)
        # (rounding could make a variance that is 0 in exact arithmetic slightly negative)
        if self._out is None:  # at reset, or after a step that departed
            g, j = self._est_at
            crb = np.sqrt(np.maximum(inf.inv[self._places[:, 0], j, j], 0.0))
            est = inf.theta[g, j]
        else:
            crb, est = self._out[self._crb_slice], self._out[self._est_slice]
        info: dict[str, Any] = {"crb": crb, "estimate": est,
                                "error": est - self._truth, "logdet": self._logdet,
                                "time": self._k / self.decision_hz,
                                "validity": self._weight}
        if departure is not None:
            info["departure"] = departure
        return info

