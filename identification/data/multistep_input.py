"""A measured multistep input as parameters: plateau levels and sub-sample edge times.

A doublet, 2-1-1, 3211 or pulse reaches the surface through the servo in a few
milliseconds; a 25 Hz recorder (the hobby suite, after Sofyan, RMIT thesis, c. 1997,
ch. 6) sees each step as one or two samples. The record alone puts the step on the 40 ms
grid, and the roll and pitch derivatives of a light aircraft move by 1-1.5 % per ms of
input timing (Telemaster card, noise-free: linear interpolation of the exact 25 Hz
surface samples reads Cl_da +9.6 %, Cm_alpha +4.4 %; +1.7 %, +2.2 % at 100 Hz). Here the
input is a sum of steps,

    u(t) = a_0 + sum_k (a_{k+1} - a_k) H(t - t_k),

with the levels a_k (input unit) and the edge times t_k (s: the time of the ideal step
with the area of the real transition) as parameters, sampled so that the hold of the
discrete model ('foh': linear interpolation, 'zoh': held over the sample) has each step's
area at its edge:

    h_k(t_i) = clip((t_i - t_k)/dt + c, 0, 1),  c = 1/2 ('foh'), 1 ('zoh'):

one sample per step lies between the two levels, and the model sees the zeroth and first
moments of every step exactly (noise-free Telemaster card, area-equivalent edges:
Cl_da +2.9 %, Cm_alpha +2.3 %, the 100 Hz level). Output error
(``output_error.estimate(..., multistep_inputs=...)``) estimates the levels and edges
together with the aerodynamic derivatives, the measured surface joining the outputs: the
errors-in-variables treatment of a multistep input, in which the surface noise and the
timing of the steps enter the bounds instead of biasing the derivatives.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flightid.identification.compatibility.reconstruction import white_noise_std
from flightid.identification.data.input_denoising import DEFAULT_WEIGHT, STEP_SIGNIFICANCE, runs

HOLD_OFFSET = {"foh": 0.5, "zoh": 1.0}


@dataclass(frozen=True)
class MultistepParameters:
    """A piecewise-constant input: ``levels`` (input unit, one more than the edges) and
    ``edges`` (s, increasing)."""

    levels: tuple[float, ...]
    edges: tuple[float, ...]

    def __post_init__(self) -> None:
        if len(self.levels) != len(self.edges) + 1:
            raise ValueError(f"a multistep has one level more than edges: {len(self.levels)} "
                             f"levels, {len(self.edges)} edges")

    def parameter_names(self, channel: str) -> list[str]:
        """Names of the levels and edges as estimated parameters of ``channel``."""
        return ([f"level_{channel}_{k}" for k in range(len(self.levels))]
                + [f"edge_{channel}_{k}" for k in range(len(self.edges))])

    def parameters(self, channel: str) -> dict[str, float]:
        """{name: value} of ``parameter_names``: levels in the input unit, edges in s."""
        return dict(zip(self.parameter_names(channel), (*self.levels, *self.edges),
                        strict=True))

    def with_parameters(self, channel: str, values: dict[str, float]) -> MultistepParameters:
        """This multistep with the levels and edges found in ``values`` replaced."""
        own = self.parameters(channel)
        own.update({n: float(values[n]) for n in own if n in values})
        v = list(own.values())
        return MultistepParameters(tuple(v[:len(self.levels)]), tuple(v[len(self.levels):]))

    def _arguments(self, time: np.ndarray, hold: str) -> tuple[np.ndarray, float]:
        c = _hold_offset(hold)
        time = np.asarray(time, dtype=float)
        dt = float(np.mean(np.diff(time)))
        return (time[:, None] - np.asarray(self.edges)[None, :]) / dt + c, dt

    def samples(self, time: np.ndarray, hold: str = "foh") -> np.ndarray:
        """Sample values (input unit) at the uniform ``time`` (s) for the model's hold."""
        arg, _ = self._arguments(time, hold)
        return self.levels[0] + np.clip(arg, 0.0, 1.0) @ np.diff(self.levels)

    def sensitivities(self, time: np.ndarray, hold: str = "foh") -> np.ndarray:
        """d samples / d (levels, edges), shape (N, levels + edges), in ``parameter_names``
        order (levels: 1, edges: 1/s times the input unit)."""
        arg, dt = self._arguments(time, hold)
        h = np.clip(arg, 0.0, 1.0)
        n = h.shape[0]
        d_levels = np.column_stack([np.ones(n), h]) - np.column_stack([h, np.zeros(n)])
        # one sample per edge moves with it: the one with 0 < arg <= 1 (one-sided when the
        # edge sits exactly on the grid)
        moving = (arg > 0.0) & (arg <= 1.0)
        d_edges = -np.where(moving, 1.0, 0.0) * np.diff(self.levels)[None, :] / dt
        return np.column_stack([d_levels, d_edges])


