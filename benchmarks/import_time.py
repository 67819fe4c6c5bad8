"""Import time of ``import flightid`` and wall time of ``flightid --help`` (fresh processes).

``import flightid``: the cumulative time of the ``flightid`` line of ``python -X importtime
-c "import flightid"`` (targets: <= 0.3 s; numpy alone, measured the same way, for scale).
``flightid --help``: wall time of the console command, interpreter start included (target:
<= 0.8 s). Best and median of N runs, since other processes on a shared machine only ever
add time. The processes may write bytecode (PYTHONDONTWRITEBYTECODE unset) and one unmeasured
run of each comes first, as for an installed package, whose modules are compiled once.
Writes benchmarks/results/import_time.txt.
Run: python benchmarks/import_time.py [N]
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import time
from datetime import date
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results" / "import_time.txt"
CONSOLE = Path(sys.executable).with_name("flightid")
ENV = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}


def import_seconds(module: str) -> float:
    """The cumulative import time of ``module`` in a fresh interpreter (s), from -X importtime."""
    out = subprocess.run([sys.executable, "-X", "importtime", "-c", f"import {module}"],
                         capture_output=True, text=True, check=True, env=ENV).stderr
    line = next(r for r in reversed(out.splitlines()) if r.rstrip().endswith(f"| {module}"))
    return int(line.split("|")[1]) / 1e6


def help_seconds() -> float:
    """Wall time of ``flightid --help`` (s)."""
    t = time.perf_counter()
    subprocess.run([str(CONSOLE), "--help"], capture_output=True, check=True, env=ENV)
    return time.perf_counter() - t


def main(runs: int = 7) -> str:
    """Measure each ``runs`` times (after one unmeasured run); write and return the text."""
    import_seconds("flightid"), help_seconds()
    rows = [("import numpy (-X importtime)", [import_seconds("numpy") for _ in range(runs)]),
            ("import flightid (-X importtime)", [import_seconds("flightid") for _ in range(runs)]),
            ("flightid --help (wall)", [help_seconds() for _ in range(runs)])]
    lines = [f"import time of flightid, {date.today()}; python {sys.version.split()[0]}; "
             f"{runs} fresh processes each", "", f"{'what':34} {'best s':>7} {'median s':>9}"]
    lines += [f"{name:34} {min(v):7.3f} {statistics.median(v):9.3f}" for name, v in rows]
    text = "\n".join(lines) + "\n"
    RESULTS.parent.mkdir(exist_ok=True)
    RESULTS.write_text(text, encoding="utf-8")
    return text


if __name__ == "__main__":
    print(main(int(sys.argv[1]) if len(sys.argv) > 1 else 7), end="")
