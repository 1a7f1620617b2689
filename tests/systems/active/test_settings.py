"""The active system's settings tree: each shared quantity declared once at the root, handed down, TOML round trip."""

import tomllib

import pytest
from pydantic import ValidationError

from sonartrack.core.settings import to_commented_toml
from sonartrack.systems.active.settings import ActiveSettings


def test_root_quantities_reach_the_stages_and_are_not_declared_below():
    s = ActiveSettings(spacing_m=0.5, sound_speed_mps=1490.0, pfa=1e-4, max_range_rate_mps=9.0)
    fe, mftd = s.front_end_settings(), s.mftd_settings()
    assert (fe.sound_speed_mps, fe.pfa, fe.max_range_rate_mps) == (1490.0, 1e-4, 9.0)
    assert mftd.max_range_rate_mps == 9.0
    for group in ("front_end", "mftd"):
        assert not {"sound_speed_mps", "pfa", "max_range_rate_mps"} & set(type(getattr(s, group)).model_fields)


def test_toml_round_trip_and_misspelt_keys_refused():
    s = ActiveSettings(spacing_m=0.5, detector="single")
    back = ActiveSettings.model_validate(tomllib.loads(to_commented_toml(s)))
    assert back == s
    with pytest.raises(ValidationError):
        ActiveSettings.model_validate({"front_end": {"pfa": 1e-3}})  # the root's, not the front end's
    with pytest.raises(ValidationError):
        ActiveSettings(pfa=0.0)


def test_tracker_defaults_are_the_systems_with_their_docs():
    s = ActiveSettings()
    t = s.tracker_settings()
    assert t.pd == 0.7 and t.q == [1e-4, 0.05] and t.clutter_density_per_m2 == 1e-6
    assert "P4" in type(s.tracker).model_fields["pd"].description


def test_checked_takes_the_channel_count():
    from sonartrack.core.errors import InputError

    assert ActiveSettings(spacing_m=0.5).checked(16).elements == 16
    with pytest.raises(InputError, match="spacing"):
        ActiveSettings().checked(16)
    with pytest.raises(InputError, match="channels"):
        ActiveSettings(spacing_m=0.5, elements=8).checked(16)
