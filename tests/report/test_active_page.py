"""The active page: a summary line first, decided targets and undecided mirror pairs in their own tables (a pair
drawn and listed as one target with two hypotheses), and the settings that differ from the defaults.

The tracks come from the contact generator of tests/systems/active/test_ghosts_targets.py (written from the
geometry, not the scene simulator): before the array's turn the target is tracked on both sides, after it decided."""

import importlib.util
import re
from pathlib import Path

import numpy as np
import pytest

from sonartrack.detection.ping_mftd import empty_detections
from sonartrack.report.active_page import active_page
from sonartrack.systems.active.contacts import Contacts
from sonartrack.systems.active.run import ActiveResult, BScan
from sonartrack.systems.active.settings import ActiveSettings

_GEN = Path(__file__).parents[1] / "systems" / "active" / "test_ghosts_targets.py"


def _generator():
    spec = importlib.util.spec_from_file_location("ghost_contacts", _GEN)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _result(pings: int, settings: ActiveSettings) -> ActiveResult:
    gen = _generator()
    r = gen.run(pings)
    empty = empty_detections()
    no_contacts = Contacts(*(np.zeros((0, 2, 2)) if k == "R" else np.zeros((0, 2)) if k == "xy" else np.zeros(0)
                             for k in ("ping", "time_s", "detection", "side", "xy", "R", "range_rate_mps",
                                       "rx_range_m", "statistic")))
    bscan = BScan(r.times, np.zeros(0), np.zeros(0), np.zeros((len(r.times), 0, 0), np.float32))
    return ActiveResult(empty, empty, empty, no_contacts, np.zeros(0, bool), r.tracks, bscan, r.geometry, r.times,
                        settings, {"tracking": 1.5})


def _rows(html: str, table_class: str) -> list[str]:
    m = re.search(rf'<table class="{table_class}">(.*?)</table>', html, re.S)
    return re.findall(r"<tr[^>]*>(.*?)</tr>", m.group(1), re.S)[1:] if m else []


@pytest.fixture(scope="module")
def settings():
    return ActiveSettings(spacing_m=0.5, pfa=2e-5)


def test_an_undecided_pair_is_one_target_with_both_hypotheses(settings):
    result = _result(20, settings)
    html = active_page(result, [], {}, {"pings": "generated"})
    summary = re.search(r'<p class="summary" id="summary">(.*?)</p>', html, re.S)
    assert summary and html.index('id="summary"') < html.index("<h2>")  # the first thing on the page
    assert summary.group(1).startswith("1 targets: 0 with the side decided, 1 undecided (1 tracked on both sides")
    assert "20 pings in 1.5 s" in summary.group(1)
    assert _rows(html, "decided") == []
    pair = _rows(html, "pairs")
    assert len(pair) == 2  # one target, two rows: its two hypotheses
    cells = [re.findall(r"<td>(.*?)</td>", row) for row in pair]
    assert cells[0][0] == "1" and cells[1][0] == ""
    assert {cells[0][1], cells[1][1]} == {"starboard", "port"}
    ids = {int(cells[0][2]), int(cells[1][2])}
    assert ids == set(np.unique(result.tracks.tracks.track_id[result.tracks.tracks.confirmed]).tolist())


def test_a_decided_target_is_listed_once_with_its_mirror_dropped(settings):
    result = _result(50, settings)
    html = active_page(result, [], {}, {"pings": "generated"})
    decided = _rows(html, "decided")
    assert len(decided) == 1 and _rows(html, "pairs") == []
    cells = re.findall(r"<td>(.*?)</td>", decided[0])
    assert cells[1] == "starboard" and (cells[-1] == "" or cells[-1].endswith("(dropped)"))


def test_settings_that_differ_from_the_defaults(settings):
    html = active_page(_result(3, settings), [], {}, {})
    rows = _rows(html.replace("class='settings-diff'", 'class="settings-diff"'), "settings-diff")
    names = [re.findall(r"<td[^>]*>(.*?)</td>", r, re.S)[0] for r in rows]
    assert [re.sub("<[^>]+>", "", n) for n in names] == ["spacing_m", "pfa"]
    nested = settings.model_copy(update={"tracker": settings.tracker.model_copy(update={"pd": 0.9})})
    html = active_page(_result(3, nested), [], {}, {})
    rows = _rows(html.replace("class='settings-diff'", 'class="settings-diff"'), "settings-diff")
    assert len(rows) == 3 and "tracker.pd" in rows[-1] and "0.9" in rows[-1] and "0.7" in rows[-1]
    assert "sound_speed_mps" not in html.split("All settings")[0]


def test_the_tactical_picture_draws_a_pair_as_dashed_twins(settings):
    import matplotlib

    matplotlib.use("Agg")
    from sonartrack.report.figures.active import tactical_picture
    from sonartrack.systems.active.records import ActiveNav

    result = _result(20, settings)
    g = result.geometry
    nav = ActiveNav(g.time_s, g.rx_xy, g.array_heading_rad, g.tx_xy, g.rx_xy, g.array_heading_rad)
    fig = tactical_picture(result, nav)
    ax = fig.axes[0]
    dashed = [ln for ln in ax.lines if ln.get_linestyle() == "--" and ln.get_color() not in ("c",)]
    solid = [ln for ln in ax.lines if ln.get_linestyle() == "-" and len(ln.get_xdata()) > 1]
    colors = {ln.get_color() for ln in dashed if len(ln.get_xdata()) > 1} - {"c"}
    assert len(colors) == 1  # one target: both hypotheses in its colour
    assert len([ln for ln in dashed if ln.get_color() in colors]) == 2
    assert [ln.get_label() for ln in solid] == ["ownship"]  # nothing drawn as a decided track
    assert any(ln.get_linestyle() == ":" and len(ln.get_xdata()) == 2 for ln in ax.lines)  # the twins joined
    import matplotlib.pyplot as plt

    plt.close(fig)
