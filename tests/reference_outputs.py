"""The reference outputs that a change of layout must leave bit-identical.

Three sets of numbers, each ``{case: {"names": [...], "values": [hex], "std": [hex]}}``
with every float stored exactly (``float.hex``):

- ``contract``: every registered method on the method contract's record (the Navion demo
  card, seed 5, window 12-32 s, the method's contract model), as
  ``flightid.testing.MethodContract`` computes it;
- ``demo``: the two output-error estimates of ``flightid demo`` (seed 1);
- ``twin_otter``: the NASA Twin Otter record through equation error (CY, Cl, Cn), output
  error from the equation-error start and frequency-domain output error, as
  benchmarks/twin_otter_reproduction.py computes them.

``python -m tests.reference_outputs`` (from the checkout) rewrites tests/reference_outputs.json;
only do so for a change that is meant to change the numbers, and say so in the commit message.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from flightid.identification.estimate import Estimate
from flightid.identification.methods import (
    equation_error,
    frequency_output_error,
    output_error,
    registry,
)
from flightid.identification.models import linear as lm
from flightid.identification.models.reference_condition import condition_from_record
from flightid.record import read
from flightid.scenarios import demo
from flightid.scenarios.cards import fly_card, load_card
from flightid.testing import MethodContract, contract_record
from tests.conftest import TWIN_OTTER

HERE = Path(__file__).resolve().parent
SAVED = HERE / "reference_outputs.json"
DEMO_SEED = 1
# the lateral equation-error regressors of Morelli & Klein example 5.1
TWIN_OTTER_EE = (("CY", ("beta", "rhat", "dr")), ("Cl", ("beta", "phat", "rhat", "da", "dr")),
                 ("Cn", ("beta", "phat", "rhat", "da", "dr")))


def numbers(est: Estimate) -> dict[str, list[str]]:
    """An estimate's names, values and standard errors, the floats as exact hex strings."""
    return {"names": list(est.names),
            "values": [float(v).hex() for v in np.asarray(est.values, dtype=float)],
            "std": [float(s).hex() for s in np.asarray(est.std, dtype=float)]}


def contract() -> dict[str, dict[str, list[str]]]:
    """Every registered method on the method contract's record."""
    record = contract_record()
    return {method_id: numbers(MethodContract(method_id, record).identify())
            for method_id in sorted(registry.methods())}


def demo_estimates() -> dict[str, dict[str, list[str]]]:
    """The demo's short-period and lateral output-error estimates."""
    measured, _ = fly_card(load_card(demo.DEFAULT_CARD), DEMO_SEED)
    return {model: numbers(est) for (model, _), est in
            zip(demo.FITS, demo.identify_flight(measured), strict=True)}


def twin_otter(path: Path) -> dict[str, dict[str, list[str]]]:
    """The Twin Otter reproductions (Morelli & Klein examples 5.1, 6.1, 7.1)."""
    record = read(path)
    out = {f"ee_{coef}": numbers(equation_error.estimate(record, coef, list(regs),
                                                         colored=coef != "Cn"))
           for coef, regs in TWIN_OTTER_EE}
    model = lm.lateral(condition_from_record(record))
    out["oe"] = numbers(output_error.estimate(record, model, start="equation_error"))
    out["fdoe"] = numbers(frequency_output_error.run(record, "lateral"))
    return out


def main() -> int:
    # one BLAS thread, as under pytest (tests/conftest.py): a threaded BLAS sums in another
    # order and changes the last bits
    with threadpool_limits(limits=1, user_api="blas"):
        saved = {"contract": contract(), "demo": demo_estimates(),
                 "twin_otter": twin_otter(TWIN_OTTER)}
    SAVED.write_text(json.dumps(saved, indent=1) + "\n", encoding="utf-8")
    print(f"wrote {SAVED}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
