"""Range-Doppler plane of an active sonar: cells, their quantisation covariance, target motion.

Im & Kim 1996 (paper P1), sec. V. State w = [range (m), range-rate (m/s)] (this order everywhere).

Cells of a CW pulse of length tau at carrier f_c (Nielsen 1991, quoted by the paper):

    range cell        dr = 0.58 tau c / 2                          (m)
    Doppler cell      df = 0.88 / tau                              (Hz)
    range-rate cell   dv = df * c / (2 f_c)                        (m/s; two-way Doppler 2 v f_c / c)
    R = diag(dr^2 / 12, dv^2 / 12)   (uniform quantisation error inside a cell, eq. 25)

The paper prints the Doppler entry of R as (0.88/tau)^2 (2c/f_c)^2 / 12. The velocity of one hertz
of two-way Doppler is c / (2 f_c) (= 0.025 m/s at 30 kHz, 1500 m/s), not 2 c / f_c (= 0.1 m/s,
4 times larger, 16 times in variance): the printed factor is a typo, and we use c / (2 f_c).
:func:`printed_quantisation_covariance` keeps the printed value for comparison.

Motion (eq. 23, 24), period T (the CPI), target acceleration a_k ~ N(0, sigma_a^2), known own-sensor
input u_k (the relative acceleration the sensor's own motion adds, from its accelerometers):

    w_{k+1} = Phi w_k + g a_k + g u_k,   Phi = [[1, T], [0, 1]],   g = [T^2/2, T]
    Q = g g^T sigma_a^2 = [[T^4/4, T^3/2], [T^3/2, T^2]] sigma_a^2

Cells are numbered row-major, m = i * n_doppler + j, with i the range index and j the Doppler
index; cell (i, j) covers [r_min + i dr, r_min + (i+1) dr) x [v_min + j dv, v_min + (j+1) dv).

The simulator (``sim/range_doppler.py``) and the detector (``detection/``) share everything here:
the plane (:class:`RangeDopplerGrid`, declared as settings by :class:`CwPlaneSettings`), the motion
model and the known own-sensor inputs (:func:`own_accel_array`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import require
from sonartrack.core.settings import Settings, setting

#: resolution factors of a CW pulse (Nielsen 1991, via the paper, sec. V)
RANGE_CELL_FACTOR = 0.58
DOPPLER_CELL_FACTOR = 0.88


def cw_cell_sizes(pulse_s: float, carrier_hz: float, sound_speed_mps: float) -> tuple[float, float, float]:
    """Cell sizes of a CW pulse (paper P1, sec. V, after Nielsen 1991).

    ``dr = 0.58 tau c / 2``, ``df = 0.88 / tau``, ``dv = df c / (2 f_c)``.

    Parameters
    ----------
    pulse_s : float
        Pulse length tau (s).
    carrier_hz : float
        Carrier frequency f_c (Hz).
    sound_speed_mps : float
        Sound speed c (m/s).

    Returns
    -------
    tuple of float
        (range cell dr in m, Doppler cell df in Hz, range-rate cell dv in m/s).

    Raises
    ------
    InputError
        If any input is not positive.
    """
    require(pulse_s > 0 and carrier_hz > 0 and sound_speed_mps > 0,
            "pulse length, carrier frequency and sound speed must be positive")
    dr = RANGE_CELL_FACTOR * pulse_s * sound_speed_mps / 2.0
    df = DOPPLER_CELL_FACTOR / pulse_s
    dv = df * sound_speed_mps / (2.0 * carrier_hz)
    return dr, df, dv


def quantisation_covariance(range_cell_m: float, range_rate_cell_mps: float) -> np.ndarray:
    """``R = diag(dr^2/12, dv^2/12)``: covariance of a uniform error inside one cell (paper P1, eq. 25, corrected).

    Parameters
    ----------
    range_cell_m : float
        Range cell size dr (m).
    range_rate_cell_mps : float
        Range-rate cell size dv (m/s).

    Returns
    -------
    ndarray, shape (2, 2)
        R for the state [range, range-rate] (m^2, m^2/s^2).
    """
    return np.diag([range_cell_m**2 / 12.0, range_rate_cell_mps**2 / 12.0])


def printed_quantisation_covariance(pulse_s: float, carrier_hz: float, sound_speed_mps: float) -> np.ndarray:
    """Paper P1's eq. 25 exactly as printed, with the (2 c / f_c) typo: for documentation and tests only.

    Parameters
    ----------
    pulse_s, carrier_hz, sound_speed_mps : float
        As :func:`cw_cell_sizes`: pulse length tau (s), carrier f_c (Hz), sound speed c (m/s).

    Returns
    -------
    ndarray, shape (2, 2)
        The printed R (m^2, m^2/s^2); its range-rate variance is 16 times the correct one.
    """
    c = sound_speed_mps
    return np.diag([(0.58 * pulse_s) ** 2 * (c / 2.0) ** 2 / 12.0,
                    (0.88 / pulse_s) ** 2 * (2.0 * c / carrier_hz) ** 2 / 12.0])


def ar_transition(period_s: float) -> np.ndarray:
    """``Phi = [[1, T], [0, 1]]`` (2 x 2) for the state [range, range-rate] and the frame period T = ``period_s``
    (s) (paper P1, eq. 23)."""
    return np.array([[1.0, float(period_s)], [0.0, 1.0]])


def ar_input_gain(period_s: float) -> np.ndarray:
    """``g = [T^2/2, T]``: how an acceleration held over one period enters [range, range-rate] (paper P1, eq. 23).

    Parameters
    ----------
    period_s : float
        Frame period T (s).

    Returns
    -------
    ndarray, shape (2,)
        g (s^2, s).
    """
    T = float(period_s)
    return np.array([T * T / 2.0, T])


def ar_process_noise(period_s: float, sigma_a_mps2: float) -> np.ndarray:
    """``Q = [[T^4/4, T^3/2], [T^3/2, T^2]] sigma_a^2`` (paper P1, eq. 24).

    Parameters
    ----------
    period_s : float
        Frame period T (s).
    sigma_a_mps2 : float
        Standard deviation of the target's (range) acceleration (m/s^2).

    Returns
    -------
    ndarray, shape (2, 2)
        Q (m^2, m^2/s, m^2/s^2).
    """
    g = ar_input_gain(period_s)
    return np.outer(g, g) * float(sigma_a_mps2) ** 2


def own_accel_array(own_accel_mps2, n_frames: int) -> np.ndarray:
    """The K - 1 known own-sensor inputs u_k (paper P1, eq. 23) as an array.

    Parameters
    ----------
    own_accel_mps2 : None, float or sequence of float
        None: zeros; a scalar: constant; a sequence: one value per frame transition (m/s^2).
    n_frames : int
        K, the number of frames.

    Returns
    -------
    ndarray, shape (K - 1,)
        u_k (m/s^2).

    Raises
    ------
    InputError
        If a sequence has the wrong length or a non-finite value.
    """
    if own_accel_mps2 is None:
        return np.zeros(max(n_frames - 1, 0))
    u = np.atleast_1d(np.asarray(own_accel_mps2, dtype=float))
    if u.size == 1:
        return np.full(max(n_frames - 1, 0), float(u[0]))
    require(u.ndim == 1 and u.size == n_frames - 1,
            f"own-sensor acceleration needs K - 1 = {n_frames - 1} values (one per frame transition), got {u.size}")
    require(bool(np.all(np.isfinite(u))), "own-sensor acceleration values must be finite")
    return u


@dataclass(frozen=True, slots=True)
class RangeDopplerGrid:
    """An n_range x n_doppler plane of cells, its lower edges and cell sizes."""

    n_range: int
    n_doppler: int
    range_cell_m: float
    range_rate_cell_mps: float
    range_min_m: float = 0.0
    range_rate_min_mps: float = 0.0

    def __post_init__(self):
        require(self.n_range >= 1 and self.n_doppler >= 1, "the plane needs at least one range and one Doppler cell")
        require(self.range_cell_m > 0 and self.range_rate_cell_mps > 0, "cell sizes must be positive")

    @classmethod
    def cw(cls, n_range: int, n_doppler: int, pulse_s: float, carrier_hz: float, sound_speed_mps: float,
           range_min_m: float = 0.0, range_rate_min_mps: float | None = None) -> RangeDopplerGrid:
        """The plane of a CW pulse; by default the Doppler axis is centred on zero range-rate.

        Parameters
        ----------
        n_range, n_doppler : int
            Number of range and Doppler cells.
        pulse_s : float
            Pulse length (s).
        carrier_hz : float
            Carrier frequency (Hz).
        sound_speed_mps : float
            Sound speed (m/s).
        range_min_m : float, default 0.0
            Lower range edge of the first range cell (m).
        range_rate_min_mps : float, optional
            Lower range-rate edge of the first Doppler cell (m/s); None centres the axis on 0.

        Returns
        -------
        RangeDopplerGrid
            The plane, cell sizes from :func:`cw_cell_sizes`.
        """
        dr, _, dv = cw_cell_sizes(pulse_s, carrier_hz, sound_speed_mps)
        v0 = -0.5 * n_doppler * dv if range_rate_min_mps is None else float(range_rate_min_mps)
        return cls(int(n_range), int(n_doppler), dr, dv, float(range_min_m), v0)

    @property
    def n_cells(self) -> int:
        """Number of cells M = n_range * n_doppler."""
        return self.n_range * self.n_doppler

    @property
    def cell_area(self) -> float:
        """A = dr * dv (m^2/s), the area of one cell in the [range, range-rate] plane (eq. 19)."""
        return self.range_cell_m * self.range_rate_cell_mps

    @property
    def R(self) -> np.ndarray:
        """Quantisation covariance of one cell, diag(dr^2/12, dv^2/12) (m^2, m^2/s^2)."""
        return quantisation_covariance(self.range_cell_m, self.range_rate_cell_mps)

    def range_centres_m(self) -> np.ndarray:
        """Centres of the range cells.

        Returns
        -------
        ndarray, shape (n_range,)
            Range (m).
        """
        return self.range_min_m + (np.arange(self.n_range) + 0.5) * self.range_cell_m

    def range_rate_centres_mps(self) -> np.ndarray:
        """Centres of the Doppler cells, as range-rate.

        Returns
        -------
        ndarray, shape (n_doppler,)
            Range-rate (m/s).
        """
        return self.range_rate_min_mps + (np.arange(self.n_doppler) + 0.5) * self.range_rate_cell_mps

    def centres(self) -> np.ndarray:
        """Cell centres v_m, row-major (m = i * n_doppler + j).

        Returns
        -------
        ndarray, shape (M, 2)
            [range (m), range-rate (m/s)] of each cell's centre.
        """
        r, v = np.meshgrid(self.range_centres_m(), self.range_rate_centres_mps(), indexing="ij")
        return np.stack([r.ravel(), v.ravel()], axis=-1)

    def extent(self) -> tuple[float, float, float, float]:
        """Edges of the plane.

        Returns
        -------
        tuple of float
            (range min, range max, range-rate min, range-rate max) in m and m/s.
        """
        return (self.range_min_m, self.range_min_m + self.n_range * self.range_cell_m,
                self.range_rate_min_mps, self.range_rate_min_mps + self.n_doppler * self.range_rate_cell_mps)

    def cell_index(self, w) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Cells that contain the states w.

        Parameters
        ----------
        w : array_like, shape (..., 2)
            States [range (m), range-rate (m/s)].

        Returns
        -------
        i : ndarray of int64, shape (...)
            Range index, clipped to the plane.
        j : ndarray of int64, shape (...)
            Doppler index, clipped to the plane.
        inside : ndarray of bool, shape (...)
            True where the state lies on the plane.
        """
        w = np.asarray(w, dtype=float)
        i = np.floor((w[..., 0] - self.range_min_m) / self.range_cell_m).astype(np.int64)
        j = np.floor((w[..., 1] - self.range_rate_min_mps) / self.range_rate_cell_mps).astype(np.int64)
        inside = (i >= 0) & (i < self.n_range) & (j >= 0) & (j < self.n_doppler)
        return np.clip(i, 0, self.n_range - 1), np.clip(j, 0, self.n_doppler - 1), inside


