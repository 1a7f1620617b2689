"""Environments: the shipped Korean cases, TEOS-10 sound speed against Mackenzie, user profiles and bad input."""

import numpy as np
import pytest

from sonartrack.acoustics.environment import DEFAULT_BOTTOM, list_environments, load_environment
from sonartrack.acoustics.sonar_equation import convergence_zones, detection_ranges, passive_snr_db
from sonartrack.acoustics.sound_speed import sound_speed_from_ts
from sonartrack.core.errors import InputError
from sonartrack.io.environment import environment_from_name_or_file, read_profile


def mackenzie(T, S, D):
    """Mackenzie (1981) nine-term sound speed (m/s): an independent formula, stated accuracy ~0.07 m/s."""
    return (1448.96 + 4.591 * T - 5.304e-2 * T**2 + 2.374e-4 * T**3 + 1.340 * (S - 35) + 1.630e-2 * D
            + 1.675e-7 * D**2 - 1.025e-2 * T * (S - 35) - 7.139e-13 * T * D**3)


@pytest.mark.parametrize("T, S, D", [(25.0, 33.0, 0.0), (10.0, 34.0, 100.0), (2.0, 34.1, 1000.0), (0.1, 34.07, 2295.0),
                                     (15.0, 35.0, 500.0)])
def test_teos10_sound_speed_agrees_with_mackenzie(T, S, D):
    c = sound_speed_from_ts(np.array([D]), np.array([T]), np.array([S]), 38.0, 130.0)[0]
    assert c == pytest.approx(mackenzie(T, S, D), abs=0.6)


def test_six_shipped_environments():
    names = list_environments()
    assert names == ["east-summer", "east-winter", "yellow-summer", "yellow-winter", "south-summer", "south-winter"]
    depths = {"east": 2295.0, "yellow": 76.0, "south": 193.0}
    for n in names:
        e = load_environment(n)
        assert e.water_depth_m == depths[n.split("-")[0]] and e.depth_m[-1] == e.water_depth_m
        assert np.all((e.sound_speed_mps > 1440) & (e.sound_speed_mps < 1545))
        assert e.sources
    # summer surface water is warmer, hence faster, than winter's
    for sea in ("east", "yellow", "south"):
        summer, winter = load_environment(f"{sea}-summer"), load_environment(f"{sea}-winter")
        assert summer.sound_speed_mps[0] > winter.sound_speed_mps[0]


def test_user_profiles_csv_and_toml(tmp_path):
    p = tmp_path / "ctd.csv"
    p.write_text("depth_m,temperature_c,salinity_psu\n0,15,34\n50,12,34.2\n100,10,34.3\n")
    e = read_profile(p)
    assert e.water_depth_m == 100.0 and len(e.sound_speed_mps) == 3
    q = tmp_path / "ssp.csv"
    q.write_text("depth_m,sound_speed_mps\n0,1500\n80,1490\n")
    e2 = read_profile(q, water_depth_m=80.0)
    np.testing.assert_allclose(e2.sound_speed_mps, [1500, 1490])


@pytest.mark.parametrize("text, needle", [
    ("depth_m,sound_speed_mps\n0,1500\n-5,1490\n", "negative depth"),
    ("depth_m,sound_speed_mps\n0,1500\n50,1490\n20,1495\n", "increase strictly"),
    ("depth_m,sound_speed_mps\n0,1.5\n50,1.49\n", "km/s"),
    ("depth_m,speed\n0,1500\n50,1490\n", "sound_speed_mps"),
])
def test_bad_profiles(tmp_path, text, needle):
    p = tmp_path / "bad.csv"
    p.write_text(text)
    with pytest.raises(InputError, match=needle) as e:
        read_profile(p)
    assert "\n" not in str(e.value)


def test_profile_not_reaching_the_bottom(tmp_path):
    p = tmp_path / "short.csv"
    p.write_text("depth_m,sound_speed_mps\n0,1500\n50,1490\n")
    with pytest.raises(InputError, match="stops at 50 m but the water is 120 m deep"):
        read_profile(p, water_depth_m=120.0)


def test_name_or_file(tmp_path):
    assert environment_from_name_or_file("yellow-winter").name == "yellow-winter"
    p = tmp_path / "mine.toml"
    p.write_text('depth_m = [0.0, 40.0]\nsound_speed_mps = [1500.0, 1495.0]\nbottom_sound_speed_mps = 1700.0\n')
    e = environment_from_name_or_file(p)
    assert e.name == "mine.toml" and e.water_depth_m == 40.0 and e.bottom_sound_speed_mps == 1700.0
    assert e.bottom_density_gcc == DEFAULT_BOTTOM[1]  # seabed keys not given take the default
    with pytest.raises(InputError, match="profile file not found"):
        environment_from_name_or_file(tmp_path / "missing.csv")


def test_unknown_environment_lists_the_choices():
    with pytest.raises(InputError, match="unknown environment 'baltic'.*east-summer"):
        load_environment("baltic")


def test_sonar_equation_and_detection_ranges():
    assert passive_snr_db(140.0, 60.0) == pytest.approx(140 - 60 + 12.5 - 73)
    r = np.arange(0, 10.0, 1.0)
    snr = np.array([5, 4, 1, -1, -2, 3, 2, -1, -1, 2.0])
    assert detection_ranges(r, snr) == [(0.0, 2.0), (5.0, 6.0), (9.0, 9.0)]
    assert convergence_zones(r, snr, min_gap_m=2.5) == [(5.0, 6.0), (9.0, 9.0)]
    assert convergence_zones(r, snr, min_gap_m=3.5) == []
    assert detection_ranges(r, snr - 10) == []
