"""A CW beam's reverberation ridge: the stationary sea's range rates over the beam's main and grating lobes.

A stationary scatterer in the direction u (unit vector) from the far field has bistatic range rate
rdot = -(u . v_T + u . v_R) (v_T, v_R the source's and receiver's velocities; far field: u_T = u_R = u). A line
array cannot tell the two mirror directions phi +- theta of a cone angle theta (phi the axis heading) apart, and
a beam steered to theta_b hears every cone theta with the pattern |sin(N x) / (N sin x)|^2,
x = pi f_c d (cos theta - cos theta_b) / c (acoustics/active_beams.py): its ridge is the set of rdot over both
mirrors of the cones where the pattern is above a level (-10 dB: the main lobe, and near endfire the grating
lobe of elements half a wavelength apart; not the -13 dB sidelobes). detection/cw_cells.py notches the Doppler
cells within a margin of it.
"""

from __future__ import annotations

import numpy as np

#: cone-angle step of the pattern's evaluation (deg): rdot moves at most |v_T + v_R| x 0.0044 rad between samples
PATTERN_STEP_DEG = 0.25


def ridge_range_rates(cone_deg, heading_rad: float, tx_velocity, rx_velocity) -> np.ndarray:
    """(..., 2) bistatic range rate (m/s) of the stationary sea in the two mirror directions of each cone angle.

    Parameters
    ----------
    cone_deg : array (...)
        Cone angles (deg from the array's forward axis).
    heading_rad : float
        Array axis heading (rad, clockwise from north).
    tx_velocity, rx_velocity : array (2,)
        Source and receiver velocities [east, north] (m/s).

    Returns
    -------
    numpy.ndarray
        rdot = -u . (v_T + v_R) for u along heading +- cone (starboard, port).
    """
    theta = np.deg2rad(np.asarray(cone_deg, float))
    v = np.asarray(tx_velocity, float) + np.asarray(rx_velocity, float)
    bearing = heading_rad + np.stack([theta, -theta], axis=-1)
    return -(np.sin(bearing) * v[0] + np.cos(bearing) * v[1])


def ridge_notch(range_rate_mps, ridge_mps: np.ndarray, half_width_mps: float) -> np.ndarray:
    """(B, J) True where a Doppler cell's range rate is within ``half_width_mps`` of any of its beam's ridge rates.

    Parameters
    ----------
    range_rate_mps : array (J,)
        The Doppler cells' bistatic range rates (m/s).
    ridge_mps : array (B, R)
        Each beam's ridge range rates (NaN: none).
    half_width_mps : float
        Half-width of the notch (m/s).

    Returns
    -------
    numpy.ndarray
        (B, J) bool.
    """
    v = np.asarray(range_rate_mps, float)
    with np.errstate(invalid="ignore"):
        return (np.abs(v[None, :, None] - np.asarray(ridge_mps, float)[:, None, :]) <= half_width_mps).any(axis=-1)


def beam_pattern_power(cone_deg, beam_cone_deg, n_elements: int, spacing_m: float, freq_hz: float,
                       sound_speed_mps: float) -> np.ndarray:
    """(B, U) |sin(N x) / (N sin x)|^2 of each beam at each cone angle (module doc; 1 where sin x = 0).

    Parameters
    ----------
    cone_deg : array (U,)
        Cone angles heard (deg).
    beam_cone_deg : array (B,)
        The beams' steering cone angles (deg).
    n_elements : int
        Elements N.
    spacing_m, freq_hz, sound_speed_mps : float
        Element spacing d (m), frequency f (Hz), sound speed c (m/s).

    Returns
    -------
    numpy.ndarray
        Power pattern, 0..1.
    """
    u = np.cos(np.deg2rad(np.asarray(cone_deg, float)))
    ub = np.cos(np.deg2rad(np.asarray(beam_cone_deg, float)))
    x = np.pi * freq_hz * spacing_m * (u[None, :] - ub[:, None]) / sound_speed_mps
    sx = np.sin(x)
    small = np.abs(sx) < 1e-9
    ratio = np.sin(n_elements * x) / (n_elements * np.where(small, 1.0, sx))
    return np.where(small, 1.0, ratio**2)


def beam_ridge_notch(range_rate_mps, beam_cone_deg, heading_rad: float, tx_velocity, rx_velocity, array,
                     carrier_hz: float, sound_speed_mps: float, level_db: float, margin_mps: float) -> np.ndarray:
    """(B, J) True where a Doppler cell is within ``margin_mps`` of its beam's ridge (module doc).

    Parameters
    ----------
    range_rate_mps : array (J,)
        The Doppler cells' bistatic range rates (m/s).
    beam_cone_deg : array (B,)
        The beams' cone angles (deg).
    heading_rad : float
        Array axis heading (rad, clockwise from north).
    tx_velocity, rx_velocity : array (2,)
        Source and receiver velocities [east, north] (m/s).
    array : LineArray
        Elements and spacing.
    carrier_hz, sound_speed_mps : float
        Carrier (Hz), sound speed (m/s).
    level_db : float
        Pattern level (dB, <= 0) above which a direction belongs to the beam's ridge.
    margin_mps : float
        Half-width added around the ridge's rates (m/s).

    Returns
    -------
    numpy.ndarray
        (B, J) bool.
    """
    cone = np.arange(0.0, 180.0 + PATTERN_STEP_DEG / 2, PATTERN_STEP_DEG)
    heard = beam_pattern_power(cone, beam_cone_deg, int(array.elements), float(array.spacing_m), carrier_hz,
                               sound_speed_mps) >= 10.0 ** (level_db / 10.0)
    rates = ridge_range_rates(cone, heading_rad, tx_velocity, rx_velocity)  # (U, 2)
    v = np.asarray(range_rate_mps, float)
    out = np.zeros((heard.shape[0], v.size), bool)
    for b in range(heard.shape[0]):
        r = rates[heard[b]].ravel()
        out[b] = (np.abs(v[:, None] - r[None, :]) <= margin_mps).any(axis=1)
    return out
