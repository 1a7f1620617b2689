"""The settings declarations: unit and doc beside each field, commented TOML that reads back."""

import tomllib

import pytest
from pydantic import ValidationError

from sonartrack.core.settings import Settings, field_help, field_unit, setting, to_commented_toml


class Inner(Settings):
    pd: float = setting(0.8, "probability of detection", unit="1", gt=0, le=1)


class Outer(Settings):
    q: list[float] = setting(default_factory=lambda: [1e-4, 0.05], doc="process noise per mode", unit="m^2/s^3")
    gate_m: float = setting(200.0, "gate half-width", unit="m", gt=0)
    name: str | None = setting(None, "optional label")
    inner: Inner = setting(default_factory=Inner, doc="detection")


def test_unit_and_doc_are_declared_beside_the_field():
    assert field_unit(Outer, "gate_m") == "m"
    assert field_help(Outer, "gate_m") == "gate half-width (m)"
    assert field_help(Inner, "pd") == "probability of detection"  # dimensionless: no unit shown


def test_commented_toml_reads_back_to_the_same_settings():
    s = Outer(gate_m=150.0, inner=Inner(pd=0.5))
    text = to_commented_toml(s)
    assert "gate_m = 150.0  # gate half-width (m)" in text and "[inner]" in text
    assert Outer.model_validate(tomllib.loads(text)) == s


@pytest.mark.parametrize("bad", [{"gate_m": -1.0}, {"gate_m": float("nan")}, {"unknown": 1}, {"inner": {"pd": 2}}])
def test_bad_values_and_unknown_keys_are_refused(bad):
    with pytest.raises(ValidationError):
        Outer.model_validate(bad)
