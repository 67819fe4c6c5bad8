"""The public API is listed once: the same names in ``flightid.__all__``, ``flightid.api``'s
``__all__`` and docstring, and docs/architecture.md; ``import flightid`` and ``flightid
--help`` load neither the simulator nor the methods (PEP 562 lazy attributes, lazy
commands), and ``import flightid`` registers the excitation environment."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import flightid
from flightid import api

ARCHITECTURE = Path(__file__).resolve().parents[2] / "docs" / "architecture.md"
HEAVY = ("flightid.api", "flightid.sim.", "flightid.identification.", "flightid.scenarios.gym.env",
         "jsbsim", "scipy", "pandas", "matplotlib", "dask")


def test_the_root_exports_the_api_and_the_version():
    assert sorted(flightid.__all__) == sorted([*api.__all__, "__version__"])
    assert {"FlightRecord", "read", "Estimate"} <= set(flightid.__all__)
    for name in api.__all__:
        assert getattr(flightid, name) is getattr(api, name), name


def test_the_api_docstring_lists_every_name_and_no_other():
    bullets = [line for line in api.__doc__.splitlines() if line.startswith("- ")]
    named = {m for line in bullets for m in re.findall(r"``(\w+)", line)}
    assert named - {"Flight", "Estimate", "Score"} <= set(api.__all__)
    assert set(api.__all__) <= named


def test_the_architecture_page_lists_the_same_names():
    line = next(r for r in ARCHITECTURE.read_text(encoding="utf-8").splitlines()
                if "public API (`flightid.__all__`)" in r)
    names = line.split("public API (`flightid.__all__`)")[1].split("(`api.py`")[0]
    listed = set(re.findall(r"`(\w+)`", names))
    assert listed == set(flightid.__all__)


def _loaded_after(code: str) -> list[str]:
    out = subprocess.run([sys.executable, "-c", code + "\nimport sys\nprint(*sys.modules)"],
                         capture_output=True, text=True, check=True).stdout.split()
    return [m for m in out if m.startswith(HEAVY)]


def test_import_flightid_registers_the_environment_and_loads_nothing_heavy():
    assert _loaded_after("import flightid, gymnasium\n"
                         "assert 'flightid/Excitation-v0' in gymnasium.registry") == []


def test_flightid_help_imports_no_command():
    code = ("import sys\nsys.argv = ['flightid', '--help']\nfrom flightid.cli import app\n"
            "try:\n    app.main()\nexcept SystemExit:\n    pass")
    assert _loaded_after(code) == []
