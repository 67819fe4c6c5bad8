"""The window test's null level, measured: blind-check cases flown again from their seeds
and the test of the model as is (``verdict.null_test`` on the base fits of ``gap.fit``)
computed on each diagnosed axis, stored per case so that variants of the test can be
compared on the same flights (docs/gap_benchmark.md, the rules for the seed-6 run).

    .venv/bin/python benchmarks/gap_window_calibration.py fly --seed 0 --nulls 100 \
        --kinds single -o study/calibration
    .venv/bin/python benchmarks/gap_window_calibration.py surrogates -o study/calibration
    .venv/bin/python benchmarks/gap_window_calibration.py variants -o study/calibration

    .venv/bin/python benchmarks/gap_window_calibration.py rules -o study/calibration

``fly`` stores one pickle per case (the axis's window fits and input channels);
``surrogates`` adds one line per case and axis to ``surrogates.jsonl`` (each channel's
tests, and the statistic on 100 surrogates where the chi-square p is below 0.01, 1e-4 in
the high band); ``variants`` prints, per seed and category, the cases with a gap on an
axis (null cases) or on the effect's axis (drawn cases) under each variant of the test
(the seed-6 rules' development); ``rules`` the same under the present ``verdict.null_test``
(the seed-7 rules' development: docs/gap_benchmark.md).
"""

from __future__ import annotations

import argparse
import json
import pickle
import time
from pathlib import Path

import numpy as np
from scipy import stats
from threadpoolctl import threadpool_limits

from flightid.identification.data.axes import AXIS_INPUTS, excited_axes
from flightid.identification.gap import verdict
from flightid.identification.gap.model.linearise import linearise
from flightid.identification.gap.model.surfaces import actuated
from flightid.identification.gap.rank import Folds, Ranker
from flightid.identification.gap.segments import segments, split
from flightid.identification.gap.window import regressors as window
from flightid.scenarios.gap_benchmark.cases import draw
from flightid.scenarios.gap_benchmark.run import fly_case, truths


class Inputs(dict):
    """The input channels of one window, as ``null_test`` reads a record."""

    time: np.ndarray


def axis_fits(record, aircraft: str, axis: str) -> tuple[dict, dict, tuple[str, ...]]:
    """The base window fits, the windows' inputs and the axis's inputs, as ``diagnose``."""
    inputs = AXIS_INPUTS[axis]
    lin = linearise(aircraft, [record], axis, None)
    windows = segments([record], None, inputs)
    if len(windows) == 1 and len(halves := split(windows[0])) == 2:
        windows = halves
    ranker = Ranker(lin, Folds.make(windows, None))
    chans = {}
    for s in windows:
        d = Inputs({c: np.asarray(s.record[c]) for c in inputs if c in s.record})
        d.time = np.asarray(s.record.time)
        chans[s.label] = d
    return ranker.base, chans, inputs


def fly(seed: int, nulls: int, kinds: set[str], n: int, out: Path) -> None:
    t = truths()
    cases = draw(n, seed, t, nulls)
    out.mkdir(parents=True, exist_ok=True)
    for case in cases:
        if case.category not in kinds:
            continue
        path = out / f"s{seed}_{case.index}.pkl"
        if path.exists():
            continue
        t0 = time.process_time()
        try:
            record = actuated([fly_case(case, "light", t.get(case.aircraft))], case.aircraft,
                              None)[0]
            axes = {a: axis_fits(record, case.aircraft, a) for a in excited_axes([record])}
        except Exception as exc:  # noqa: BLE001  (a departure, a failed trim: listed)
            print(f"seed {seed} case {case.index}: {type(exc).__name__}: {exc}")
            continue
        with open(path, "wb") as f:
            pickle.dump({"case": case.to_json(), "axes": axes}, f)
        print(f"seed {seed} case {case.index} {case.aircraft} {case.category} "
              f"{time.process_time() - t0:.1f} s", flush=True)


