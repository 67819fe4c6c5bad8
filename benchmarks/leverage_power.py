"""Output error's colored-residual bounds against the scatter, for each power of the leverage
correction, on development realizations of a card.

Each realization is flown and identified as ``flightid montecarlo`` does it (realization i
of base seed S flies ``sub_seed(S, "montecarlo:i")``; standard data reduction, output error,
every option at its default). The fit's sensitivities, residuals and noise covariance are
kept as ``engine.results`` hands them to ``engine.bounds``, and the bounds are computed
again from the same residuals with each power p of the correction: the whitened residual
power of frequency bin f divided by (I - H_f)^p (p = 1: HC2, p = 2: HC3; MacKinnon & White
1985, Long & Ervin 2000). Per derivative: rms bound / rms error over the realizations and
the share within 1.96 bounds. Also printed: the leverage-weighted flatness of the residual
spectrum, rho = (sum_f H_f u_f / sum_f H_f) / mean_f u_f with u_f the bin's power restored
by HC2 (1 for a white residual, larger when the residual's power sits where the parameters
take a large share of the bin).

    python benchmarks/leverage_power.py --card twinotter-lateral-0alpha --seed 9100 --n 100
    python benchmarks/leverage_power.py --card navion-demo --seed 9200 --n 100
    python benchmarks/leverage_power.py --card navion-demo --seed 9200 --n 40 --model lon

Writes benchmarks/results/leverage_power-CARD-SEED[-lon].txt. Development seeds only
(docs/validation.md, "Choosing the leverage correction").
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

import flightid.identification.engine.results as fit_results
from flightid.identification.data.reduction import standard_reduction
from flightid.identification.engine.bounds import MAX_LEVERAGE
from flightid.identification.evaluation.scoring import record_truth, score
from flightid.identification.identify import identify
from flightid.scenarios.cards import fly_card, load_card
from flightid.scenarios.montecarlo.study import Study

RESULTS = Path(__file__).parent / "results"


def _spectra(sens: np.ndarray, residuals: np.ndarray, noise: np.ndarray,
             information: np.ndarray) -> dict:
    """The FFTs and per-bin leverage that ``engine.bounds.colored_residual_covariance``
    forms, kept so that every power reuses them."""
    n = residuals.shape[0]
    size = int(2 ** np.ceil(np.log2(2 * n)))
    root = np.linalg.cholesky(np.linalg.inv(noise)).T
    fa = np.fft.rfft(np.matmul(root, sens), n=size, axis=0)
    fe = np.fft.rfft(residuals @ root.T, n=size, axis=0)[:, :, None]
    inv = np.linalg.inv(information)
    h = (fa @ inv) @ np.conj(np.swapaxes(fa, 1, 2)) / n
    vals, vecs = np.linalg.eigh(h)
    factor = np.full(fa.shape[0], 2.0)
    factor[0] = 1.0
    factor[-1] = 1.0
    return {"n": n, "size": size, "fa": fa, "fe": fe, "inv": inv, "h": h,
            "vals": np.clip(vals, 0.0, MAX_LEVERAGE), "vecs": vecs, "factor": factor}


def bounds_with_power(s: dict, power: float) -> np.ndarray:
    """Standard errors (parameter units) with the bins' residual power divided by
    (I - H_f)^power."""
    vecs = s["vecs"]
    keep = (1.0 - s["vals"]) ** (-0.5 * power)
    fe = vecs @ (keep[:, :, None] * (np.conj(np.swapaxes(vecs, 1, 2)) @ s["fe"]))
    w = (np.conj(np.swapaxes(fe, 1, 2)) @ s["fa"])[:, 0, :]
    middle = (np.conj(w).T @ (s["factor"][:, None] * w)).real / (s["size"] * s["n"])
    cov = s["inv"] @ middle @ s["inv"]
    return np.sqrt(np.clip(np.diag(cov), 0.0, None))


def flatness(s: dict) -> float:
    """rho: the HC2-restored residual power where the fit takes its share, over its mean."""
    hd = np.clip(np.real(np.einsum("fjj->fj", s["h"])), 0.0, MAX_LEVERAGE)
    u = np.abs(s["fe"][:, :, 0]) ** 2 / (1.0 - hd)
    w = s["factor"][:, None]
    return float(np.sum(w * hd * u) / np.sum(w * hd) / (np.sum(w * u) / np.sum(w)))


def realization(study: Study, index: int, powers: list[float]) -> tuple:
    """(names, errors, {power: bounds}, rho) of one realization's output-error fit."""
    kept: dict = {}
    plain = fit_results.output_error_covariance

    def keeping(information, sens, residuals, noise, colored, *rest):
        kept.update(information=information, sens=sens, residuals=residuals, noise=noise)
        return plain(information, sens, residuals, noise, colored, *rest)

    card = load_card(study.card)
    measured, truth_record = fly_card(card, study.realization_seed(index, card))
    record = standard_reduction(measured, False).record
    fit_results.output_error_covariance = keeping
    try:
        est = identify(record, "oe", study.model)
    finally:
        fit_results.output_error_covariance = plain
    rows = {r.name: r for r in score(est, record_truth(truth_record)).rows
            if r.error is not None}
    names = [n for n in est.names if n in rows]
    idx = [list(est.names).index(n) for n in names]
    s = _spectra(kept["sens"], kept["residuals"], kept["noise"], kept["information"])
    errors = np.array([rows[n].error for n in names])
    return names, errors, {p: bounds_with_power(s, p)[idx] for p in powers}, flatness(s)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--card", default="twinotter-lateral-0alpha")
    parser.add_argument("--seed", type=int, default=9100)
    parser.add_argument("--n", type=int, default=100)
    parser.add_argument("--model", default="lat", help="lat or lon, as for identify")
    parser.add_argument("--powers", default="1,1.25,1.5,1.75,2")
    args = parser.parse_args()
    powers = [float(p) for p in args.powers.split(",")]
    study = Study(args.card, args.n, model=args.model, seed=args.seed)
    errors, bounds, rhos = [], {p: [] for p in powers}, []
    with threadpool_limits(1):
        for i in range(args.n):
            names, err, by_power, rho = realization(study, i, powers)
            errors.append(err)
            rhos.append(rho)
            for p in powers:
                bounds[p].append(by_power[p])
    err = np.array(errors)
    rms_error = np.sqrt(np.mean(err ** 2, axis=0))
    lines = [f"python benchmarks/leverage_power.py --card {args.card} --seed {args.seed} "
             f"--n {args.n} --model {args.model}: output error, {len(err)} realizations",
             "rms bound / rms error (share within 1.96 bounds), per power p of (I - H_f)",
             " " * 8 + "".join(f"{f'p = {p:g}':>16}" for p in powers)]
    for j, name in enumerate(names):
        row = f"{name:<8}"
        for p in powers:
            b = np.array(bounds[p])[:, j]
            inside = np.mean(np.abs(err[:, j]) <= 1.96 * b)
            ratio = np.sqrt(np.mean(b ** 2)) / rms_error[j]
            row += f"{ratio:9.2f} ({100 * inside:3.0f} %)"
        lines.append(row)
    pooled = [100 * np.mean(np.abs(err) <= 1.96 * np.array(bounds[p])) for p in powers]
    lines.append(f"{'pooled':<8}" + "".join(f"{f'{c:.1f} %':>16}" for c in pooled))
    lines.append(f"flatness rho: min {min(rhos):.2f}, median {float(np.median(rhos)):.2f}, "
                 f"max {max(rhos):.2f}")
    text = "\n".join(lines) + "\n"
    print(text, end="")
    RESULTS.mkdir(exist_ok=True)
    suffix = "" if args.model == "lat" else f"-{args.model}"
    (RESULTS / f"leverage_power-{args.card}-{args.seed}{suffix}.txt").write_text(
        text, encoding="utf-8")


if __name__ == "__main__":
    main()
