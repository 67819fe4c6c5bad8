"""One entry point per identification method, for the command line and scripts.

``METHODS[name](record, model, options)`` returns a list of Estimate. ``model`` is a
preset name ("lateral", "longitudinal") or an explicit structure
"Cn=beta+phat+rhat+da+dr; CY=beta+rhat+dr" (for stepwise regression the terms are the
explanatory variables from which the candidates are formed). ``options`` are the
method's keyword options; "coefficients" restricts the model to those coefficients.
Other methods register here under their own name (``METHODS['oe'] = ...``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from flightid.identification.estimate import Estimate
from flightid.record import FlightRecord

LATERAL = ("beta", "phat", "rhat", "da", "dr")
LONGITUDINAL = ("alpha", "qhat", "de")
MODELS: dict[str, dict[str, tuple[str, ...]]] = {
    "lateral": {"CY": LATERAL, "Cl": LATERAL, "Cn": LATERAL},
    "longitudinal": {"CX": LONGITUDINAL, "CZ": LONGITUDINAL, "Cm": LONGITUDINAL},
}
MODELS["all"] = {**MODELS["longitudinal"], **MODELS["lateral"]}


def parse_model(model: str) -> dict[str, list[str]]:
    """{coefficient: terms} from a preset name or 'Cn=beta+phat; CY=beta+rhat'."""
    text = model.strip()
    if text in MODELS:
        return {c: list(t) for c, t in MODELS[text].items()}
    if "=" not in text:
        raise ValueError(
            f"unknown model {model!r}: use a preset ({', '.join(MODELS)}) or "
            "'Coef=term+term; Coef=...'"
        )
    out: dict[str, list[str]] = {}
    for part in filter(None, (p.strip() for p in text.split(";"))):
        coef, sep, terms = part.partition("=")
        if not sep or not terms.strip():
            raise ValueError(f"model part {part!r}: expected 'Coef=term+term'")
        out[coef.strip()] = [t.strip() for t in terms.split("+") if t.strip()]
    return out


def _restrict(structure: dict[str, list[str]], options: Mapping[str, Any]) -> dict:
    wanted = options.get("coefficients")
    if not wanted:
        return structure
    missing = [c for c in wanted if c not in structure]
    if missing:
        raise ValueError(f"coefficients {missing} are not in the model ({', '.join(structure)})")
    return {c: structure[c] for c in wanted}


def check_options(options: Mapping[str, Any] | None, allowed: tuple[str, ...],
                  method: str) -> dict[str, Any]:
    """A method's keyword options: a copy without 'coefficients', unknown keys refused."""
    options = dict(options or {})
    options.pop("coefficients", None)
    unknown = [k for k in options if k not in allowed]
    if unknown:
        raise ValueError(f"unknown {method} options {unknown}; known: {', '.join(allowed)}")
    return options


def run_equation_error(
    record: FlightRecord, model: str = "lateral", options: Mapping[str, Any] | None = None
) -> list[Estimate]:
    """Equation error (OLS) for every coefficient of the model."""
    from flightid.identification import equation_error

    structure = _restrict(parse_model(model), options or {})
    kw = check_options(options, ("bias", "reference", "colored"), "equation-error")
    return [equation_error.estimate(record, c, t, **kw) for c, t in structure.items()]


def run_stepwise(
    record: FlightRecord, model: str = "lateral", options: Mapping[str, Any] | None = None
) -> list[Estimate]:
    """Stepwise regression per coefficient over linear terms, squares and products."""
    from flightid.identification import stepwise

    structure = _restrict(parse_model(model), options or {})
    kw = check_options(options, ("f_in", "f_out", "min_r2_gain", "reference", "colored",
                                 "order"), "stepwise")
    order = kw.pop("order", 2)
    return [
        stepwise.estimate(record, c, stepwise.candidate_terms(t, order), **kw)
        for c, t in structure.items()
    ]


def run_output_error(
    record: FlightRecord, model: str = "lateral", options: Mapping[str, Any] | None = None
) -> list[Estimate]:
    """Output error (maximum likelihood) on a linear model preset: lateral, longitudinal,
    short_period; or on the nonlinear 6-DOF equations: 6dof (body-axis forces CX CY CZ),
    6dof_stability (lift and drag)."""
    from flightid.identification import output_error

    if model in ("6dof", "6dof_stability"):
        from flightid.identification import nonlinear_6dof

        return [nonlinear_6dof.run(record, model, options)]
    return [output_error.run(record, model, options)]