# the variants of docs/gap_benchmark.md (the rules for the seed-6 run): main: "satt" for
# the calibrated p (scaled chi-square), "cons": never below the chi-square p, "focused":
# the seed-5 rules' focused test at that MODEL_MATERIAL, "alpha", "drop": channels left out
VARIANTS = {
    "seed-5 rules": {"focused": 0.02},
    "focused dropped": {},
    "focused at 0.05": {"focused": 0.05},
    "calibrated (the seed-6 rules)": {"main": "satt", "high": "satt"},
    "calibrated, ALPHA 2e-4": {"main": "satt", "high": "satt", "alpha": 2e-4},
    "calibrated without floor, ALPHA 2e-4": {"main": "satt", "high": "satt", "alpha": 2e-4,
                                             "cons": False},
    "calibrated, phi left out": {"main": "satt", "high": "satt", "drop": ("phi",)},
}


def satterthwaite_p(w: float, ws: list[float]) -> float:
    """p of ``w`` against c chi2(nu) matched to the surrogates ``ws``."""
    m, var = float(np.mean(ws)), float(np.var(ws, ddof=1))
    return float(stats.chi2.sf(w / (var / (2 * m)), 2 * m * m / var))


def channel_gap(r: dict, v: dict) -> bool:
    """One channel's gap under the variant ``v``."""
    if not r["slow"]:
        p = r["p"]
        if v.get("main") and r["ws"]:
            pc = satterthwaite_p(r["w"], r["ws"])
            p = max(p, pc) if v.get("cons", True) else pc
        if p < v.get("alpha", verdict.ALPHA) and r["share"] >= verdict.MATERIAL:
            return True
        f = v.get("focused")
        if f is not None and r["focused"][0] < 3e-3 and r["focused"][1] >= f:
            return True
    hp, he = r["high"]
    if v.get("high") and r["high_ws"]:
        hp = max(hp, satterthwaite_p(r["high_w"], r["high_ws"]))
    return hp < verdict.HIGH_ALPHA and he >= verdict.HIGH_MATERIAL


def counts(rows: list[dict], v: dict) -> dict[str, str]:
    """Per seed and category: cases with a gap (null: any axis; drawn: the effect's axis)
    of those measured."""
    by: dict[str, dict] = {}
    for row in rows:
        by.setdefault(row["case"], {})[row["axis"]] = row
    seen: dict[str, list[int]] = {}
    for case, axes in by.items():
        first = next(iter(axes.values()))
        if first["category"] == "null":
            want = set(axes)
        else:
            want = {e["axis"] for e in first["effects"]}
            want = set(axes) if "both" in want else want & set(axes)
        gap = any(channel_gap(r, v) for a in want
                  for c, r in axes[a]["channels"].items() if c not in v.get("drop", ()))
        key = f"{case.split('_')[0]} {first['category']}"
        seen.setdefault(key, [0, 0])
        seen[key][0] += int(gap)
        seen[key][1] += 1
    return {k: f"{g} of {n}" for k, (g, n) in sorted(seen.items())}


def tests(out: Path):
    for path in sorted(out.glob("*.pkl")):
        with open(path, "rb") as f:
            d = pickle.load(f)
        yield path.stem, d


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("what", choices=("fly", "surrogates", "variants", "rules"))
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--nulls", type=int, default=100)
    ap.add_argument("--n", type=int, default=150)
    ap.add_argument("--kinds", default="null")
    ap.add_argument("-o", "--output", type=Path, required=True)
    a = ap.parse_args()
    with threadpool_limits(1):
        if a.what == "fly":
            fly(a.seed, a.nulls, set(a.kinds.split(",")), a.n, a.output)
            return
        if a.what == "rules":
            present_rules(a.output)
            return
        if a.what == "surrogates":
            done = a.output / "surrogates.jsonl"
            seen = ({json.loads(x)["case"] for x in done.read_text().splitlines()}
                    if done.exists() else set())
            with open(done, "a") as f:
                for name, d in tests(a.output):
                    if name in seen:
                        continue
                    for axis, (fits, chans, inputs) in d["axes"].items():
                        t0 = time.process_time()
                        rows = surrogate_rows(fits, chans, inputs)
                        f.write(json.dumps({"case": name, "category": d["case"]["category"],
                                            "aircraft": d["case"]["aircraft"], "axis": axis,
                                            "effects": d["case"]["effects"],
                                            "cpu": time.process_time() - t0,
                                            "channels": rows}) + "\n")
                    f.flush()
            return
        rows = [json.loads(x) for x in (a.output / "surrogates.jsonl").read_text().splitlines()]
        for name, v in VARIANTS.items():
            print(name, counts(rows, v))




