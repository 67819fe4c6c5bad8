"""The scenario runner behind ``flightid simulate``: fly a card, write records, plot them.

``simulate(card, output, truth_path, plot_path, seed)`` flies a card file or library card
(``flightid.scenarios.cards``) with a rich progress bar, writes the measured record (and
the truth), and ``plot_record`` draws inputs and responses on a shared time axis.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from flightid.record import FlightRecord
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
    """(name, one-line description) of every library card."""
    from flightid.scenarios.cards import describe, library_cards

    return [(name, describe(path)) for name, path in library_cards().items()]


def plot_record(measured: FlightRecord, path: str | Path, truth: FlightRecord | None = None,
                title: str = "") -> Path:
    """PNG of inputs and responses (measured as lines, truth dashed) on one time axis (s)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

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
    fig, axes = plt.subplots(len(panels), 1, sharex=True, figsize=(10, 1.9 * len(panels)),
                             squeeze=False)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
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
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def fly_with_progress(card, seed: int | None = None, show: bool = True
                      ) -> tuple[FlightRecord, FlightRecord]:
    """``fly_card`` with a progress bar (simulated seconds, elapsed time, ETA) when ``show``."""
    from rich.progress import (
        BarColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    from flightid.scenarios.cards import fly_card

    if not show:
        return fly_card(card, seed)
    with Progress(TextColumn("[bold]{task.description}"), BarColumn(),
                  TextColumn("{task.completed:.0f}/{task.total:.0f} s flown"),
                  TimeElapsedColumn(), TimeRemainingColumn(), transient=True) as bar:
        task = bar.add_task(f"flying {card.name}", total=card.duration)

        def progress(k: int, n: int) -> None:
            bar.update(task, completed=k / card.rate)

        return fly_card(card, seed, progress=progress)


def simulate(card: str, output: str | Path, truth_path: str | Path | None = None,
             plot_path: str | Path | None = None, seed: int | None = None,
             show_progress: bool = True) -> tuple[FlightRecord, FlightRecord]:
    """Fly ``card`` (path or library name) and write the measured record to ``output``."""
    from flightid.scenarios.cards import load_card

    c = load_card(card)
    measured, truth = fly_with_progress(c, seed, show=show_progress)
    measured.write(output)
    if truth_path is not None:
        truth.write(truth_path)
    if plot_path is not None:
        used = c.seed if seed is None else seed
        plot_record(measured, plot_path, truth if measured is not truth else None,
                    title=f"{c.name} ({c.aircraft}), seed {used}")
    return measured, truth


def run_cli(card: str | None, output: str | None, truth: str | None, plot: str | None,
            seed: int | None, list_only: bool) -> None:
    """Command-line wrapper: clear messages and exit codes instead of tracebacks."""
    import typer

    from flightid.scenarios.cards import CardError
    from flightid.sim.flight import DepartureError
    from flightid.sim.trim import TrimError

    if list_only:
        for name, text in list_cards():
            typer.echo(f"{name:32s} {text}")
        return
    if card is None or output is None:
        raise typer.BadParameter("give a CARD and -o/--output (or --list)")
    try:
        measured, _ = simulate(card, output, truth, plot, seed)
    except (CardError, TrimError) as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(2) from None
    except DepartureError as exc:
        typer.echo(f"error: the flight departed: {exc}", err=True)
        raise typer.Exit(3) from None
    typer.echo(f"wrote {output}: {len(measured)} samples, {measured.time[-1]:.2f} s, "
               f"{len(measured.channels)} channels at {measured.meta.sample_rate:g} Hz")
    for extra in (truth, plot):
        if extra:
            typer.echo(f"wrote {extra}")
