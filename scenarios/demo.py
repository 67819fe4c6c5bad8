"""``flightid demo``: fly the built-in Navion card, identify by output error, score, report.

The main job, end to end: a flight card (``scenarios/library/navion-demo.toml``: elevator
3211, aileron doublet, rudder 2-1-1, research-grade sensors, light turbulence) is flown
in JSBSim; the record carries its maneuvers, the exact truth of the JSBSim model at the
card's trim and the card's a priori values. Output error (``identify``, default options)
fits a short-period model on the elevator maneuver and a lateral model (all 15
derivatives) on the aileron and rudder maneuvers; each estimate is scored against the
record's truth and an HTML report is written.

CL_q and Cm_alphadot are held at the card's a priori values (Teper 1969, stated in the
card): a short-period maneuver does not separate them from CL_alpha and Cm_q (Morelli &
Klein 2016 sec. 6.3).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from flightid.identification.estimate import Estimate
from flightid.identification.evaluation.report import write_html
from flightid.identification.evaluation.scoring import Score, record_truth, score
from flightid.identification.identify import identify
from flightid.identification.models import linear as lm
from flightid.record import FlightRecord
from flightid.scenarios.cards import load_card
from flightid.scenarios.simulate import fly_with_progress, plot_record

DEFAULT_CARD = "navion-demo"
# (model, derivatives) of the two output-error fits
FITS = (("short_period", lm.SHORT_PERIOD_DERIVATIVES), ("lateral", lm.LATERAL_DERIVATIVES))


@dataclass
class DemoResult:
    """Everything the demo made: records, truth, estimates, scores and the report path."""

    measured: FlightRecord
    truth_record: FlightRecord
    truth: dict[str, float]
    estimates: list[Estimate]
    scores: list[Score]
    report: Path | None


def identify_flight(measured: FlightRecord) -> list[Estimate]:
    """Output error on the record's longitudinal and lateral maneuver windows.

    Parameters
    ----------
    measured : FlightRecord
        The measured flight with its maneuver windows.

    Returns
    -------
    list[Estimate]
        One estimate per fit: short-period, then lateral-directional.
    """
    return [identify(measured, "oe", model, derivatives=list(names)) for model, names in FITS]


def run(card: str = DEFAULT_CARD, seed: int | None = None,
        report: str | Path | None = "flightid-demo.html",
        progress: Callable[[float, float], None] | None = None) -> DemoResult:
    """Fly ``card``, identify by output error, score against the record's truth, write the
    report; ``progress(flown_s, total_s)`` follows the flight.

    Parameters
    ----------
    card : str, optional
        Library card name or path. Default ``"navion-demo"``.
    seed : int or None, optional
        Noise and turbulence seed; None uses the card's seed.
    report : str or Path or None, optional
        HTML report path (a PNG of the flight goes next to it); None writes no report.
    progress : callable or None, optional
        ``progress(flown_s, total_s)``, simulated seconds, called while flying.

    Returns
    -------
    DemoResult
        Measured and truth records, truth derivatives, estimates, scores and the report path.
    """
    c = load_card(card)
    used_seed = c.seed if seed is None else int(seed)
    measured, truth_record = fly_with_progress(c, used_seed, progress=progress)
    truth = record_truth(measured)
    estimates = identify_flight(measured)
    scores = []
    for est in estimates:
        scored = score(est, truth)
        scored.method = f"output error, {est.fit.get('model', '')}".strip(", ")
        scores.append(scored)
    path = None
    if report is not None:
        fig_path = Path(report).with_suffix(".flight.png")
        plot_record(measured, fig_path, truth_record, title=f"{c.name}, seed {used_seed}")
        held = sorted({f"{n} = {v['value']:g} ({v['source']})" for e in estimates
                       for n, v in (e.fit.get("a_priori") or {}).items()})
        cond = c.condition
        path = write_html(
            report, f"flightid demo: {c.name} (seed {used_seed})", estimates,
            truth={n: truth[n] for e in estimates for n in e.names if n in truth},
            notes=[c.description,
                   f"Truth: JSBSim {c.aircraft} at {cond.altitude_m:g} m, {cond.speed_m_s:g} m/s, "
                   "body axes, central differences of the model's aerodynamics.",
                   "Held at a priori values: " + "; ".join(held) + "."]
            + [s.verdict for s in scores],
            figures=[("Flight: measured and truth", fig_path)],
        )
    return DemoResult(measured, truth_record, truth, estimates, scores, path)
