"""Sound speed in seawater from temperature and salinity with TEOS-10 (``gsw``).

For each depth z (m, positive down) at latitude phi and longitude lambda:
    p  = gsw.p_from_z(-z, phi)                 sea pressure (dbar)
    SA = gsw.SA_from_SP(SP, p, lambda, phi)    absolute salinity from practical salinity
    CT = gsw.CT_from_t(SA, t, p)               conservative temperature from in-situ temperature
    c  = gsw.sound_speed(SA, CT, p)            (IOC, SCOR & IAPSO 2010, eq. 2.17.1)
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.errors import require


def sound_speed_from_ts(depth_m, temperature_c, salinity_psu, latitude_deg: float, longitude_deg: float) -> np.ndarray:
    """Sound speed from in-situ temperature and practical salinity with TEOS-10 (module docstring).

    Parameters
    ----------
    depth_m : array_like, shape (n,)
        Depths (m, positive down).
    temperature_c : array_like, shape (n,)
        In-situ temperature (deg C).
    salinity_psu : array_like, shape (n,)
        Practical salinity (PSU).
    latitude_deg : float
        Latitude (deg), for the pressure.
    longitude_deg : float
        Longitude (deg), for the absolute salinity.

    Returns
    -------
    ndarray, shape (n,)
        Sound speed (m/s).

    Raises
    ------
    InputError
        If the columns differ in length, hold NaN, or are not sea temperatures / practical salinities.
    """
    import gsw

    z = np.asarray(depth_m, dtype=float)
    t = np.asarray(temperature_c, dtype=float)
    sp = np.asarray(salinity_psu, dtype=float)
    require(z.shape == t.shape == sp.shape, "depth, temperature and salinity columns must have the same length")
    require(bool(np.all(np.isfinite(t)) and np.all(np.isfinite(sp))),
            "temperature/salinity contain NaN: fill or drop those rows")
    require(bool(np.all((t > -3) & (t < 40))),
            f"temperatures {t.min():.3g}..{t.max():.3g} are not sea temperatures in deg C (Fahrenheit or kelvin?)")
    require(bool(np.all((sp >= 0) & (sp < 45))),
            f"salinities {sp.min():.3g}..{sp.max():.3g} are not practical salinities "
            "(PSU, about 30-35 in the open sea)")
    p = gsw.p_from_z(-z, latitude_deg)
    sa = gsw.SA_from_SP(sp, p, longitude_deg, latitude_deg)
    ct = gsw.CT_from_t(sa, t, p)
    return np.asarray(gsw.sound_speed(sa, ct, p), dtype=float)
