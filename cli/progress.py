"""A rich progress bar for the library's plain progress callbacks.

The library reports a flight's progress as ``progress(flown_s, total_s)`` (simulated
seconds; ``flightid.scenarios.simulate.fly_with_progress``) and draws nothing; the
command line draws the bar:

    with flight_progress(f"flying {card.name}", card.duration) as progress:
        simulate(card, output, progress=progress)
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager

from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn


@contextmanager
def flight_progress(description: str, total_s: float, show: bool = True
                    ) -> Iterator[Callable[[float, float], None] | None]:
    """A ``progress(flown_s, total_s)`` callback drawing a transient bar (simulated seconds,
    elapsed time, ETA) while the block runs; None when ``show`` is false."""
    if not show:
        yield None
        return
    with Progress(TextColumn("[bold]{task.description}"), BarColumn(),
                  TextColumn("{task.completed:.0f}/{task.total:.0f} s flown"),
                  TimeElapsedColumn(), TimeRemainingColumn(), transient=True) as bar:
        task = bar.add_task(description, total=total_s)

        def progress(flown_s: float, total: float) -> None:
            bar.update(task, completed=flown_s, total=total)

        yield progress
