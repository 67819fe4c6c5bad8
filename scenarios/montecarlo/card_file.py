"""A study's card with command-line overrides (``--set``, ``--turbulence``, ``--sensors``):
written as ``STUDY/card.toml`` so that every realization, worker and continuation flies the
same overridden card, and a changed override is a different study (refused on continuation)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from flightid.scenarios.cards import load_card, overridden_card
from flightid.scenarios.montecarlo.design.experiment import card_text

CARD_FILE = "card.toml"


def card_with_overrides(card: str | Path, study_dir: str | Path,
                        assignments: Sequence[str] = (), turbulence: str | None = None,
                        sensors: str | None = None) -> str:
    """``card`` (a library name or a file) unchanged without overrides; else the path of
    ``study_dir/card.toml``, the card with ``flightid.scenarios.cards.override``'s changes,
    validated, and written only when its text differs. Raises CardError or ValueError
    naming the override.

    Parameters
    ----------
    card : str or Path
        Library card name or card file.
    study_dir : str or Path
        The study folder.
    assignments : Sequence[str], optional
        ``KEY=VALUE`` overrides.
    turbulence : str or None, optional
        ``none``, ``light`` or ``moderate``.
    sensors : str or None, optional
        A built-in sensor suite.

    Returns
    -------
    str
        The card to fly: ``card`` or the written card's path.
    """
    if not assignments and turbulence is None and sensors is None:
        return str(card)
    base = load_card(card)
    changed = overridden_card(base, assignments, turbulence, sensors)
    data = dict(changed.data)
    data.setdefault("name", base.name)
    text = card_text(data)
    path = Path(study_dir) / CARD_FILE
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.exists() or path.read_text(encoding="utf-8") != text:
        path.write_text(text, encoding="utf-8")
    return str(path)
