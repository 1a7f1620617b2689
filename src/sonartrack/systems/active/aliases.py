"""A line array's grating-lobe alias of an echo, and the chain's alias test built for a pulse on an array (the active
chain's tracker withholds the aliases of held echoes and of still clutter points: contact_tracker.py)."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from sonartrack.core.errors import require
from sonartrack.systems.active.settings import ActiveSettings


@dataclass(frozen=True, slots=True)
class EndfireAlias:
    """A line array's grating-lobe alias of an echo: a plane wave at u = cos(cone) is also passed by the beams at
    u +- lambda / d (the array factor sum_n exp(i 2 pi n d u / lambda) is periodic in u with period lambda / d, Van
    Trees, Optimum Array Processing, 2002, sec. 2.4, eq. 2.98), and a beam steered to u_b hears u within its main
    lobe |u - u_b| <= lambda / (N d) (the first null, eq. 2.96). At d = lambda / 2 the period is 2: an echo near
    one endfire (u ~ -1) is heard at the other (u ~ +1) at the same travel time, as strong as in its own beam (both
    endfire beams are the widest). A contact is an alias of an anchor when |u - u_a -+ lambda / d| <= lambda / (N d)
    and their bistatic ranges differ by at most ``range_m``.

    ``period_u`` lambda / d; ``lobe_u`` lambda / (N d); ``range_m`` the r_B window (m): the delay's resolution,
    c / (B sqrt(12)) with B the pulse's band (1 / tau for a CW), and not below the clutter map's image window.

    ``clutter_range_m`` the r_B window (m) about a contact the clutter map shows still (None: ``range_m``): c / B_i,
    B_i = min(B, f_0 / N), the image's own band (only there is it in the beam's main lobe, eq. 2.96 read in frequency;
    benchmarks/bench_active_family.py: study trial 18's images 1-32 m off their point's r_B, two false pairs)."""

    period_u: float
    lobe_u: float
    range_m: float
    clutter_range_m: float | None = None

    @classmethod
    def of(cls, wavelength_m: float, spacing_m: float, elements: int, resolution_m: float) -> EndfireAlias:
        """From the carrier's wavelength (m), the element spacing (m), their number and the r_B window (m)."""
        require(wavelength_m > 0 and spacing_m > 0 and elements >= 2 and resolution_m >= 0,
                "endfire alias: wavelength, spacing > 0, elements >= 2 and a window >= 0 are needed")
        return cls(wavelength_m / spacing_m, wavelength_m / (elements * spacing_m), float(resolution_m))

    def of_contacts(self, xy, tx_xy, rx_xy, heading_rad, anchor, range_m: float | None = None) -> np.ndarray:
        """(m,) bool: the contacts within the alias lobe and r_B window (``range_m``, m; None: the class's) of an
        ``anchor`` contact (class doc)."""
        xy, anchor = np.asarray(xy, float).reshape(-1, 2), np.asarray(anchor, bool)
        if not anchor.any():
            return np.zeros(len(xy), bool)
        d = xy - np.asarray(rx_xy, float)
        h = float(heading_rad)  # bearings clockwise from north: the array axis (sin h, cos h)
        u = (d[:, 0] * np.sin(h) + d[:, 1] * np.cos(h)) / np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-9)
        r_b = np.linalg.norm(xy - np.asarray(tx_xy, float), axis=1) + np.hypot(d[:, 0], d[:, 1])
        du = np.abs(np.abs(u[:, None] - u[None, anchor]) - self.period_u)
        near = np.abs(r_b[:, None] - r_b[None, anchor]) <= (self.range_m if range_m is None else float(range_m))
        return ((du <= self.lobe_u) & near).any(axis=1)


def endfire_alias_of(settings: ActiveSettings, waveform) -> EndfireAlias | None:
    """The chain's :class:`EndfireAlias` for ``waveform`` (carrier, and band: an LFM's swept band, a CW's 1 / tau)
    on ``settings``'s array, or None when ``endfire_alias`` is off; its r_B window c / (B sqrt(12)), not below the
    clutter map's ``clutter_map_image_m``; about the clutter map's anchors c / B_i, B_i = min(B, f_0 / N) the grating
    image's band (:class:`EndfireAlias` ``clutter_range_m``)."""
    if not settings.endfire_alias:
        return None
    c = float(settings.sound_speed_mps)
    band = waveform.bandwidth_hz if waveform.kind == "lfm" and waveform.bandwidth_hz > 0 else 1.0 / waveform.duration_s
    window = max(c / (band * np.sqrt(12.0)), settings.clutter_map_image_m or 0.0)
    alias = EndfireAlias.of(c / waveform.carrier_hz, float(settings.spacing_m), int(settings.elements), window)
    image_band = min(band, waveform.carrier_hz / int(settings.elements))  # the grating image's own band (class doc)
    return replace(alias, clutter_range_m=max(window, c / image_band))
