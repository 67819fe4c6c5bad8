"""Locating cards: the library folder (scenarios/library/*.toml) and card files."""

from __future__ import annotations

import tomllib
from pathlib import Path

from flightid.scenarios.cards.schema import CardError

LIBRARY = Path(__file__).resolve().parent.parent / "library"


def library_cards() -> dict[str, Path]:
    """Library card names -> paths (scenarios/library/*.toml).

    Returns
    -------
    dict[str, Path]
        Card name -> file, sorted by name.
    """
    return {p.stem: p for p in sorted(LIBRARY.glob("*.toml"))}


def find_card(name_or_path: str | Path) -> Path:
    """Path of a card given as a file path or a library card name.

    Parameters
    ----------
    name_or_path : str or Path
        A card file path or a library card name.

    Returns
    -------
    Path
        The card file.
    """
    p = Path(name_or_path)
    if p.is_file():
        return p
    lib = library_cards()
    stem = p.stem if p.suffix == ".toml" else p.name
    if str(name_or_path) == stem and stem in lib:
        return lib[stem]
    raise CardError(str(name_or_path), None, None,
                    f"no such card file, and not a library card; library cards: "
                    f"{', '.join(lib) or 'none'}")


def describe(path: Path) -> str:
    """The one-line description of a card file (without validating it).

    Parameters
    ----------
    path : Path
        Card file.

    Returns
    -------
    str
        The ``description`` field ("" if none; a note if the file is unreadable).
    """
    try:
        return str(tomllib.loads(path.read_text(encoding="utf-8")).get("description", ""))
    except (OSError, tomllib.TOMLDecodeError) as exc:
        return f"(unreadable: {exc})"


