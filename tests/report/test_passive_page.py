"""The passive page's summary line (hours processed, targets by side, ranges determined) and its JSON block of the
settings as run (read back by the survey page). The page of a real run is checked in test_survey_page.py (each
survey recording's page is a passive page)."""

from __future__ import annotations

from sonartrack.report.passive_page import read_page_settings, settings_block, summary_line
from sonartrack.systems.passive.settings import PassiveSettings


def test_the_summary_line_counts_targets_by_side_and_determined_ranges():
    line = summary_line(5400.0, ["starboard", "port", "starboard", "unresolved"], [True, False, True, False], 1)
    assert line == ("1.50 h processed; 4 targets (1 narrowband): 2 starboard, 1 port, 1 unresolved; "
                    "2 of 4 ranges determined")
    assert summary_line(60.0, [], [], 0) == "0.02 h processed; 0 targets; 0 of 0 ranges determined"
    assert "1 target: 1 port;" in summary_line(60.0, ["port"], [False], 0)


def test_the_settings_block_reads_back_to_the_same_settings(tmp_path):
    s = PassiveSettings(spacing_m=2.5, min_track_s=60.0, tracker={"gate_deg": 5.0})
    page = tmp_path / "index.html"
    page.write_text(f"<!doctype html><html><body><p>x</p>{settings_block(s)}</body></html>")
    assert PassiveSettings.model_validate(read_page_settings(page)) == s
    assert read_page_settings(tmp_path / "none.html") is None
    (tmp_path / "old.html").write_text("<html><pre>spacing_m = 2.5</pre></html>")
    assert read_page_settings(tmp_path / "old.html") is None


def test_the_settings_block_cannot_close_its_script_early(tmp_path):
    from sonartrack.core.settings import Settings, setting

    class Named(Settings):
        label: str = setting("x", "a label")

    page = tmp_path / "index.html"
    page.write_text(f"<html><body>{settings_block(Named(label='a</script><b>'))}<p>after</p></body></html>")
    assert read_page_settings(page) == {"label": "a</script><b>"}
