"""The delay-Doppler skirt of a notched CW echo (detection/cw_cells.py skirt_gain, notch_skirts), checked against a
rectangular pulse's ambiguity computed here by direct correlation of sampled signals (not by the chain's filters)."""

import numpy as np

from sonartrack.detection.cw_cells import SKIRT_SOURCE_STAT, notch_skirts, skirt_gain

TAU, FS = 1.0, 400.0


def ambiguity_power(dt_s: float, df_hz: float) -> float:
    """|chi(dt, df)|^2 of a unit rectangular CW of length TAU, by summing u(t) u*(t + dt) exp(2 pi i df t) over
    samples (normalised to 1 at the origin)."""
    n = int(TAU * FS)
    t = np.arange(-2 * n, 3 * n) / FS
    u = ((t >= 0) & (t < TAU)).astype(complex)
    shift = int(round(dt_s * FS))
    v = np.roll(u, -shift)
    return float(np.abs(np.sum(u * np.conj(v) * np.exp(2j * np.pi * df_hz * t))) ** 2 / n**2)


def test_skirt_gain_hand_worked_points():
    assert skirt_gain(0.0, 0.0, TAU) == 1.0
    assert np.isclose(skirt_gain(0.5, 0.0, TAU), 0.25)  # the delay triangle squared
    assert skirt_gain(1.0, 0.0, TAU) == 0.0 and skirt_gain(-1.2, 3.0, TAU) == 0.0
    # a sidelobe peak of sinc^2 (|sin| = 1 at x = 1.5): the envelope is exact there
    assert np.isclose(skirt_gain(0.0, 1.5 / TAU, TAU), 1.0 / (1.5 * np.pi) ** 2)


def test_skirt_gain_bounds_the_sampled_ambiguity():
    """The envelope is never below the true ambiguity, and meets it on sinc's sidelobe peaks."""
    for dt in (0.0, 0.25, 0.5, 0.7):
        for df in np.linspace(0.0, 4.0, 33):
            true = ambiguity_power(dt, df)
            assert skirt_gain(dt, df, TAU) >= true - 2e-3, (dt, df)
    rest = 1.0 - 0.5 / TAU
    df_peak = 2.5 / (TAU * rest)  # x = 2.5: a sidelobe peak at half a pulse's delay offset
    assert np.isclose(skirt_gain(0.5, df_peak, TAU), ambiguity_power(0.5, df_peak), rtol=0.05)


def _grid(echoes, notch_cells):
    """One beam's cells: unit background plus each echo's sampled ambiguity (power, delay s, Doppler Hz)."""
    delay = np.arange(0.0, 12.0, 0.25)
    doppler = np.arange(-8, 9) * 0.5 / TAU
    power = np.ones((1, len(delay), len(doppler)))
    for p, t0, f0 in echoes:
        for i, t in enumerate(delay):
            for j, f in enumerate(doppler):
                if abs(t - t0) < TAU:
                    power[0, i, j] += p * ambiguity_power(t - t0, f - f0)
    notch = np.zeros((1, len(doppler)), bool)
    notch[0, notch_cells] = True
    return power, delay, doppler, notch


def test_notched_point_skirt_withheld_target_kept():
    """A 30 dB point on the notch (Doppler 0): its skirt beyond the notch is withheld; a 20 dB target 2 Hz off the
    ridge at another delay, and one inside the skirt's reach but stronger than the skirt, are kept."""
    power, delay, doppler, notch = _grid([(1000.0, 5.0, 0.0), (100.0, 9.0, 2.0), (300.0, 5.5, 3.0)], [7, 8, 9])
    skirt = notch_skirts(power, power, notch, delay, doppler, TAU, 3.0)[0]
    assert not skirt[:, notch[0]].any()
    loud_skirt = (power[0] > 10.0) & ~notch[0][None, :] & (np.abs(delay[:, None] - 5.0) < 0.3) & (
        np.abs(doppler[None, :]) <= 1.5)
    assert loud_skirt.any() and skirt[loud_skirt].all()
    d_t, j_t = np.searchsorted(delay, 9.0), np.searchsorted(doppler, 2.0)
    d_s, j_s = np.searchsorted(delay, 5.5), np.searchsorted(doppler, 3.0)
    assert not skirt[d_t, j_t] and not skirt[d_s, j_s]
    assert not skirt[np.abs(delay - 5.0) >= 2 * TAU].any()  # a notched skirt cell above the level is a source too


def test_no_source_no_skirt():
    """A notched cell below SKIRT_SOURCE_STAT (the ridge's own reverberation) explains nothing."""
    p = 0.8 * SKIRT_SOURCE_STAT - 1.0
    power, delay, doppler, notch = _grid([(p, 5.0, 0.0)], [7, 8, 9])
    assert not notch_skirts(power, power, notch, delay, doppler, TAU, 3.0).any()
