"""The ranked effect and the held-out measures pooled over windows: each channel's gap
(residual over measured energy), its white-noise floor, their mean over channels, and an
effect's parameters combined over the windows (inverse-variance mean)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from flightid.identification.gap.candidates.build import Candidate
from flightid.identification.gap.fit import FilterFit, WindowFit, noise_energy


def pooled_fractions(fits: list[WindowFit]) -> dict[str, float]:
    """Per channel: residual energy / measured energy (mean removed per window), pooled.

    Parameters
    ----------
    fits : list of WindowFit
        The window fits, all with the same channels.

    Returns
    -------
    dict of str to float
        {channel: fraction}, 1; nan where the measured energy is zero.
    """
    out = {}
    for ch in fits[0].residual:
        res = sum(float(np.sum(f.residual[ch] ** 2)) for f in fits)
        spread = sum(float(np.sum((f.measured[ch] - np.mean(f.measured[ch])) ** 2))
                     for f in fits)
        out[ch] = res / spread if spread > 0 else float("nan")
    return out


def pooled_noise(fits: list[WindowFit]) -> dict[str, float]:
    """Per channel: the white-noise energy of the residual / measured energy, pooled over windows.

    The white-noise energy is ``fit.noise_energy``'s: the floor no effect can take a gap below.

    Parameters
    ----------
    fits : list of WindowFit
        The window fits, all with the same channels.

    Returns
    -------
    dict of str to float
        {channel: fraction}, 1; nan where the measured energy is zero.
    """
    out = {}
    for ch in fits[0].residual:
        noise = sum(noise_energy(f.residual[ch]) for f in fits)
        spread = sum(float(np.sum((f.measured[ch] - np.mean(f.measured[ch])) ** 2))
                     for f in fits)
        out[ch] = noise / spread if spread > 0 else float("nan")
    return out


def mean_gap(fractions: dict[str, float]) -> float:
    """The gap of a set of channels: the mean of their fractions.

    Parameters
    ----------
    fractions : dict of str to float
        {channel: fraction}, 1.

    Returns
    -------
    float
        The mean of the finite fractions; nan when none is known.
    """
    known = [v for v in fractions.values() if math.isfinite(v)]
    return float(np.mean(known)) if known else float("nan")


@dataclass
class Ranked:
    """One candidate's fit, evidence and held-out check."""

    candidate: Candidate
    values: dict[str, float]  # linear-model values of the freed parameters (combined)
    std: dict[str, float]
    parameters: dict[str, dict[str, float]]  # catalogue units
    delta_bic: float
    fit_cost_change: float
    heldout_before: dict[str, float] = field(default_factory=dict)
    heldout_after: dict[str, float] = field(default_factory=dict)
    heldout_cost_change: float = float("nan")
    heldout_windows: list[str] = field(default_factory=list)
    confirmed: bool = False
    note: str = ""
    # outside the catalogue's physical range: the family that fits (``ranges.out_of_range``)
    family: str = ""
    # per held-out window: the cost change with the effect (``heldout_cost_change`` summed)
    heldout_changes: dict[str, float] = field(default_factory=dict)
    # confirmed effects the held-out data cannot tell apart from this one (``simplest``)
    alternatives: list[Ranked] = field(default_factory=list)
    # a named effect's equivalence class in words (``candidates.classes.class_text``)
    equivalent: str = ""

    @property
    def shrink(self) -> float:
        """Relative shrink of the held-out gap (1: closed, 0: unchanged)."""
        before, after = mean_gap(self.heldout_before), mean_gap(self.heldout_after)
        return 1.0 - after / before if before > 0 else float("nan")

    def to_json(self) -> dict:
        return {"name": self.candidate.entry,
                "label": self.candidate.label, "options": dict(self.candidate.options),
                "parameters": self.parameters,
                "evidence": {"delta_bic": self.delta_bic, "fit_cost_change": self.fit_cost_change,
                             "heldout_cost_change": self.heldout_cost_change,
                             "heldout_shrink": self.shrink, "confirmed": self.confirmed,
                             "heldout_windows": self.heldout_windows},
                "heldout_before": self.heldout_before, "heldout_after": self.heldout_after,
                "note": self.note, "family": self.family or None,
                "not_told_apart_from": [a.candidate.label for a in self.alternatives],
                "class": self.equivalent or None}


def combine(fits: Sequence[WindowFit | FilterFit], names: tuple[str, ...]
            ) -> tuple[dict[str, float], dict[str, float]] | None:
    """Inverse-variance mean of the windows' estimates.

    Parameters
    ----------
    fits : list of WindowFit
        The window fits.
    names : tuple of str
        The parameters combined.

    Returns
    -------
    tuple of (dict of str to float, dict of str to float) or None
        ({name: value}, {name: standard error}) in the parameters' units; None when no window
        identifies some parameter.
    """
    values, std = {}, {}
    for n in names:
        pts = [(f.values[n], f.std[n]) for f in fits
               if n not in f.unidentifiable and math.isfinite(f.std[n]) and f.std[n] > 0]
        if not pts:
            return None
        w = np.array([1.0 / s**2 for _, s in pts])
        values[n] = float(np.sum(w * np.array([v for v, _ in pts])) / np.sum(w))
        std[n] = float(1.0 / math.sqrt(np.sum(w)))
    return values, std
