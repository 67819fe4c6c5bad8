"""A study is known by its card's content, not by the path the card was given by: the
same card file named by its absolute and by a relative path continues one study; a card
whose content differs is refused naming card_sha256."""

from __future__ import annotations

import json

import pytest

from flightid.scenarios import montecarlo
from flightid.scenarios.cards import load_card
from flightid.scenarios.montecarlo import store
from flightid.scenarios.montecarlo.design.experiment import card_text
from flightid.scenarios.montecarlo.study import Study


def test_the_same_card_by_another_path_continues_one_study(tmp_path, monkeypatch):
    data = load_card("navion-demo").to_dict()
    (tmp_path / "card.toml").write_text(card_text(data))
    absolute = str(tmp_path / "card.toml")
    folder = tmp_path / "study"
    montecarlo.run(absolute, 1, "oe", "lat", study_dir=folder, workers=1, report=False)
    stamp = store.result_path(folder, 0).stat().st_mtime_ns
    monkeypatch.chdir(tmp_path)
    summary = montecarlo.run("card.toml", 1, "oe", "lat", study_dir="study", workers=1,
                             report=False)
    assert summary.realizations == 1
    assert store.result_path(folder, 0).stat().st_mtime_ns == stamp  # nothing flown again
    stored = store.read_description(folder)
    assert stored["identity"]["card"] == absolute  # the path stays, for information
    assert stored["identity"]["card_sha256"] == Study("card.toml", 1).identity()["card_sha256"]
    # another content at the same path is another study, named by its hash only
    (tmp_path / "card.toml").write_text(card_text({**data, "duration": data["duration"] + 5.0}))
    with pytest.raises(montecarlo.StudyMismatch, match="card_sha256") as info:
        store.open_study("study", Study("card.toml", 1, "oe", "lat"))
    assert "card: stored" not in str(info.value)


def test_a_study_of_an_earlier_flightid_is_refused_saying_so(tmp_path):
    """A study.json written before the data reduction entered the identity (its rows were
    identified without it) is another study; the message says why, not 'stored None'."""
    (tmp_path / "card.toml").write_text(card_text(load_card("navion-demo").to_dict()))
    study = Study(str(tmp_path / "card.toml"), 1, "oe", "lat")
    folder = tmp_path / "study"
    store.open_study(folder, study)
    path = folder / "study.json"
    stored = json.loads(path.read_text())
    del stored["identity"]["data_reduction"]
    path.write_text(json.dumps(stored))
    with pytest.raises(montecarlo.StudyMismatch,
                       match="data_reduction: not stored, asked 'standard' "
                             r"\(a study of an earlier flightid"):
        store.open_study(folder, study)
