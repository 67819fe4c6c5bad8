"""Reading a tlog (``flightid.sim.bridge.tlog``) loads nothing of the air side: a ground
station converts recordings without the simulator's streaming, scheduling or links."""

from __future__ import annotations

import subprocess
import sys

AIR_SIDE = ("air", "schedule", "signing", "link", "recording", "loopback")


def test_reading_a_tlog_imports_no_air_side():
    code = ("import sys, flightid.sim.bridge.tlog\n"
            f"print(sorted(m for m in sys.modules if m.startswith('flightid.sim.bridge.') "
            f"and m.rsplit('.', 1)[1] in {AIR_SIDE!r}))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "[]", out.stdout
