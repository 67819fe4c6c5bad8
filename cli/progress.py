"""Rich progress bars for the library's plain progress callbacks.

The library reports a flight's progress as ``progress(flown_s, total_s)`` (simulated
seconds; ``flightid.scenarios.simulate.fly_with_progress``) and a study's as the count of
realizations or cases done; it draws nothing, the command line draws the bar:

    with flight_progress(f"flying {card.name}", card.duration) as progress:
        simulate(card, output, progress=progress)
    with count_progress("Monte Carlo navion-demo") as update:
        montecarlo.run(card, n, progress=lambda done, total: update(done, total))
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager

from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    ProgressColumn,
    Task,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.text import Text

Update = Callable[..., None]  # update(done, total, label=None)


@contextmanager
def flight_progress(description: str, total_s: float, show: bool = True
                    ) -> Iterator[Callable[[float, float], None] | None]:
    """A ``progress(flown_s, total_s)`` callback drawing a transient bar on stderr
    (simulated seconds, elapsed time, ETA) while the block runs; None when ``show`` is
    false."""
    if not show:
        yield None
        return
    with Progress(TextColumn("[bold]{task.description}"), BarColumn(),
                  TextColumn("{task.completed:.0f}/{task.total:.0f} s flown"),
                  TimeElapsedColumn(), TimeRemainingColumn(), transient=True,
                  console=Console(stderr=True)) as bar:
        task = bar.add_task(description, total=total_s)

        def progress(flown_s: float, total: float) -> None:
            bar.update(task, completed=flown_s, total=total)

        yield progress


class RateColumn(ProgressColumn):
    """Items (realizations, cases) per minute."""

    def render(self, task: Task) -> Text:
        speed = task.finished_speed or task.speed
        return Text("" if speed is None else f"{60 * speed:.1f}/min")


@contextmanager
def count_progress(description: str, show: bool = True) -> Iterator[Update | None]:
    """An ``update(done, total, label=None)`` callback drawing a transient bar on stderr
    (done/total, rate per minute, elapsed time, ETA; ``label`` replaces the description)
    while the block runs; None when ``show`` is false."""
    if not show:
        yield None
        return
    with Progress(TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(),
                  RateColumn(), TimeElapsedColumn(), TimeRemainingColumn(), transient=True,
                  console=Console(stderr=True)) as bar:
        task = bar.add_task(description, total=None)

        def update(done: int, total: int, label: str | None = None) -> None:
            bar.update(task, completed=done, total=total,
                       description=description if label is None else label)

        yield update