def from_measurement(time: np.ndarray, y: np.ndarray, sigma: float | None = None,
                     hold: str = "foh", weight: float = DEFAULT_WEIGHT,
                     significance: float = STEP_SIGNIFICANCE) -> MultistepParameters:
    """Levels and edges of a measured multistep.

    The steps and plateau levels are those of ``input_denoising.piecewise_constant``; each
    edge is placed where the step's area matches the measured samples next to it (two samples
    before the step to one after it), so that a sample caught mid-transition puts it between
    the samples.

    Parameters
    ----------
    time : numpy.ndarray
        Uniform sample times, s; shape (n,).
    y : numpy.ndarray
        The measured input, its unit; shape (n,).
    sigma : float, optional
        White-noise standard deviation of ``y``. Default ``white_noise_std(y)``.
    hold : str, optional
        The model's input hold the edges are placed for: "foh" or "zoh". Default "foh".
    weight : float, optional
        As in ``piecewise_constant``. Default ``DEFAULT_WEIGHT``.
    significance : float, optional
        As in ``piecewise_constant``. Default ``STEP_SIGNIFICANCE``.

    Returns
    -------
    MultistepParameters
        The plateau levels (unit of ``y``) and the step edges (s).

    Raises
    ------
    ValueError
        When ``time`` and ``y`` are not 1-D of one length, or ``hold`` is unknown.
    """
    time = np.asarray(time, dtype=float)
    y = np.asarray(y, dtype=float)
    if time.shape != y.shape or time.ndim != 1:
        raise ValueError(f"time and measurement must be 1-D of one length, got {time.shape} "
                         f"and {y.shape}")
    c = _hold_offset(hold)
    sigma = white_noise_std(y) if sigma is None else float(sigma)
    # a noise-free (simulated) surface: the floor keeps its steps
    sigma = max(sigma, 1e-6 * float(np.ptp(y)))
    parts = _transitions_joined(runs(y, sigma, weight, significance))
    # plateau levels without the samples next to a step, which may be mid-transition
    levels = [float((p[1 if k else 0:p.size - 1 if k < len(parts) - 1 else None]
                     if p.size >= 4 else p).mean()) for k, p in enumerate(parts)]
    dt = float(np.mean(np.diff(time)))
    edges = []
    first = 0
    for k, part in enumerate(parts[:-1]):
        first += part.size  # index of the first sample after the step
        lo, hi = first - min(2, part.size), first + min(1, parts[k + 1].size - 1)
        a, b = levels[k], levels[k + 1]
        # sum over lo..hi of h(t_i) = (t_hi - t_k)/dt + c while the ramp is inside
        area = float(np.sum(y[lo:hi + 1] - a) / (b - a))
        edge = time[hi] + c * dt - dt * area
        edges.append(float(np.clip(edge, time[lo] + c * dt, time[hi] + (c - 1) * dt)))
    return MultistepParameters(tuple(levels), tuple(edges))


def _hold_offset(hold: str) -> float:
    """c of the module docstring for the model's input hold."""
    if hold not in HOLD_OFFSET:
        raise ValueError(f"hold must be one of {', '.join(HOLD_OFFSET)}, got {hold!r}")
    return HOLD_OFFSET[hold]


def _transitions_joined(parts: list[np.ndarray]) -> list[np.ndarray]:
    """Runs of one sample lying between their neighbours' levels (a sample caught
    mid-transition, which the edge then accounts for) joined to the nearer neighbour."""
    parts = list(parts)
    k = 1
    while k < len(parts) - 1:
        before, after = parts[k - 1].mean(), parts[k + 1].mean()
        value = parts[k].mean()
        if parts[k].size == 1 and min(before, after) < value < max(before, after):
            j = k - 1 if abs(value - before) <= abs(value - after) else k + 1
            lo, hi = min(j, k), max(j, k)
            parts[lo:hi + 1] = [np.concatenate(parts[lo:hi + 1])]
        else:
            k += 1
    return parts
