"""Wall time of the main job, `flightid demo`, as a user runs it (a fresh process).

Writes benchmarks/results/demo.txt (best and median of N runs; the target is < 60 s).
Run: python benchmarks/bench_demo.py [N]
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import tempfile
import time
from datetime import date
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results" / "demo.txt"


def main(runs: int = 3) -> str:
    """Time ``flightid demo`` ``runs`` times in fresh processes; write and return the text."""
    times = []
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(runs):
            t = time.perf_counter()
            subprocess.run([sys.executable, "-m", "flightid.cli.app", "demo", "--report",
                            str(Path(tmp) / "demo.html")], check=True, capture_output=True)
            times.append(time.perf_counter() - t)
    text = (f"flightid demo (navion-demo card, output error, HTML report), {date.today()}\n"
            f"python {sys.version.split()[0]}; {runs} runs in fresh processes, wall time\n"
            f"best {min(times):.1f} s, median {statistics.median(times):.1f} s, "
            f"worst {max(times):.1f} s; target < 60 s: "
            f"{'met' if max(times) < 60 else 'NOT met'}\n")
    RESULTS.parent.mkdir(exist_ok=True)
    RESULTS.write_text(text)
    return text


if __name__ == "__main__":
    print(main(int(sys.argv[1]) if len(sys.argv) > 1 else 3))
