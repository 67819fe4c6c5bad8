"""``flightid frequency-response``: a frequency response with coherence and random error
printed as a table, optionally a Bode/coherence PNG (printing only; the work is
``flightid.identification.frequency.record_response``)."""

from __future__ import annotations

from typing import Annotated

import numpy as np
import typer

from flightid.cli import study_options as opts
from flightid.cli.checks import (
    Output,
    check_frequency_band,
    check_number,
    check_paths,
    check_suffix,
    printed_warnings,
    read_record,
)
from flightid.files import atomic_path
from flightid.identification.frequency.grids import default_windows
from flightid.identification.frequency.plots import bode_figure
from flightid.identification.frequency.record_response import frequency_response


def frequency_response_command(
    record: Annotated[str, typer.Argument(help="flight record: .parquet, .csv or SIDPAC .mat")],
    input: Annotated[str, typer.Option("--input", help="input channel, e.g. de")],
    output: Annotated[str, typer.Option("--output", help="output channel, e.g. q")],
    condition_on: Annotated[
        list[str] | None, typer.Option(help="other input to condition on (repeatable)")
    ] = None,
    window: Annotated[
        list[float] | None, typer.Option(help="window length in s (repeatable; composite)")
    ] = None,
    f_min: Annotated[float | None, typer.Option(help="lowest frequency, Hz")] = None,
    f_max: Annotated[float | None, typer.Option(help="highest frequency, Hz")] = None,
    plot: Annotated[str | None, typer.Option(help="write a Bode/coherence PNG here")] = None,
    force: opts.Force = False,
) -> None:
    """Frequency response output/input with coherence and random error (CIFER style)."""
    for w in window or ():
        check_number("--window", w, low=0.0, low_open=True, unit="s")
    check_suffix("--plot", plot, (".png", ".svg", ".pdf"))
    check_paths({"RECORD": record}, [Output("--plot", plot)], force)
    with printed_warnings("frequency-response"):
        rec = read_record(record, "frequency-response", force=force)
    check_frequency_band(f_min, f_max, rec.dt)
    span = float(rec.time[-1] - rec.time[0]) if len(rec) > 1 else 0.0
    for w in window or ():
        if w > span:
            raise ValueError(f"--window {w:g} s is longer than the record ({span:g} s)")
    for name in (input, output, *(condition_on or [])):
        rec[name]  # KeyError naming the channels the record has
    wins = tuple(window) if window else default_windows(span, rec.dt)
    freqs = None
    if f_min is not None or f_max is not None:
        lo = f_min if f_min is not None else 2.0 / max(wins)
        hi = f_max if f_max is not None else 0.2 / rec.dt
        if not lo < hi:
            raise ValueError(f"the band {lo:g}..{hi:g} Hz is empty; give --f-min below "
                             f"--f-max (the longest window, {max(wins):g} s, resolves "
                             f"down to {2.0 / max(wins):g} Hz)")
        freqs = np.geomspace(lo, hi, 100)
    r = frequency_response(rec, input, output, other_inputs=condition_on or [], windows=wins,
                           frequencies=freqs)
    unit = f"{rec.unit(output)} per {rec.unit(input)}"
    print(f"# {output}/{input} ({unit}), windows {', '.join(f'{w:g}' for w in wins)} s"
          + (f", conditioned on {', '.join(r.conditioned_on)}" if r.conditioned_on else ""))
    print(f"{'f_Hz':>9} {'mag_dB':>9} {'phase_deg':>10} {'coherence':>9} {'rand_err':>9}")
    for f, m, p, c, e in zip(r.frequency, r.magnitude_db, r.phase_deg, r.coherence,
                             r.random_error, strict=True):
        print(f"{f:9.4f} {m:9.3f} {p:10.2f} {c:9.3f} {e:9.4f}")
    if plot:
        fig = bode_figure([r], title=f"{rec.meta.aircraft or record}: {output}/{input}")
        with atomic_path(plot) as tmp:
            fig.savefig(tmp, dpi=110)
        print(f"# Bode plot written to {plot}")
