"""The size limits of the package layout (docs/architecture.md, The tree): no module over
``MAX_LINES`` lines and no package folder with more than ``MAX_MODULES`` loose modules
(modules besides ``__init__.py``). The command line (``cli/``, one module per command) is
exempt.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

from tests.conftest import SLOW_MODULES

ROOT = Path(__file__).resolve().parent.parent
MAX_LINES = 500
MAX_MODULES = 12
EXEMPT = {"cli"}


def package_folders() -> list[Path]:
    """Every folder of the installed packages (pyproject's package-dir), sub-packages too."""
    mapping = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))[
        "tool"]["setuptools"]["package-dir"]
    out = []
    for folder in sorted(set(mapping.values())):
        top = ROOT / folder
        out += [p for p in (top, *sorted(top.rglob("*"))) if p.is_dir()
                and (p / "__init__.py").is_file() and "__pycache__" not in p.parts]
    return out


def relative(path: Path) -> str:
    return path.relative_to(ROOT).as_posix()


def exempt(folder: Path) -> bool:
    return relative(folder).split("/")[0] in EXEMPT


def test_the_package_folders_are_found():
    names = {relative(p) for p in package_folders()}
    assert {"flightid", "sim/flight", "identification/engine", "scenarios/cards"} <= names


def test_no_module_is_over_the_line_limit():
    over = {relative(m): n for folder in package_folders() if not exempt(folder)
            for m in folder.glob("*.py")
            if (n := len(m.read_text(encoding="utf-8").splitlines())) > MAX_LINES}
    assert over == {}


def test_no_folder_has_too_many_loose_modules():
    over = {relative(folder): n for folder in package_folders() if not exempt(folder)
            if (n := sum(1 for m in folder.glob("*.py") if m.name != "__init__.py"))
            > MAX_MODULES}
    assert over == {}


# test folders that check the whole package rather than one part of it
CROSS_CUTTING = {"contract", "badinput"}


def test_the_tests_mirror_the_package():
    """Every test folder below tests/ is a package folder's mirror (tests/sim/bridge holds
    the tests of sim/bridge), apart from the cross-cutting suites."""
    tests = ROOT / "tests"
    packages = {relative(p) for p in package_folders()}
    folders = {p.parent.relative_to(tests).as_posix() for p in tests.rglob("__init__.py")
               if p.parent != tests}
    strays = {f for f in folders if f not in packages and f.split("/")[0] not in CROSS_CUTTING}
    assert strays == set()


def test_every_slow_module_exists():
    """The keys of conftest's SLOW_MODULES name test modules that exist (a move that missed
    a key would silently put a slow module back into ``-m "not slow"``)."""
    missing = [m for m in SLOW_MODULES if not (ROOT / "tests" / m).is_file()]
    assert missing == []