def present_rules(out: Path) -> None:
    """Per seed and category: the stored cases with a gap (null: any axis; drawn: the
    effect's axis) under the present ``verdict.null_test``, and the null cases' channels."""
    seen: dict[str, list[int]] = {}
    for name, d in tests(out):
        case = d["case"]
        tested = {a: verdict.null_test(*fits) for a, fits in d["axes"].items()}
        want = {e["axis"] for e in case["effects"]}
        axes = set(tested) if case["category"] == "null" or "both" in want \
            else want & set(tested)
        gap = any(tested[a].gap for a in axes)
        key = f"{name.split('_')[0]} {case['category']}"
        seen.setdefault(key, [0, 0])
        seen[key][0] += int(gap)
        seen[key][1] += 1
        if gap and case["category"] == "null":
            print(name, case["aircraft"], {a: t.gap_channels() for a, t in tested.items()})
    print({k: f"{g} of {n}" for k, (g, n) in sorted(seen.items())})


def surrogate_rows(fits, chans, inputs, b: int = 100, min_shift_s: float = 1.5, seed: int = 0,
                   main_below: float = 0.01, high_below: float = 1e-4):
    """Per channel: the observed tests (main, focused, high band) and the main (high
    band's) statistic on ``b`` surrogates where its nominal p is below ``main_below``
    (``high_below``): each window's regressors circularly shifted by at least
    ``min_shift_s`` from the residual."""
    labels = [k for k in fits if k in chans]
    dts = {k: float(np.median(np.diff(fits[k].time))) for k in labels}
    xs = [window.highpass(window.regressors(fits[k], chans[k], inputs), dts[k])
          for k in labels]
    xh = [window.fast_regressors(fits[k], chans[k], inputs) for k in labels]
    rng = np.random.default_rng(seed)
    shifts = []
    for _ in range(b):
        row = []
        for x, k in zip(xs, labels, strict=True):
            m = int(round(min_shift_s / dts[k]))
            n = x.shape[0]
            row.append(int(rng.integers(m, n - m)) if n > 2 * m else n // 2)
        shifts.append(row)

    def rolled(blocks, row):
        return np.vstack([np.roll(x, s, axis=0) for x, s in zip(blocks, row, strict=True)])

    base = verdict.null_test(fits, chans, inputs)
    xf = np.vstack([window.highpass(window.regressors(fits[k], chans[k], inputs, 1), dts[k])
                    for k in labels])  # the seed-5 rules' focused test (one filter an input)
    out = {}
    for ch, t in base.channels.items():
        raw = [fits[k].residual[ch] - np.mean(fits[k].residual[ch]) for k in labels]
        hp = t.high.chi2_p if np.isfinite(t.high.chi2_p) else t.high.p_value
        r = {"slow": t.slow, "gap": t.gap, "high": (hp, t.high.explained),
             "high_w": t.high.statistic, "high_dof": t.high.dof, "high_ws": []}
        if hp < high_below:
            hb = sum(window.band_energy(fits[k].measured[ch], dts[k], verdict.HIGH_HZ)
                     for k in labels)
            r["high_ws"] = [verdict.channel_test(np.concatenate(raw), rolled(xh, row), hb,
                                                 ch).statistic for row in shifts]
        if not t.slow:
            v = np.concatenate([window.highpass(x, dts[k]) for x, k in
                                zip(raw, labels, strict=True)])
            spread = sum(float(np.sum((fits[k].measured[ch] - np.mean(fits[k].measured[ch]))
                                      ** 2)) for k in labels)
            p = t.chi2_p if np.isfinite(t.chi2_p) else t.p_value
            driven = sum(float(np.sum((fits[k].model[ch] - np.mean(fits[k].model[ch])) ** 2))
                         for k in labels)
            f = verdict.channel_test(v, xf, spread, ch)
            r.update({"w": t.statistic, "dof": t.dof, "p": p, "share": t.share,
                      "focused": (f.p_value, f.share * spread / driven), "ws": []})
            if p < main_below:
                r["ws"] = [verdict.channel_test(v, rolled(xs, row), spread, ch).statistic
                           for row in shifts]
        out[ch] = r
    return out

if __name__ == "__main__":
    main()
