"""``studies.listing()``, what ``sonartrack studies`` prints, read from the study modules' source without importing
them: it must say what the imported modules say, and fall back to importing a module whose values it cannot read."""

from __future__ import annotations

import importlib.util
import sys

import pytest

from sonartrack import studies

#: a study module in miniature: the listed names and a Config whose run counts default to them
FAKE_STUDY = """
TITLE = "A title"
PAPER = "A paper"
RUNS = {runs}
QUICK_RUNS = 3


class Config:
    def __init__(self, runs=RUNS):
        self.runs = runs

    @classmethod
    def quick(cls):
        return cls(runs=QUICK_RUNS)
"""


@pytest.mark.parametrize("sid", studies.available())
def test_listing_says_what_the_imported_study_says(sid):
    """Title, citation and both run counts as the module and its Config give them: a ``RUNS`` or ``QUICK_RUNS``
    that drifts from the Config's default (a number written twice again) fails here."""
    rows = {row[0]: row for row in studies.listing()}
    mod = studies.load(sid)
    assert rows[sid] == (sid, mod.TITLE, mod.PAPER, mod.Config().runs, mod.Config.quick().runs)


@pytest.mark.parametrize("sid", studies.available())
def test_every_study_is_listed_from_its_source(sid):
    """Every shipped study declares the four names as literals, so ``listing`` never needs its import."""
    origin = importlib.util.find_spec(studies.STUDIES[sid]).origin
    assert studies._source_literals(origin) is not None


@pytest.fixture
def fake_study(tmp_path, monkeypatch):
    """Write a study module ``fake_listing_study`` with the given ``RUNS`` expression; make it the only study."""
    name = "fake_listing_study"

    def write(runs: str) -> str:
        (tmp_path / f"{name}.py").write_text(FAKE_STUDY.format(runs=runs))
        monkeypatch.syspath_prepend(str(tmp_path))
        monkeypatch.setattr(studies, "STUDIES", {"fake": name})
        return name

    yield write
    sys.modules.pop(name, None)


def test_literals_are_read_without_importing_the_module(fake_study):
    name = fake_study("6")
    assert studies.listing() == [("fake", "A title", "A paper", 6, 3)]
    assert name not in sys.modules


def test_a_count_built_by_an_expression_is_taken_from_the_imported_module(fake_study):
    name = fake_study("2 * 3")
    assert studies._source_literals(importlib.util.find_spec(name).origin) is None
    assert studies.listing() == [("fake", "A title", "A paper", 6, 3)]
    assert name in sys.modules