class CwPlaneSettings(Settings):
    """Cell geometry of a CW pulse's range-Doppler plane (paper P1, sec. V); the plane's size comes
    from the frames (``detect``) or the scenario (the mftd study)."""

    pulse_s: float = setting(0.125, "CW pulse length tau (sets both cell sizes)", unit="s", gt=0, le=100)
    carrier_hz: float = setting(30e3, "carrier frequency f_c (Doppler cell to range-rate)", unit="Hz", gt=0,
                             le=1e7)
    sound_speed_mps: float = setting(1500.0, "sound speed c", unit="m/s", ge=1300, le=1700)
    range_min_m: float = setting(0.0, "lower range edge of the first range cell", unit="m")
    range_rate_min_mps: float | None = setting(
        None, "lower range-rate edge of the first Doppler cell (not set: the Doppler axis is centred on 0)",
        unit="m/s")

    def grid(self, n_range: int, n_doppler: int) -> RangeDopplerGrid:
        """The n_range x n_doppler plane of these cells (:meth:`RangeDopplerGrid.cw`).

        Parameters
        ----------
        n_range, n_doppler : int
            Number of range and Doppler cells.

        Returns
        -------
        RangeDopplerGrid
            The plane.
        """
        return RangeDopplerGrid.cw(n_range, n_doppler, self.pulse_s, self.carrier_hz, self.sound_speed_mps,
                                   self.range_min_m, self.range_rate_min_mps)
