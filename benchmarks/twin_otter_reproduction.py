"""The NASA Twin Otter record (totter_f1_017) through equation error, output error and
frequency-domain output error, against the published estimates of Morelli & Klein
examples 5.1, 6.1 and 7.1 (shared/data/twin_otter/README.md).

Writes benchmarks/results/twin_otter.md: per derivative, published value (std), ours
(std), and the difference in published standard errors.
Run: python benchmarks/twin_otter_reproduction.py
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from flightid.identification.methods import equation_error, frequency_output_error, output_error
from flightid.identification.models import linear as lm
from flightid.identification.models.reference_condition import condition_from_record
from flightid.record import read

HERE = Path(__file__).resolve().parent
# the record where the tests find it (tests/conftest.py: shared/ beside the checkout, or
# FLIGHTID_SHARED)
sys.path.insert(0, str(HERE.parent / "tests"))
from conftest import TWIN_OTTER as RECORD  # noqa: E402

# (value, std) from the record's README (stability axes, per rad)
PUBLISHED = {
    "ee": {
        "CY_beta": (-0.8451, 0.0074), "CY_r": (0.9631, 0.0553), "CY_dr": (0.3426, 0.0290),
        "Cl_beta": (-0.10513, 0.00254), "Cl_p": (-0.5283, 0.0099), "Cl_r": (0.1926, 0.0083),
        "Cl_da": (-0.2117, 0.0034), "Cl_dr": (0.0299, 0.0039),
        "Cn_beta": (0.08544, 0.00036), "Cn_p": (-0.05151, 0.00143), "Cn_r": (-0.19758, 0.00130),
        "Cn_da": (0.00234, 0.00050), "Cn_dr": (-0.13054, 0.00060),
    },
    "oe": {
        "CY_beta": (-0.8646, 0.0028), "CY_r": (0.9331, 0.0167), "CY_dr": (0.3800, 0.0081),
        "Cl_beta": (-0.11959, 0.00061), "Cl_p": (-0.5859, 0.0026), "Cl_r": (0.1889, 0.0018),
        "Cl_da": (-0.2282, 0.0009), "Cl_dr": (0.0422, 0.0007),
        "Cn_beta": (0.08638, 0.00021), "Cn_p": (-0.06441, 0.00098), "Cn_r": (-0.19059, 0.00062),
        "Cn_da": (-0.00298, 0.00036), "Cn_dr": (-0.13548, 0.00027),
    },
    "fdoe": {
        "CY_beta": (-0.8608, 0.0071), "CY_r": (0.8888, 0.0439), "CY_dr": (0.3417, 0.0217),
        "Cl_beta": (-0.11979, 0.00092), "Cl_p": (-0.5929, 0.0040), "Cl_r": (0.1738, 0.0029),
        "Cl_da": (-0.2330, 0.0015), "Cl_dr": (0.0261, 0.0014),
        "Cn_beta": (0.08547, 0.00055), "Cn_p": (-0.06610, 0.00253), "Cn_r": (-0.19329, 0.00169),
        "Cn_da": (-0.00364, 0.00094), "Cn_dr": (-0.13737, 0.00077),
    },
}
TITLES = {"ee": "equation error (example 5.1)", "oe": "output error (example 6.1)",
          "fdoe": "frequency-domain output error, 0.1-1.5 Hz (example 7.1)"}


def estimates(record):
    """{method: (Estimate-like {name: (value, std)}, seconds)} for the three methods."""
    out = {}
    t = time.perf_counter()
    ee = {}
    for coef, regs in (("CY", ["beta", "rhat", "dr"]),
                       ("Cl", ["beta", "phat", "rhat", "da", "dr"]),
                       ("Cn", ["beta", "phat", "rhat", "da", "dr"])):
        est = equation_error.estimate(record, coef, regs, colored=coef != "Cn")
        ee.update({n: (est[n], est.std_of(n)) for n in est.names if n in PUBLISHED["ee"]})
    out["ee"] = (ee, time.perf_counter() - t)
    model = lm.lateral(condition_from_record(record))
    t = time.perf_counter()
    est = output_error.estimate(record, model, start="equation_error")
    out["oe"] = ({n: (est[n], est.std_of(n)) for n in est.names if n in PUBLISHED["oe"]},
                 time.perf_counter() - t)
    t = time.perf_counter()
    est = frequency_output_error.run(record, "lateral")
    out["fdoe"] = ({n: (est[n], est.std_of(n)) for n in est.names if n in PUBLISHED["fdoe"]},
                   time.perf_counter() - t)
    return out


def main() -> int:
    record = read(RECORD)
    lines = ["# NASA Twin Otter record totter_f1_017: flightid vs the published estimates", "",
             "Morelli & Klein (2016) examples 5.1, 6.1, 7.1; values per rad, stability axes;",
             "'diff/std' is (ours - published) / published standard error.", ""]
    for method, (ours, seconds) in estimates(record).items():
        lines += [f"## {TITLES[method]} ({seconds:.2f} s)", "",
                  "| derivative | published (std) | flightid (std) | diff/std | rel. diff |",
                  "|---|---|---|---|---|"]
        worst = 0.0
        for name, (pv, ps) in PUBLISHED[method].items():
            v, s = ours[name]
            z = (v - pv) / ps
            worst = max(worst, abs(z))
            lines.append(f"| {name} | {pv:.5g} ({ps:.2g}) | {v:.5g} ({s:.2g}) | {z:+.2f} | "
                         f"{100 * (v - pv) / abs(pv):+.2f} % |")
        lines += ["", f"largest difference: {worst:.2f} published standard errors", ""]
    out = HERE / "results" / "twin_otter.md"
    out.parent.mkdir(exist_ok=True)
    out.write_text("\n".join(lines))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
