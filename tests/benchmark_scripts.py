"""The scripts of benchmarks/ as modules, for the tests of their non-timing parts."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import ModuleType

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


def load(name: str) -> ModuleType:
    """The script ``benchmarks/<name>.py`` as a module (its ``__main__`` part not run).

    Parameters
    ----------
    name : str
        The script's name without ``.py``.

    Returns
    -------
    types.ModuleType
        The loaded module.
    """
    spec = importlib.util.spec_from_file_location(name, BENCHMARKS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
