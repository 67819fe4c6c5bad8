"""Reading a tlog (``flightid.sim.bridge.ground.tlog``) loads nothing of the air side: a ground
station converts recordings without the simulator's streaming, scheduling or links."""

from __future__ import annotations

import subprocess
import sys

# the air side's package, and the modules of streaming and links outside it
AIR_SIDE = ("flightid.sim.bridge.air", "flightid.sim.bridge.link",
            "flightid.sim.bridge.ground.recording", "flightid.sim.bridge.loopback")


def test_reading_a_tlog_imports_no_air_side():
    code = ("import sys, flightid.sim.bridge.ground.tlog\n"
            f"print(sorted(m for m in sys.modules if m.startswith({AIR_SIDE!r})))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "[]", out.stdout
