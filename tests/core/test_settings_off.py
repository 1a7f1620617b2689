"""The TOML spelling of None ("off") for settings that may be switched off (core/settings.py)."""

import tomllib
from typing import Literal

import pytest

from sonartrack.core.errors import InputError
from sonartrack.core.settings import Settings, setting, to_commented_toml
from sonartrack.io.toml import validate


class Inner(Settings):
    margin_db: float | None = setting(3.0, "a margin that can be switched off", unit="dB")


class Outer(Settings):
    margin_db: float | None = setting(3.0, "a margin that can be switched off", unit="dB")
    unset_m: float | None = setting(None, "a length that is off unless given", unit="m")
    mode: Literal["off", "late"] = setting("off", "a mode whose own value is 'off'")
    name: str | None = setting("x", "a name: the string 'off' is a name like any other")
    inner: Inner = setting(default_factory=Inner, doc="a nested group")


class Required(Settings):
    spacing_m: float = setting(..., "a value the user must give", unit="m", gt=0)


@pytest.mark.parametrize("spelling", ["off", "OFF", " Off "])
def test_off_means_none_where_none_is_allowed(spelling):
    s = Outer.model_validate({"margin_db": spelling, "inner": {"margin_db": spelling}})
    assert s.margin_db is None and s.inner.margin_db is None


def test_off_is_a_value_where_it_is_one():
    s = Outer.model_validate({"mode": "late", "name": "off"})
    assert s.name == "off" and s.mode == "late"
    assert Outer.model_validate({"mode": "off"}).mode == "off"


def test_printed_config_reads_back_to_the_same_settings():
    s = Outer.model_validate({"margin_db": "off", "inner": {"margin_db": None}, "unset_m": None})
    text = to_commented_toml(s)
    assert 'margin_db = "off"' in text and "# unset_m = (not set)" in text
    assert Outer.model_validate(tomllib.loads(text)) == s
    # a value that is set prints as the value and also reads back
    t = Outer.model_validate({"margin_db": 1.5, "unset_m": 2.0})
    assert Outer.model_validate(tomllib.loads(to_commented_toml(t))) == t


def test_a_required_value_not_yet_given_prints_as_not_set():
    # a face may print a config whose required value is still to come (bearings --print-config without --spacing)
    text = to_commented_toml(Required(spacing_m=1.0).model_copy(update={"spacing_m": None}))
    assert text.startswith("# spacing_m = (not set)")


def test_a_misspelt_off_names_the_key_and_the_spelling():
    with pytest.raises(InputError) as info:
        validate(Outer, {"inner": {"margin_db": "of"}}, source="config c.toml")
    message = str(info.value)
    assert "inner.margin_db" in message and '"off"' in message and "\n" not in message
    with pytest.raises(InputError) as info:  # a field that cannot be off is not offered the spelling
        validate(Outer, {"mode": "sometimes"})
    assert '"off" to switch' not in str(info.value)
