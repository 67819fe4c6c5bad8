"""``flightid identify``: read a record, identify, print the estimate and its score."""

from __future__ import annotations

import json
import math
from typing import Annotated, Any

import typer
from rich.console import Console

from flightid.cli import study_options as opts
from flightid.cli.checks import (
    Output,
    check_choice,
    check_model,
    check_paths,
    printed_warnings,
    read_options,
    read_record,
)
from flightid.cli.tables import estimate_table, print_score
from flightid.identification import nuisance
from flightid.identification.agreement import Agreement
from flightid.identification.agreement import compare as compare_estimates
from flightid.identification.data.input_denoising import denoise_channels
from flightid.identification.data.reduction import SKIPPED, standard_reduction
from flightid.identification.engine import convergence
from flightid.identification.estimate import Estimate
from flightid.identification.evaluation.report import write_html
from flightid.identification.evaluation.scoring import load_truth, record_truth, score
from flightid.identification.identify import identify
from flightid.identification.methods import registry
from flightid.record import FlightRecord


def parse_options(texts: list[str]) -> dict[str, str]:
    """{key: text} from 'key=value' texts (the method's option types convert the texts)."""
    out: dict[str, str] = {}
    for text in texts:
        key, sep, value = text.partition("=")
        if not sep or not key.strip():
            raise ValueError(f"--option {text!r}: expected KEY=VALUE")
        out[key.strip()] = value
    return out


def parse_window(text: str) -> str | tuple[float, float]:
    """'auto', 'none' or 'START,END' (s)."""
    if text in ("auto", "none"):
        return text
    start, sep, end = text.partition(",")
    try:
        first, last = float(start), float(end)
    except ValueError:
        raise ValueError(f"--window must be auto, none or START,END in s, got {text!r}") \
            from None
    if not (math.isfinite(first) and math.isfinite(last) and first < last):
        raise ValueError(f"--window {text!r}: START and END must be finite with START < END "
                         "(s)")
    return first, last


def identify_command(
    record: Annotated[str, typer.Argument(help="flight record: .parquet, .csv or SIDPAC .mat")],
    method: Annotated[str, typer.Option(help="method id (flightid methods)")] = "oe",
    model: Annotated[str, typer.Option(
        help="auto (the axis the record excites: short_period for an elevator-only record, "
             "else the method's default), lat[eral], lon[gitudinal], short_period, 6dof, all, "
             "or 'Cn=beta+phat+rhat; ...' (regression methods)")] = "auto",
    coefficient: Annotated[list[str] | None, typer.Option(
        help="regression methods: only this coefficient (repeatable)")] = None,
    truth: Annotated[str | None, typer.Option(
        help="JSON of true derivative values (default: the truth a simulated record "
             "carries)")] = None,
    format: Annotated[str, typer.Option(help="table or json")] = "table",
    report: Annotated[str | None, typer.Option(help="write an HTML report here")] = None,
    option: Annotated[list[str] | None, typer.Option(
        help="method option KEY=VALUE (repeatable; flightid methods lists them)")] = None,
    window: Annotated[str, typer.Option(
        help="auto (the maneuvers on the model's inputs, when the record lists them), none, "
             "or START,END in s")] = "auto",
    all_rows: Annotated[bool, typer.Option(
        "--all", help="score every truth derivative, also those not estimated")] = False,
    multistep_input: Annotated[list[str] | None, typer.Option(
        help="input flown as a multistep whose measurement is noisy: --method oe estimates "
             "its levels and edge times, the other methods take it made piecewise "
             "constant (repeatable)")] = None,
    compare: Annotated[list[str] | None, typer.Option(
        help="also fit this method (repeatable) with the same model and window, and say "
             "whether the methods agree within their bounds, or why not")] = None,
    strict: opts.Strict = False,
    force: opts.Force = False,
    raw: opts.Raw = False,
) -> None:
    """Identify stability and control derivatives from a flight record and score them."""
    check_choice("--format", format, ("table", "json"))
    span = parse_window(window)
    options: dict[str, Any] = read_options(method, parse_options(option or []))
    check_model("--model", method, model)
    for other in compare or []:
        check_choice("--compare", other, list(registry.methods()))
        check_model("--compare", other, model)
    check_paths({"RECORD": record, "--truth": truth}, [Output("--report", report, "html")],
                force)
    with printed_warnings("identify"):
        data = read_record(record, method, force=force)
        if isinstance(span, tuple) and (span[1] <= data.time[0] or span[0] >= data.time[-1]):
            raise ValueError(f"--window {window}: outside the record ({data.time[0]:g} .. "
                             f"{data.time[-1]:g} s)")
        reduction = standard_reduction(data, raw)
        data = reduction.record
        for text in reduction.warnings:
            typer.echo(f"flightid identify: warning: {text}", err=True)
        if multistep_input and method == "oe":
            options["multistep_inputs"] = list(multistep_input)
        elif multistep_input:
            data = denoise_channels(data, multistep_input)
        if coefficient:
            options["coefficients"] = list(coefficient)
        est = identify(data, method, model, window=span, strict=strict, **options)
        agreement = compared(data, est, compare or [], span) if compare else None
    not_converged = convergence.verdict_line(est, f"method {method}")
    truth_values = load_truth(truth) if truth else record_truth(data)
    scored = score(est, truth_values, scope="all" if all_rows else "estimated") \
        if truth_values else None
    if scored is not None and not_converged:
        scored.verdict = f"{convergence.NOT_CONVERGED}; {scored.verdict}"
    if report:
        write_html(report, f"flightid identify {record} --method {method} --model "
                           f"{est.fit.get('model', model)}",
                   [est], truth_values or None,
                   notes=[n for n in (not_converged, scored.verdict if scored else "") if n])
    if format == "json":
        out = est.as_dict()
        out["fit"] = {k: v for k, v in out["fit"].items()
                      if not isinstance(v, list) or len(v) < 1000}
        if scored is not None:
            out["score"] = scored.as_dict()
        out["data_reduction"] = SKIPPED if raw else reduction.applied
        if agreement is not None:
            out["agreement"] = agreement.to_json()
        print(json.dumps(out, indent=2, default=str))
        return
    console = Console()
    for line in reduction.applied:
        typer.echo(f"data reduction: {line}")
    console.print(estimate_table(est))
    biases = nuisance.from_fit(est)
    if biases:
        typer.echo("nuisance biases (the trim's part and the excess over it):")
        for line in nuisance.describe(biases):
            typer.echo(f"  {line}")
    for part in (est.fit.get("coefficients") or {}).values():
        for step in part.get("steps", []):
            console.print(f"  {step['action']:>6} {step['term']}: {step['why']}")
    if scored is not None:
        print_score(scored, console)
    if agreement is not None:
        for line in agreement.lines():
            typer.echo(line)


def compared(data: FlightRecord, est: Estimate, methods: list[str],
             span: str | tuple[float, float]) -> Agreement:
    """``est`` compared with each of ``methods`` fitted to ``data`` with its model and
    window (``agreement.compare``); a method that cannot fit them is refused, named."""
    others = []
    for method in methods:
        try:
            others.append(identify(data, method, est.fit["model"], window=span))
        except (KeyError, ValueError) as exc:
            raise ValueError(f"--compare {method}: {exc}") from None
    return compare_estimates([est, *others])
