"""The live active chain's source and receiver: an ActiveGeometry of the navigation fixes so far, grown fix by fix.

The active chain (systems/active/run.py ``_Chain``) reads its geometry -- source Tx and array centre Rx positions,
the array's heading, their velocities, the side of a position -- only at and before the ping it is running (the
velocities by a central difference of +-1 s, contacts.py :meth:`ActiveGeometry.velocity`). :class:`LiveGeometry`
answers these from the ship's fixes (systems/live/navigation.py :class:`LiveNavigation`: projected once each, as
the passive live chain takes them): the source ``source_tow_m`` and the array ``array_tow_m`` behind the ship along
its own track (io/nmea.py's tow model, the simulated scene's too: sim/active_scene.py), rebuilt when a fix has come.
A ping waits until the fixes reach one velocity step past it (:meth:`LiveGeometry.covers`); from then on the rows
the chain reads no longer change as fixes are added (the tow model looks back along the track only, and each
heading is the fix's own), so a live run on the growing fixes gives the chain the geometry the whole log gives.
"""

from __future__ import annotations

import numpy as np

from sonartrack.systems.active.contacts import ActiveGeometry
from sonartrack.systems.live.navigation import LiveNavigation

#: the half-width of ActiveGeometry.velocity's central difference (s): a ping needs fixes this far past it
VELOCITY_STEP_S = 1.0


class LiveGeometry:
    """Source, receiver and array heading from the live fixes (module doc); duck-typed as ActiveGeometry.

    Parameters
    ----------
    nav : LiveNavigation
        The ship's fixes as they come.
    source_tow_m, array_tow_m : float
        The source and the array centre behind the ship along its track (m).
    """

    def __init__(self, nav: LiveNavigation, source_tow_m: float, array_tow_m: float):
        self.nav, self.source_tow_m, self.array_tow_m = nav, float(source_tow_m), float(array_tow_m)
        self._built: tuple[int, ActiveGeometry | None] = (-1, None)

    def current(self) -> ActiveGeometry | None:
        """The ActiveGeometry of the fixes kept (None with fewer than two), rebuilt when a fix has come."""
        version = self.nav.version
        if self._built[0] != version:
            geometry = None
            if len(self.nav.fixes) >= 2:
                ship = self.nav.ship()
                tx, rx = self.nav.towed(self.source_tow_m, ship), self.nav.towed(self.array_tow_m, ship)
                geometry = ActiveGeometry(ship[0] - self.nav.start_utc.timestamp(), np.stack(tx[:2], axis=-1),
                                          np.stack(rx[:2], axis=-1), rx[2])
            self._built = (version, geometry)
        return self._built[1]

    def covers(self, t_s: float) -> bool:
        """Whether the fixes reach one velocity step past ``t_s`` (s): the chain's reads at ``t_s`` are final."""
        return self.current() is not None and self.nav.last_time_s() >= t_s + VELOCITY_STEP_S

    def ship_at(self, t_s: float) -> tuple[float, float, float] | None:
        """The ship's position (m) and heading (rad) at ``t_s`` (held at the last fix after it); None without fixes."""
        if len(self.nav.fixes) < 2:
            return None
        t, x, y, h = self.nav.ship()
        t = t - self.nav.start_utc.timestamp()
        return float(np.interp(t_s, t, x)), float(np.interp(t_s, t, y)), float(np.interp(t_s, t, h))

    # ActiveGeometry's interface (contacts.py), on the current geometry
    def tx_at(self, t):
        """Source position(s) (m) at time(s) ``t`` (s): ActiveGeometry.tx_at of the fixes so far."""
        return self.current().tx_at(t)

    def rx_at(self, t):
        """Array centre position(s) (m) at time(s) ``t`` (s): ActiveGeometry.rx_at of the fixes so far."""
        return self.current().rx_at(t)

    def heading_at(self, t):
        """Array axis heading(s) (rad, unwrapped) at ``t`` (s): ActiveGeometry.heading_at of the fixes so far."""
        return self.current().heading_at(t)

    def velocity(self, t, which: str, dt_s: float = VELOCITY_STEP_S):
        """Source ("tx") or array ("rx") velocity (m/s) at ``t``: ActiveGeometry.velocity of the fixes so far."""
        return self.current().velocity(t, which, dt_s)

    def side_of(self, t, xy):
        """+1 starboard / -1 port of positions ``xy`` at ``t``: ActiveGeometry.side_of of the fixes so far."""
        return self.current().side_of(t, xy)
