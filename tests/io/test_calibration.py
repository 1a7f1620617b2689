"""Hydrophone calibration (io/calibration.py): volts to pascals against hand-worked values, levels re 1 uPa,
TOML and CSV files, refusals."""

from __future__ import annotations

import numpy as np
import pytest

from sonartrack.core.errors import InputError
from sonartrack.io.calibration import (
    Calibration,
    level_db_re_1upa,
    read_calibration,
    rms_level_db,
    sensitivity_db_re_v_per_upa,
)


def test_hand_worked_volts_to_pascals(tmp_path):
    """S = -180 dB re 1 V/uPa is 1e-9 V/uPa = 1 mV/Pa; with G = 20 dB the chain gives 10 mV/Pa, so 1 mV is
    0.1 Pa, whose level is 20 log10(0.1 / 1e-6) = 100 dB re 1 uPa. Channel 1: S = -170, G = 0 -> 3.162 mV/Pa."""
    (tmp_path / "c.toml").write_text("sensitivity_db = [-180.0, -170.0]\ngain_db = [20.0, 0.0]\n")
    cal = read_calibration(tmp_path / "c.toml")
    assert cal.channels == 2
    p = cal.to_pascals(np.array([[1e-3, -2e-3], [1e-3, 0.0]]))
    np.testing.assert_allclose(p[0], [0.1, -0.2], rtol=1e-12)
    np.testing.assert_allclose(p[1, 0], 1e-3 / (10 ** (-170 / 20) * 1e6), rtol=1e-12)
    assert p[1, 0] == pytest.approx(0.31623, rel=1e-4)
    assert level_db_re_1upa(0.1) == pytest.approx(100.0)
    assert level_db_re_1upa(1.0) == pytest.approx(120.0)


def test_full_scale_voltage_and_one_value_for_every_channel(tmp_path):
    """A recorder whose full-scale sample is 2.5 V: sample 0.4 is 1 V; S = -160, G = 0 gives 10 mV/Pa: 100 Pa."""
    (tmp_path / "c.toml").write_text("sensitivity_db = -160\nfull_scale_v = 2.5\n")
    cal = read_calibration(tmp_path / "c.toml")
    assert cal.channels is None
    np.testing.assert_allclose(cal.to_pascals(np.full((3, 2), 0.4)), 100.0, rtol=1e-12)


def test_csv_rows_in_any_order_equal_the_toml(tmp_path):
    (tmp_path / "c.csv").write_text("channel,sensitivity_db,gain_db\n1,-170,0\n0,-180,20\n")
    (tmp_path / "c.toml").write_text("sensitivity_db = [-180.0, -170.0]\ngain_db = [20.0, 0.0]\n")
    np.testing.assert_allclose(read_calibration(tmp_path / "c.csv").pa_per_unit(2),
                               read_calibration(tmp_path / "c.toml").pa_per_unit(2), rtol=1e-15)


def test_default_samples_are_pascals():
    cal = read_calibration(None)
    x = np.random.default_rng(0).standard_normal((4, 10))
    np.testing.assert_array_equal(cal.to_pascals(x), x)
    assert Calibration.identity().is_identity


def test_rms_level_of_a_sine():
    """A sine of amplitude 1 Pa has rms 1/sqrt(2) Pa: 120 - 3.0103 dB re 1 uPa."""
    t = np.arange(4000) / 4000.0
    x = np.sin(2 * np.pi * 50.0 * t)[None]
    assert rms_level_db(x)[0] == pytest.approx(120.0 - 10 * np.log10(2), abs=1e-9)
    assert sensitivity_db_re_v_per_upa(1e-3) == pytest.approx(-180.0)


def _refused(tmp_path, name, text, *words):
    (tmp_path / name).write_text(text)
    with pytest.raises(InputError) as e:
        read_calibration(tmp_path / name)
    assert "\n" not in str(e.value)
    for w in words:
        assert w in str(e.value), str(e.value)


def test_refusals(tmp_path):
    _refused(tmp_path, "vpa.toml", "sensitivity_db = -45\n", "dB re 1 V/Pa", "subtract 120")
    _refused(tmp_path, "key.toml", "sensitivity_db = -170\ngain = 3\n", "unknown key", "gain_db")
    _refused(tmp_path, "none.toml", "gain_db = 3\n", "no sensitivity_db")
    _refused(tmp_path, "len.toml", "sensitivity_db = [-170, -171]\ngain_db = [0, 0, 0]\n", "different lengths")
    _refused(tmp_path, "txt.toml", "sensitivity_db = 'high'\n", "number or a list")
    _refused(tmp_path, "ch.csv", "channel,sensitivity_db\n0,-170\n2,-170\n", "0..N-1")
    _refused(tmp_path, "nan.csv", "channel,sensitivity_db\n0,abc\n", "not a number")
    _refused(tmp_path, "c.json", "{}", ".toml or .csv")
    with pytest.raises(InputError, match="gives 2 channels but the recording has 3"):
        (tmp_path / "two.toml").write_text("sensitivity_db = [-170, -171]\n")
        read_calibration(tmp_path / "two.toml").to_pascals(np.zeros((3, 4)))
    with pytest.raises(InputError, match="not found"):
        read_calibration(tmp_path / "missing.toml")
