"""The scenario runner behind ``flightid simulate``: fly a card, write records, plot them.

``simulate(card, output, truth_path, plot_path, seed, progress)`` flies a card file or
library card (``flightid.scenarios.cards``), reporting its progress to an optional
callback, writes the measured record (and the truth), and ``plot_record`` draws inputs
and responses on a shared time axis. Printing, progress bars and exit codes are the
command line's (``flightid.cli.simulate``).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.figure import Figure

from flightid.files import atomic_path
from flightid.record import FlightRecord
from flightid.scenarios.cards import Card, describe, fly_card, library_cards, load_card
from flightid.scenarios.inputs import total_signals
from flightid.units import DEG

# (channel, label, scale to the plotted unit) per panel: inputs first, then responses
_PANELS: tuple[tuple[str, tuple[tuple[str, float], ...]], ...] = (
    ("surfaces (deg)", (("de", 1 / DEG), ("da", 1 / DEG), ("dr", 1 / DEG))),
    ("throttle (-)", (("throttle", 1.0),)),
    ("angles of attack, sideslip (deg)", (("alpha", 1 / DEG), ("beta", 1 / DEG))),
    ("body rates (deg/s)", (("p", 1 / DEG), ("q", 1 / DEG), ("r", 1 / DEG))),
    ("attitude (deg)", (("phi", 1 / DEG), ("theta", 1 / DEG))),
    ("airspeed (m/s)", (("V", 1.0),)),
    ("specific force (m/s^2)", (("ax", 1.0), ("ay", 1.0), ("az", 1.0))),
    ("turbulence (m/s)", (("turb_u", 1.0), ("turb_v", 1.0), ("turb_w", 1.0))),
)


def list_cards() -> list[tuple[str, str]]:
    """(name, one-line description) of every library card.

    Returns
    -------
    list[tuple[str, str]]
        (card name, description) pairs.
    """
    return [(name, describe(path)) for name, path in library_cards().items()]


def plot_record(measured: FlightRecord, path: str | Path, truth: FlightRecord | None = None,
                title: str = "") -> Path:
    """PNG of inputs and responses (measured as lines, truth dashed) on one time axis (s).

    Drawn on a bare matplotlib ``Figure`` (no pyplot, no backend chosen: the caller's
    matplotlib state is left alone).

    Parameters
    ----------
    measured : FlightRecord
        The measured flight.
    path : str or Path
        PNG file to write.
    truth : FlightRecord or None, optional
        The truth record, drawn dashed; None draws only the measured one.
    title : str, optional
        Figure title.

    Returns
    -------
    Path
        The written PNG.
    """
    def has(name: str) -> bool:
        return name in measured or (truth is not None and name in truth)

    panels = []
    for label, chans in _PANELS:
        present = tuple((c, k) for c, k in chans if has(c))
        if not present:
            continue
        values = [rec[c] for rec in (measured, truth) if rec is not None
                  for c, _ in present if c in rec]
        if label.startswith(("throttle", "turbulence")) and all(np.ptp(v) < 1e-9
                                                                for v in values):
            continue  # a constant throttle or calm air says nothing
        panels.append((label, present))
    fig = Figure(figsize=(10, 1.9 * len(panels)))
    axes = fig.subplots(len(panels), 1, sharex=True, squeeze=False)
    colors = matplotlib.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, (label, chans) in zip(axes[:, 0], panels, strict=True):
        for i, (c, k) in enumerate(chans):
            color = colors[i % len(colors)]
            if c in measured:
                ax.plot(measured.time, k * measured[c], color=color, lw=1.0, label=c)
            if truth is not None and c in truth:
                ax.plot(truth.time, k * truth[c], color=color, lw=0.8, ls="--",
                        label=None if c in measured else f"{c} (truth)")
        ax.set_ylabel(label, fontsize=8)
        ax.legend(loc="upper right", fontsize=7, ncol=len(chans))
        ax.grid(True, alpha=0.3)
    axes[-1, 0].set_xlabel("time (s)")
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    path = Path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110)
    return path


def fly_with_progress(card: Card, seed: int | None = None, show: bool = True,
                      progress: Callable[[float, float], None] | None = None
                      ) -> tuple[FlightRecord, FlightRecord]:
    """``fly_card`` reporting its progress: ``progress(flown_s, total_s)`` (simulated
    seconds) is called about once per simulated second. The library draws nothing; the
    command line passes a callback that draws a bar (``flightid.cli.progress``).
    ``show=False`` turns the callback off.

    Parameters
    ----------
    card : Card
        The card to fly.
    seed : int or None, optional
        Noise and turbulence seed; None uses the card's seed.
    show : bool, optional
        False turns ``progress`` off. Default True.
    progress : callable or None, optional
        ``progress(flown_s, total_s)``, simulated seconds; None reports nothing.

    Returns
    -------
    tuple[FlightRecord, FlightRecord]
        (measured, truth) records.
    """
    if progress is None or not show:
        return fly_card(card, seed)

    def steps(k: int, n: int) -> None:
        progress(k / card.rate, card.duration)

    return fly_card(card, seed, progress=steps)


# a surface whose flown peak falls short of the commanded one by more than this fraction
# (plus CLIP_TOLERANCE_RAD) hit its travel limit; an actuator lag alone does not cut the
# peak of a held step by 5 %
CLIP_FRACTION = 0.05
CLIP_TOLERANCE_RAD = 0.002


class ClippedInputWarning(UserWarning):
    """A commanded input went beyond the surface's travel and was clipped."""


