"""No absolute path of a particular machine in the code, tests, benchmarks or docs: data
are found relative to the checkout (tests/conftest.py: shared/ beside it, or
FLIGHTID_SHARED), scratch files in the system's temporary folder."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FOLDERS = ("flightid", "aircraft", "sim", "identification", "scenarios", "cli", "tests",
           "benchmarks", "docs", ".ci")
SUFFIXES = {".py", ".md", ".toml", ".txt", ".cfg", ".yml", ".yaml", ""}
# an absolute path into a home, scratch or workplace folder
MACHINE_PATH = re.compile(r"(?<![\w.~])/(?:work|root|home|tmp|Users)/")


def _text_files():
    yield ROOT / "README.md"
    yield ROOT / "pyproject.toml"
    for folder in FOLDERS:
        for path in (ROOT / folder).rglob("*"):
            if path.is_file() and path.suffix in SUFFIXES and "__pycache__" not in path.parts:
                yield path


def test_no_absolute_machine_path():
    hits = []
    for path in _text_files():
        text = path.read_text(encoding="utf-8", errors="replace")
        hits += [f"{path.relative_to(ROOT)}:{text.count(chr(10), 0, m.start()) + 1}"
                 for m in MACHINE_PATH.finditer(text)]
    assert not hits, f"absolute machine paths: {hits}"
