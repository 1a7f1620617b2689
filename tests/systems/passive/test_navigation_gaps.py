"""Navigation gaps and impossible speeds in the passive chain on files (systems/passive/files.py): the conftest's
300 s scene (the ownship turns 40-130 s) run on its nav.csv and on the same file with 16 s of the turn cut out.
The targets the clean run determines are not determined across the gap, with the gap as the reason in targets.csv
and a warning naming it; a batch ML faster than ``verdict.max_speed_mps`` is not printed as determined; a tow
length no array has is refused in one line before anything is written."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from sonartrack.cli import main
from sonartrack.systems.passive.files import run_passive_recording, write_passive_tables
from sonartrack.systems.passive.nav_flags import bound_batch_speed
from sonartrack.systems.passive.settings import PassiveSettings
from sonartrack.systems.passive.tables import summary_lines

SETTINGS = PassiveSettings(spacing_m=2.5)


@pytest.fixture(scope="module")
def runs(scene_dir, tmp_path_factory):
    d = tmp_path_factory.mktemp("nav-gap")
    nav = pd.read_csv(scene_dir / "nav.csv")
    cut = nav[(nav["time_s"] < 70) | (nav["time_s"] > 85)]  # rows 70..85 s: the heading turns 8 deg in them
    cut.to_csv(d / "gap.csv", index=False)
    clean = run_passive_recording(scene_dir / "recording.wav", scene_dir / "nav.csv", SETTINGS).result
    gap = run_passive_recording(scene_dir / "recording.wav", d / "gap.csv", SETTINGS).result
    return clean, gap, d


def _ml_determined(target) -> bool:
    return bool(target.ml.solution.range_flags()[-1])


def test_a_gap_in_the_turn_withholds_the_ranges_across_it(runs):
    clean, gap, d = runs
    across = [tg for tg in clean.targets if tg.track.time_s[0] < 86 and tg.track.time_s[-1] > 69]
    determined = [tg.target_id for tg in across if _ml_determined(tg)]
    assert determined, "the clean run determines a range across 69-86 s (else this test shows nothing)"
    assert not any("navigation" in w for w in clean.warnings)
    lines = [w for w in gap.warnings if "no navigation for 17 s (69-86 s" in w]
    assert len(lines) == 1 and "the ship turned in it (the heading changes 8 deg across it)" in lines[0]
    by_id = {tg.target_id: tg for tg in gap.targets}
    reason = "navigation gap 69-86 s during the track, the ship turned in it"
    for k in determined:
        sol = by_id[k].ml.solution
        assert not sol.range_flags().any() and set(sol.reasons()) == {reason}
        seq = by_id[k].sequential.solution
        after = np.asarray(seq.time_s) >= 69
        assert not seq.range_flags()[after].any() and (seq.reasons()[after] == reason).all()
    write_passive_tables(gap, d)
    table = pd.read_csv(d / "targets.csv")
    rows = table[table["target_id"].isin(determined) & (table["method"] == "ml")]
    assert len(rows) and not rows["range_determined"].any() and rows["range_m"].isna().all()
    assert (rows["undetermined_reason"] == reason).all()
    summary = summary_lines(gap)
    assert all(f"range NOT DETERMINED ({reason})" in summary[[t.target_id for t in gap.targets].index(k)]
               for k in determined)


def test_a_batch_ml_faster_than_any_ship_is_not_determined(runs):
    """The bound the sequential filters' verdict applies (58 kn), applied to the batch ML: here lowered below a
    determined target's own speed, so that the clean scene's answer crosses it."""
    clean, _, _ = runs
    tg = next(t for t in clean.targets if _ml_determined(t))
    state = np.asarray(tg.ml.solution.state)
    speed = float(np.hypot(state[-1, 2], state[-1, 3]))
    verdict = tg.ml.settings.verdict.model_copy(update={"max_speed_mps": 0.9 * speed})
    slow = replace(tg, ml=replace(tg.ml, settings=tg.ml.settings.model_copy(update={"verdict": verdict})))
    out = bound_batch_speed(replace(clean, targets=[slow if t is tg else t for t in clean.targets], warnings=()))
    got = next(t for t in out.targets if t.target_id == tg.target_id)
    assert not got.ml.solution.range_flags().any() and set(got.ml.solution.reasons()) == {"diverged"}
    assert len(out.warnings) == 1 and f"target {tg.target_id}: the batch ML makes it" in out.warnings[0]
    assert bound_batch_speed(clean).targets == clean.targets  # the scene's own ships are all below 58 kn


@pytest.mark.parametrize("tow", ["1e9", "-1", "nan"])
def test_an_implausible_tow_length_is_refused_in_one_line(scene_dir, tmp_path, capsys, tow):
    out = tmp_path / "out"
    code = main(["passive", "--wav", str(scene_dir / "recording.wav"), "--nav", str(scene_dir / "nav.csv"),
                 "--spacing", "2.5", "--tow-length", tow, "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("error: tow length") and len(err.strip().splitlines()) == 1, err
    assert "0..10000 m" in err and not out.exists()


def test_levels_outside_any_sea_are_named_with_their_likely_cause(runs, scene_dir, tmp_path):
    """The recording is in pascals: read through a calibration whose full scale is 1000 V (millivolts given as
    volts, with a sensitivity of -170 dB: 60 dB too loud), its median level lies beyond any sea and the run's
    warnings say so and name the calibration; the clean run (no calibration) has no such warning."""
    clean = runs[0]
    assert not any("any sea" in w for w in clean.warnings)
    cal = tmp_path / "cal.toml"
    cal.write_text("sensitivity_db = -250.0\ngain_db = 0.0\nfull_scale_v = 1.0\n")
    loud = run_passive_recording(scene_dir / "recording.wav", scene_dir / "nav.csv", SETTINGS, calibration=cal).result
    line = [w for w in loud.warnings if "any sea" in w]
    assert len(line) == 1 and "above any sea" in line[0] and "calibration" in line[0]