def clipped_inputs(card: Card, truth: FlightRecord) -> dict[str, dict[str, float]]:
    """The surfaces whose commanded increments (the card's maneuvers) went beyond what the
    aircraft flew, i.e. were clipped at the surface's travel limit: {surface:
    {"commanded_rad", "flown_rad", "samples"}} with the peak |increment| commanded and
    flown (rad from the trim) and how many samples fell short.

    Parameters
    ----------
    card : Card
        The flown card (its maneuvers give the commanded increments).
    truth : FlightRecord
        The truth record of the flight (surfaces flown, rad).

    Returns
    -------
    dict[str, dict[str, float]]
        Surface name -> {"commanded_rad", "flown_rad", "samples"}; empty if nothing clipped.
    """
    if not card.maneuvers:
        return {}
    planned = total_signals(list(card.maneuvers), truth.time)
    out: dict[str, dict[str, float]] = {}
    for surface, u in planned.items():
        if surface not in ("de", "da", "dr", "throttle") or surface not in truth:
            continue
        flown = truth[surface] - truth[surface][0]
        for sign in (1.0, -1.0):
            want, got = float(np.max(sign * u)), float(np.max(sign * flown))
            if want > got * (1 + CLIP_FRACTION) + CLIP_TOLERANCE_RAD:
                short = int(np.sum(sign * u > sign * flown + CLIP_TOLERANCE_RAD + CLIP_FRACTION
                                   * np.abs(u)))
                entry = out.setdefault(surface, {"commanded_rad": 0.0, "flown_rad": 0.0,
                                                 "samples": 0})
                if want > entry["commanded_rad"]:
                    entry["commanded_rad"], entry["flown_rad"] = want, got
                entry["samples"] += short
    return out


def _mark_clipped(card: Card, measured: FlightRecord, truth: FlightRecord) -> None:
    clipped = clipped_inputs(card, truth)
    if not clipped:
        return
    for rec in {id(measured): measured, id(truth): truth}.values():
        rec.meta.extra["clipped"] = clipped
    for surface, c in clipped.items():
        want, got = c["commanded_rad"], c["flown_rad"]
        amounts = (f"{want:.3g} (fraction)", f"{got:.3g}") if surface == "throttle" else (
            f"{want:.3g} rad ({want / DEG:.1f} deg)", f"{got:.3g} rad ({got / DEG:.1f} deg)")
        warnings.warn(
            f"card {card.name}: {surface} was commanded {amounts[0]} from trim but reached "
            f"only {amounts[1]}: clipped at its travel limit in {int(c['samples'])} samples "
            "(recorded in meta.extra['clipped'])", ClippedInputWarning, stacklevel=3)


def simulate(card: str | Card, output: str | Path, truth_path: str | Path | None = None,
             plot_path: str | Path | None = None, seed: int | None = None,
             progress: Callable[[float, float], None] | None = None
             ) -> tuple[FlightRecord, FlightRecord]:
    """Fly ``card`` (a loaded card, a path or a library name) and write the measured record
    to ``output``; ``progress(flown_s, total_s)`` as in :func:`fly_with_progress`. An input
    clipped at a surface's travel limit is recorded in ``meta.extra['clipped']`` of both
    records and warned about (:class:`ClippedInputWarning`).

    Parameters
    ----------
    card : str or Card
        A loaded card, a card file path or a library card name.
    output : str or Path
        File for the measured record.
    truth_path : str or Path or None, optional
        File for the truth record; None writes none.
    plot_path : str or Path or None, optional
        PNG of the flight (:func:`plot_record`); None draws none.
    seed : int or None, optional
        Noise and turbulence seed; None uses the card's seed.
    progress : callable or None, optional
        ``progress(flown_s, total_s)``, simulated seconds.

    Returns
    -------
    tuple[FlightRecord, FlightRecord]
        (measured, truth) records.
    """
    c = card if isinstance(card, Card) else load_card(card)
    measured, truth = fly_with_progress(c, seed, progress=progress)
    _mark_clipped(c, measured, truth)
    measured.write(output)
    if truth_path is not None:
        truth.write(truth_path)
    if plot_path is not None:
        used = c.seed if seed is None else seed
        plot_record(measured, plot_path, truth if measured is not truth else None,
                    title=f"{c.name} ({c.aircraft}), seed {used}")
    return measured, truth
