"""The settings that differ from the defaults (core/settings_diff.py, report/settings_table.py) on hand-made trees:
a changed nested value shows with its default and unit, an unchanged one does not; a nested group is compared with
the group its parent declares (not its class's own defaults); a required field always shows."""

from __future__ import annotations

from sonartrack.core.settings import Settings, setting
from sonartrack.core.settings_diff import NO_DEFAULT, SettingChange, default_settings, settings_changes
from sonartrack.report.settings_table import merged_settings_table_html, settings_table_html


class Inner(Settings):
    a_m: float = setting(1.0, "a length", unit="m")
    b: int = setting(2, "a count", unit="1")


class Outer(Settings):
    inner: Inner = setting(default_factory=Inner, doc="a group")
    name: str = setting("x", "a name")
    #: the parent's default of a group differs from the group class's own
    tuned: Inner = setting(default_factory=lambda: Inner(a_m=7.0), doc="a tuned group")
    items: list[Inner] = setting(default_factory=lambda: [Inner(), Inner(b=5)], doc="groups")
    band_hz: list[float] = setting(default_factory=lambda: [10.0, 20.0], doc="a band", unit="Hz")


class Required(Settings):
    spacing_m: float = setting(..., "required spacing", unit="m")
    c_mps: float = setting(1500.0, "sound speed", unit="m/s")


def _names(changes):
    return [c.name for c in changes]


def test_a_changed_nested_value_shows_and_an_unchanged_one_does_not():
    changes = settings_changes(Outer(inner=Inner(a_m=2.5)))
    assert changes == [SettingChange("inner.a_m", 2.5, 1.0, "m", "a length")]
    assert settings_changes(Outer()) == []


def test_a_group_is_compared_with_its_parents_default():
    assert settings_changes(Outer(tuned=Inner(a_m=7.0))) == []  # the parent's default, though Inner's a_m is 1
    (c,) = settings_changes(Outer(tuned=Inner()))
    assert (c.name, c.value, c.default) == ("tuned.a_m", 1.0, 7.0)


def test_lists_of_groups_item_by_item_and_plain_lists_whole():
    assert _names(settings_changes(Outer(items=[Inner(), Inner(b=6)]))) == ["items[1].b"]
    (c,) = settings_changes(Outer(items=[Inner()]))  # another length: the whole list, as plain values
    assert c.name == "items" and c.value == [{"a_m": 1.0, "b": 2}] and len(c.default) == 2
    (c,) = settings_changes(Outer(band_hz=[10.0, 30.0]))
    assert (c.name, c.value, c.default, c.unit) == ("band_hz", [10.0, 30.0], [10.0, 20.0], "Hz")


def test_a_required_field_always_shows_without_a_default():
    changes = settings_changes(Required(spacing_m=2.5))
    assert [(c.name, c.value, c.default) for c in changes] == [("spacing_m", 2.5, NO_DEFAULT)]
    assert default_settings(Required) is None and default_settings(Required, Required(spacing_m=1.0)).c_mps == 1500.0
    assert _names(settings_changes(Required(spacing_m=2.5, c_mps=1480.0))) == ["spacing_m", "c_mps"]


def test_an_explicit_default_of_another_class_is_refused():
    import pytest

    with pytest.raises(TypeError):
        settings_changes(Outer(), Inner())


def test_the_html_table_states_name_value_default_unit():
    text = settings_table_html(Outer(inner=Inner(a_m=2.5), name="y"))
    assert "<code>inner.a_m</code></td><td>2.5</td><td>1</td><td>m</td>" in text
    assert "<code>name</code></td><td>y</td><td>x</td><td></td>" in text
    assert "inner.b" not in text and "tuned" not in text
    assert "Every setting at its default" in settings_table_html(Outer())


def test_the_merged_table_names_the_runs_of_each_value():
    text = merged_settings_table_html({"leg1": Outer(name="y"), "leg2": Outer(name="y", inner=Inner(b=3)),
                                       "leg3": Outer(name="z")})
    assert "<code>name</code></td><td>y</td><td>x</td><td></td><td>leg1, leg2</td>" in text
    assert "<code>name</code></td><td>z</td><td>x</td><td></td><td>leg3</td>" in text
    assert "<code>inner.b</code></td><td>3</td><td>2</td><td></td><td>leg2</td>" in text
    both = merged_settings_table_html({"a": Outer(name="y"), "b": Outer(name="y")})
    assert "<td>all</td>" in both


def test_a_real_tree_changed_in_one_nested_value():
    from sonartrack.systems.passive.settings import PassiveSettings

    default_gate = PassiveSettings().tracker.gate_deg
    (c,) = settings_changes(PassiveSettings(tracker={"gate_deg": default_gate + 1.0}))
    assert (c.name, c.value, c.default, c.unit) == ("tracker.gate_deg", default_gate + 1.0, default_gate, "deg")