METHODS: dict[str, Callable[[FlightRecord, str, Mapping[str, Any] | None], list[Estimate]]] = {
    "ee": run_equation_error,
    "swr": run_stepwise,
    "oe": run_output_error,
    "fem": lambda record, model, options: [_filter_error().run(record, model, options)],
    "fdee": lambda record, model, options: _frequency_domain().run_fdee(record, model, options),
    "fdoe": lambda record, model, options: _frequency_domain().run_fdoe(record, model, options),
    "fr": lambda record, model, options: _frequency_domain().run_fr(record, model, options),
}


def _frequency_domain():
    """The frequency-domain module (fdee, fdoe, fr), imported on first use."""
    from flightid.identification import frequency_domain

    return frequency_domain


def _filter_error():
    """The filter-error module, imported on first use (scipy Riccati solvers are heavy)."""
    from flightid.identification import filter_error

    return filter_error


def parse_options(texts: list[str]) -> dict[str, Any]:
    """{key: value} from 'key=value' texts; values read as JSON where they parse (true,
    3, 0.5, ["a"]), else kept as strings."""
    import json

    out: dict[str, Any] = {}
    for text in texts:
        key, sep, value = text.partition("=")
        if not sep or not key.strip():
            raise ValueError(f"option {text!r}: expected KEY=VALUE")
        try:
            out[key.strip()] = json.loads(value)
        except json.JSONDecodeError:
            out[key.strip()] = value
    return out


MODEL_ALIASES = {"lon": "longitudinal", "lat": "lateral"}


def identify(
    record: FlightRecord, method: str, model: str = "lateral",
    options: Mapping[str, Any] | None = None,
) -> list[Estimate]:
    """Run the named method (a key of METHODS) and return its estimates as a list."""
    model = MODEL_ALIASES.get(model, model)
    try:
        run = METHODS[method]
    except KeyError:
        raise ValueError(f"unknown method {method!r}; known: {', '.join(METHODS)}") from None
    result = run(record, model, options)
    return [result] if isinstance(result, Estimate) else list(result)


def run_cli(
    path: str, method: str, model: str, coefficients: list[str], truth: str | None, fmt: str,
    report: str | None = None, option_texts: list[str] | None = None,
    multistep_inputs: list[str] | None = None,
) -> None:
    """The ``flightid identify`` command: read, identify, print a table or JSON, score."""
    import json

    from rich.console import Console
    from rich.table import Table

    from flightid.identification.scoring import load_truth, score
    from flightid.record import read

    if fmt not in ("table", "json"):
        raise SystemExit(f"--format must be table or json, got {fmt!r}")
    record = read(path)
    options = parse_options(option_texts or [])
    if multistep_inputs and method == "oe":  # levels and edges estimated with the derivatives
        options["multistep_inputs"] = list(multistep_inputs)
    elif multistep_inputs:  # regression takes the denoised samples
        from flightid.identification.input_denoising import denoise_channels

        record = denoise_channels(record, multistep_inputs)
    if coefficients:
        options["coefficients"] = coefficients
    estimates = identify(record, method, model, options)
    truth_values = load_truth(truth) if truth else None
    scored = score(estimates, truth_values) if truth_values else None
    if report:
        from flightid.identification.report import write_html

        write_html(report, f"flightid identify {path} --method {method} --model {model}",
                   estimates, truth_values, notes=[scored.verdict] if scored else [])
    if fmt == "json":
        out: dict[str, Any] = {"estimates": {}, "fit": {}, "unidentifiable": {}}
        for est in estimates:
            d = est.as_dict()
            out["estimates"].update(d["estimates"])
            out["unidentifiable"].update(d["unidentifiable"])
            key = est.fit.get("coefficient", est.method)
            out["fit"][key] = {k: v for k, v in d["fit"].items() if k != "steps"}
            if "steps" in d["fit"]:
                out["fit"][key]["steps"] = d["fit"]["steps"]
        if scored is not None:
            out["score"] = scored.as_dict()
        print(json.dumps(out, indent=2, default=str))
        return
    console = Console()
    for est in estimates:
        coef = est.fit.get("coefficient", "")
        r2 = 100 * est.fit.get("R2", float("nan"))
        table = Table(title=f"{est.method} {coef}  R^2 {r2:.2f} %  std: {est.fit.get('std_kind')}")
        for col in ("parameter", "value", "std", "|value|/std"):
            table.add_column(col, justify="left" if col == "parameter" else "right")
        for name, value, std in zip(est.names, est.values, est.std, strict=True):
            ratio = abs(value) / std if std > 0 else float("inf")
            table.add_row(name, f"{value:.5g}", f"{std:.3g}", f"{ratio:.1f}")
        for name, reason in est.unidentifiable.items():
            table.add_row(name, "unidentifiable", reason, "", style="yellow")
        console.print(table)
        for step in est.fit.get("steps", []):
            console.print(f"  {step['action']:>6} {step['term']}: {step['why']}")
    if scored is not None:
        scored.print(console)
