"""``flightid demo``: fly the built-in Navion card, identify by output error, score, report.

The main job, end to end: a flight card (``scenarios/library/navion-demo.toml``: elevator
3211, aileron doublet, rudder 2-1-1, research-grade sensors, light turbulence) is flown
in JSBSim; the truth derivatives come from the same JSBSim model at the card's trim
(body axes: the perturbation models use body rates); output error fits a short-period
model to the elevator maneuver and a lateral model to the aileron and rudder maneuvers;
each estimate is scored against truth and an HTML report is written.

Cm_alphadot and CL_q are held at their a priori (truth-file) values: with a
short-period maneuver they are not separable from Cm_q and CL_alpha (Morelli & Klein
2016 sec. 6.x; the identifiability check reports them so when freed).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from flightid.identification.estimate import Estimate
from flightid.identification.scoring import Score
from flightid.record import FlightRecord

DEFAULT_CARD = "navion-demo"
# derivatives fixed at their a priori value in the short-period fit (see module docstring)
A_PRIORI = ("CL_q", "Cm_alphadot")
SETTLE_S = 8.0  # s of free response kept after the last input of a window


@dataclass
class DemoResult:
    """Everything the demo made: records, truth, estimates, scores and the report path."""

    measured: FlightRecord
    truth_record: FlightRecord
    truth: dict[str, float]
    estimates: list[Estimate]
    scores: list[Score]
    report: Path | None


def maneuver_window(card, surfaces: tuple[str, ...], duration: float) -> tuple[float, float]:
    """(start, end) in s covering the card's maneuvers on ``surfaces`` plus settling time."""
    chosen = [m for m in card.maneuvers if set(m.surfaces()) & set(surfaces)]
    if not chosen:
        raise ValueError(f"card {card.name!r} has no maneuver on {', '.join(surfaces)}")
    start = max(0.0, min(m.start for m in chosen) - 1.0)
    later = [m.start for m in card.maneuvers if m.start > max(x.end for x in chosen)]
    end = min([duration, max(m.end for m in chosen) + SETTLE_S, *later])
    return start, end


def identify_card_flight(card, measured: FlightRecord, truth: dict[str, float]) -> list[Estimate]:
    """Output error on the card's longitudinal and lateral windows of ``measured``."""
    from flightid.identification import linear_models as lm
    from flightid.identification import output_error

    estimates = []
    t0, t1 = maneuver_window(card, ("de",), card.duration)
    lon = measured.slice(t0, t1)
    names = lm.SHORT_PERIOD_DERIVATIVES
    model = lm.short_period(lm.condition_from_record(lon), derivatives=names,
                            start={n: truth[n] for n in A_PRIORI if n in truth})
    free = [p for p in model.parameters if p not in A_PRIORI]
    estimates.append(output_error.estimate(lon, model, free=free, start="equation_error",
                                           initial_state="estimate", colored=True))
    t0, t1 = maneuver_window(card, ("da", "dr"), card.duration)
    lat = measured.slice(t0, t1)
    model = lm.lateral(lm.condition_from_record(lat), derivatives=lm.LATERAL_DERIVATIVES)
    estimates.append(output_error.estimate(lat, model, start="equation_error",
                                           initial_state="estimate", colored=True))
    return estimates


def run(card: str = DEFAULT_CARD, seed: int | None = None,
        report: str | Path | None = "flightid-demo.html", show: bool = True) -> DemoResult:
    """Fly ``card``, identify by output error, print the scored tables, write the report."""
    from rich.console import Console

    from flightid.identification.report import write_html
    from flightid.identification.scoring import score
    from flightid.scenarios.cards import load_card
    from flightid.scenarios.simulate import fly_with_progress, plot_record
    from flightid.sim.model import load
    from flightid.sim.trim import trim
    from flightid.sim.truth import derivatives

    console = Console(quiet=not show)
    c = load_card(card)
    used_seed = c.seed if seed is None else int(seed)
    measured, truth_record = fly_with_progress(c, used_seed, show=show)
    cond = c.condition
    model = load(c.aircraft)
    trimmed = trim(model, cond.altitude_m, cond.speed_m_s, cond.gamma_rad, cond.bank_rad,
                   cond.flaps_rad)
    truth = derivatives(model, trimmed, axes="body").values
    with console.status("output error: short period and lateral models"):
        estimates = identify_card_flight(c, measured, truth)
    scores = []
    for est in estimates:
        scored = score(est, {n: truth[n] for n in est.names if n in truth})
        scored.method = f"output error, {est.fit.get('model', '')}".strip(", ")
        scores.append(scored)
        console.print(scored.table())
    path = None
    if report is not None:
        fig_path = Path(report).with_suffix(".flight.png")
        plot_record(measured, fig_path, truth_record, title=f"{c.name}, seed {used_seed}")
        path = write_html(
            report, f"flightid demo: {c.name} (seed {used_seed})", estimates,
            truth={n: truth[n] for e in estimates for n in e.names if n in truth},
            notes=[c.description,
                   f"Truth: JSBSim {c.aircraft} at {cond.altitude_m:g} m, {cond.speed_m_s:g} m/s, "
                   "body axes, central differences of the model's aerodynamics.",
                   "Held at a priori (truth-file) values: " + ", ".join(A_PRIORI) + "."]
            + [s.verdict for s in scores],
            figures=[("Flight: measured and truth", fig_path)],
        )
        console.print(f"report: {path}")
    return DemoResult(measured, truth_record, truth, estimates, scores, path)



def run_cli(card: str, seed: int | None, report: str) -> None:
    """Command-line wrapper: a clear message and exit code 2 instead of a traceback."""
    import typer

    from flightid.scenarios.cards import CardError
    from flightid.sim.flight import DepartureError
    from flightid.sim.trim import TrimError

    try:
        run(card, seed, report)
    except (CardError, TrimError, DepartureError, ValueError) as exc:
        typer.echo(f"flightid demo: {exc}", err=True)
        raise typer.Exit(2) from None
