"""The settings declarations: unit and doc beside each field, commented TOML that reads back."""

import pickle
import tomllib

import pytest
from pydantic import ValidationError, model_validator

from sonartrack.core.settings import Settings, derived_settings, field_help, field_unit, setting, to_commented_toml


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


class Stage(Settings):
    """A library stage that declares a quantity a system would share (window_s) and checks a pair of fields."""

    window_s: float = setting(1.0, "window", unit="s", gt=0)
    low_hz: float = setting(10.0, "low edge", unit="Hz", ge=0)
    high_hz: float = setting(100.0, "high edge", unit="Hz", gt=0)

    @model_validator(mode="after")
    def _ordered(self):
        if self.low_hz >= self.high_hz:
            raise ValueError("low_hz must be below high_hz")
        return self


SystemStage = derived_settings(Stage, "SystemStage", "the stage inside a system", drop=("window_s",),
                               defaults={"high_hz": (50.0, "high edge chosen by the system")})


def test_derived_stage_drops_the_root_quantity_and_declares_the_system_default():
    assert "window_s" not in SystemStage.model_fields
    assert SystemStage().high_hz == 50.0
    assert field_help(SystemStage, "high_hz") == "high edge chosen by the system (Hz)"  # the unit stays the library's
    assert "high edge chosen by the system" in to_commented_toml(SystemStage())
    with pytest.raises(ValidationError):
        SystemStage(window_s=2.0)  # the root holds it now: refused in the stage's group
    with pytest.raises(ValidationError):
        SystemStage(high_hz=-1.0)  # the library's bounds still hold


def test_derived_stage_keeps_the_library_checks_and_builds_the_library_settings():
    with pytest.raises(ValidationError, match="low_hz must be below high_hz"):
        SystemStage(low_hz=60.0)  # 60 >= the system's default high edge 50
    built = SystemStage(low_hz=20.0).build(window_s=2.5)
    assert isinstance(built, Stage) and (built.window_s, built.low_hz, built.high_hz) == (2.5, 20.0, 50.0)
    assert pickle.loads(pickle.dumps(SystemStage(low_hz=5.0))) == SystemStage(low_hz=5.0)
    with pytest.raises(TypeError, match="no field"):
        derived_settings(Stage, "Bad", "bad", drop=("nonexistent",))
