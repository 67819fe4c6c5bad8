"""Two other forms of the window test, measured on stored flights and not adopted
(docs/gap_benchmark.md, the rules for the seed-8 run): the joint multivariate Wald test
over an axis's tested channels, and the partial test with fewer nuisance channels.

    .venv/bin/python benchmarks/gap_window_calibration.py fly --seed 0 --nulls 100 \
        --kinds single,null -o study/calibration
    .venv/bin/python benchmarks/gap_window_joint.py -o study/joint.jsonl study/calibration/*.pkl

Per stored case (``gap_window_calibration.py fly``: the base window fits of each axis) and
axis, one line: the joint statistic, its chi-square and calibrated p, the Satterthwaite
scale; per channel the plain share (no nuisance), the partial share and p of the present
test, and the partial share and p with only the flow angle (``vane``) or the flow angle and
the acceleration (``vane+acc``) as nuisance.

The joint test: the high-passed residuals V (N, m) of the tested channels, each scaled to
unit variance, regressed on the input regressors X (N, k): Theta = (X^T X)^-1 X^T V (with
the same regressors for every channel seemingly-unrelated regression is OLS; Zellner 1962).
W = vec(Theta)^T C^-1 vec(Theta), m k degrees of freedom, C the colored cross-channel
covariance of Morelli & Klein 2016 eq. 6.54 with the leverage correction of
``engine.bounds.colored_residual_covariance`` (block-diagonal regressors: the leverage is
one scalar per frequency), calibrated on the window test's surrogates (``scaled_chi2_p``)
where its chi-square p is below 1e-3 and some channel's plain share is at least 0.003.
"""

from __future__ import annotations

import argparse
import json
import pickle
import sys
import time
from pathlib import Path

import numpy as np
from scipy import stats
from threadpoolctl import threadpool_limits

from flightid.identification.engine.bounds import MAX_LEVERAGE
from flightid.identification.gap import verdict
from flightid.identification.gap.window import regressors as window
from flightid.identification.gap.window.surrogates import (
    rolled,
    scaled_chi2_p,
    surrogate_shifts,
)

VANES = {"beta", "alpha"}
NUISANCE = {"all": None, "vane": VANES, "vane+acc": VANES | {"ay", "az"}}


class Inputs(dict):
    """The input channels of one window (as ``gap_window_calibration.py`` stored them)."""

    time: np.ndarray


def joint_statistic(v: np.ndarray, x: np.ndarray) -> tuple[float, int]:
    """(W, degrees of freedom) of the joint test of ``v`` (N, m) on ``x`` (N, k)."""
    n, m = v.shape
    k = x.shape[1]
    inv = np.linalg.inv(x.T @ x)
    theta = inv @ (x.T @ v)
    e = v - x @ theta
    size = int(2 ** np.ceil(np.log2(2 * n)))
    fx = np.fft.rfft(x, n=size, axis=0)
    fe = np.fft.rfft(e, n=size, axis=0)
    h = np.sum((fx @ inv) * np.conj(fx), axis=1).real / n
    fe = fe / (1.0 - np.clip(h, 0.0, MAX_LEVERAGE))[:, None]
    w = (np.conj(fe)[:, :, None] * fx[:, None, :]).reshape(fe.shape[0], m * k)
    factor = np.full(w.shape[0], 2.0)
    factor[0] = 1.0
    if size % 2 == 0:
        factor[-1] = 1.0
    middle = (np.conj(w).T @ (factor[:, None] * w)).real / (size * n)
    big = np.kron(np.eye(m), inv)
    cov = big @ middle @ big
    t = theta.T.reshape(-1)
    return float(t @ np.linalg.pinv(0.5 * (cov + cov.T)) @ t), m * k


def axis_row(fits, chans, inputs) -> dict:
    labels = [k for k in fits if k in chans]
    dts = [float(np.median(np.diff(fits[k].time))) for k in labels]
    xs = [window.highpass(window.regressors(fits[k], chans[k], inputs), dt)
          for k, dt in zip(labels, dts, strict=True)]
    x_all = np.vstack(xs)
    scale = np.sqrt(np.sum(x_all * x_all, axis=0))
    keep = scale > 1e-12 * max(float(scale.max(initial=0.0)), 1e-300)
    cols = window.independent_index(x_all[:, keep] / scale[keep])

    def design(x: np.ndarray) -> np.ndarray:
        return (x[:, keep] / scale[keep])[:, cols]

    hp = {c: [window.highpass(fits[k].residual[c] - np.mean(fits[k].residual[c]), dt)
              for k, dt in zip(labels, dts, strict=True)] for c in fits[labels[0]].residual}
    blocks = window.nuisance_blocks(hp, dts)
    tested = {c: np.concatenate(hp[c]) for c in blocks if c not in verdict.SLOW_CHANNELS}
    channels = {}
    for c, v in tested.items():
        spread = sum(float(np.sum((fits[k].measured[c] - np.mean(fits[k].measured[c])) ** 2))
                     for k in labels)
        row = {"plain_share": verdict.channel_test(v, x_all, spread, c).share}
        for name, kept in NUISANCE.items():
            sub = {o: b for o, b in blocks.items() if kept is None or o in kept or o == c}
            t = verdict.channel_test(v, x_all, spread, c,
                                     window.other_outputs(hp, c, dts, sub))
            row[name] = {"p": t.p_value, "share": t.share}
        channels[c] = row
    v = np.column_stack([tested[c] / np.std(tested[c]) for c in tested])
    w, dof = joint_statistic(v, design(x_all))
    p = float(stats.chi2.sf(w, dof))
    out = {"w": w, "dof": dof, "p": p, "calibrated_p": p, "channels": channels}
    if p < 1e-3 and max(r["plain_share"] for r in channels.values()) >= 0.003:
        shifts = surrogate_shifts([x.shape[0] for x in xs], dts)
        ws = [joint_statistic(v, design(rolled(xs, row)))[0] for row in shifts]
        out["calibrated_p"] = scaled_chi2_p(w, ws, p)
        out["satterthwaite_c"] = float(np.var(ws, ddof=1) / (2 * np.mean(ws)))
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("flights", nargs="+", type=Path)
    ap.add_argument("-o", "--output", type=Path, required=True)
    a = ap.parse_args()
    sys.modules["__main__"].Inputs = Inputs  # the stored windows' class
    with threadpool_limits(1), open(a.output, "a") as f:
        for path in a.flights:
            with open(path, "rb") as g:
                d = pickle.load(g)
            t0 = time.process_time()
            axes = {ax: axis_row(*fits) for ax, fits in d["axes"].items()}
            f.write(json.dumps({"case": path.stem, "c": d["case"], "axes": axes,
                                "cpu": time.process_time() - t0}) + "\n")
            f.flush()


if __name__ == "__main__":
    main()
