"""The active chain's tracker on contacts: P4's IMM-IPDA per ping with the gates in front of it (range rate, decided
sides, clutter map) and the mirror-pair deleters behind it (stages 4-5 of systems/active/run.py's module doc), and
:func:`track_detections`, stages 3-5 on stored detections (the study tracks one set of detections with several
trackers)."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from sonartrack.core.errors import require
from sonartrack.detection.cells import Detections
from sonartrack.systems.active.aliases import EndfireAlias, endfire_alias_of  # noqa: F401 (the chain's names)
from sonartrack.systems.active.contacts import (
    ActiveGeometry,
    Contacts,
    form_contacts,
    in_position_gate,
    range_rate_gate,
    resolve_mirrors,
)
from sonartrack.systems.active.cw_tracking import cw_clutter_area
from sonartrack.systems.active.ridge_skirt import (
    RIDGE_HOLD_PROBABILITY,
    RIDGE_SKIRT_DENSITY,
    RidgePlaces,
    skirt_density,
)
from sonartrack.systems.active.settings import ActiveSettings
from sonartrack.systems.active.sides import GhostDeleter, SideDecisions, SideTracker
from sonartrack.tracking.deleters import listed_tracks
from sonartrack.tracking.run import PositionTracks
from sonartrack.tracking.settings import PositionTrackerSettings


@dataclass(frozen=True, slots=True)
class ActiveTracks:
    """The tracker's output, one row per live track per ping: ``tracks`` (tracking/run.py :class:`PositionTracks`)
    and ``P (n, 4, 4)`` the combined covariances (m^2, m^2/s, m^2/s^2) of the same rows (ellipses, sds);
    ``sides`` the side decision of each confirmed track (sides.py); ``joins`` (track id, earlier track id) pairs: a
    confirmed track deleted as the duplicate of another (tracking/duplicates.py), or confirmed soon after a confirmed
    track was lost and passing the track-to-track test against that track's prediction (:class:`ContactTracker`
    ``rejoin_s``), is a later segment of the same target (targets.py lists them as one)."""

    tracks: PositionTracks
    P: np.ndarray
    sides: SideDecisions | None = None
    joins: tuple | dict | None = None  # (later track, earlier track) pairs of one target (merged into / re-joined)

    def __len__(self) -> int:
        return len(self.tracks)




class ContactTracker:
    """P4's IMM-IPDA over the pings' contacts, with the range-rate gate in front (stages 4-5 of the module doc).

    Parameters
    ----------
    settings : PositionTrackerSettings
        The tracker.
    geometry : ActiveGeometry
        Source and receiver (their velocities enter the predicted range rate).
    gate_sigma : float or None
        Width of the range-rate gate in standard deviations (None: no gate).
    rate_sd_mps : float
        Standard deviation of a measured range rate (m/s): a Doppler cell / sqrt(12).
    side_turn_deg : float or None
        A confirmed track that has lived through this much change of the array's heading has its side decided
        by the likelihood ratio of sides.py; a track on its target's side then has the mirror contacts of the
        detections it gates dropped (contacts.py :func:`resolve_mirrors`), a ghost the contacts in its gate;
        None: the decisions are reported only, both mirror contacts always go to the tracker.
    merge_probability : float or None
        Gate probability of the track-to-track test (tracking/duplicates.py) by which a track that follows the
        same target as a confirmed one is deleted after each scan; None: no merging.
    max_range_rate_mps : float or None
        The range rates searched span +-this (m/s): a contact's measured range rate (a CW's) multiplies its
        likelihood ratio by its Gaussian likelihood over this uniform clutter law (tracking/measurements.py
        :class:`RangeRatePositionMeasurements`); None: position only.
    clutter_area_m2 : float or None
        The area the contacts can fall in (m^2): the clutter density of each scan is then the contacts' own,
        lambda = (contacts so far + 1) / ((scans so far + 1) area) (the nonparametric density of the PDA,
        Bar-Shalom, Willett, Tian 2011, sec. 3.4.2, pooled over the scans), not ``settings``'s: a CW gives ~100 times
        fewer contacts than the LFM P4's 1e-6 was tuned on (measured on the default scene as CW, 900 s, single-ping
        detections: 6.4 contacts a ping over ~1.6e9 m^2, 4e-9; with 1e-6 no track was confirmed, with 1e-8 the
        strongest target was held 87 % of the pings, no false track). None: the setting's.
    turns : TurnModes or None
        Coordinated-turn modes added to the tracker's IMM (tracking/configurations.py ``position_motion``);
        None: the settings' CV modes only.
    clutter_map : ClutterMap or None
        detection/clutter_map.py: a contact at a recurring still world position goes only to the confirmed tracks
        whose gate holds it (a confirmed track keeps its contacts when its target slows, stops or crosses a
        clutter point); None: no map.
    scan_interval_s : float or None
        The ping interval (s): the stated false-track rate per hour to one per scan (``false_tracks_per_h``); None
        (a single ping): the settings' ``confirm_threshold``.
    rejoin_s : float or None
        A track confirmed within this time (s) of the loss of a confirmed track (deleted for its existence), whose
        state passes the track-to-track test (tracking/duplicates.py, gate ``merge_probability``, 0.99 when not set)
        against that track's last state predicted to now (CV with the straight-running, smallest q: with the largest
        a target appearing 3 km off a lost one was joined to it in tests/systems/active/test_rows_join.py), is
        recorded as the same target's next segment (``ActiveTracks.joins``; the nearest such lost track, each once);
        None: no re-joining. (A re-join onto the reflection of a lost track, the other hypothesis, was tried: with
        the duplicate merges it chained two crossing targets into one row on the default scene as CW, seed 1.)
    claims : {"confirmed", "all"} or None
        Contacts shared by rank (tracking/associators.py :class:`ClaimedPDA`): a track is given a contact only as
        far as no track ranked above it claims it; "confirmed": the confirmed tracks claim from the tentative ones
        (a new track in a confirmed track's gate gains no existence on the contacts that track takes), "all": every
        track claims from those ranked below it (confirmed first, then by existence); None: each track on its own
        (IPDA).
    keep_apart : bool
        Two confirmed tracks once told apart by the track-to-track test while both held their targets are never
        merged as duplicates (tracking/duplicates.py ``keep_apart``), unless reunited: ``reunite_scans``.
    reunite_scans : int
        Scans in a row on which a told-apart pair passes the test on position and velocity and shares its nearest
        contact before it is merged after all (tracking/duplicates.py ``reunite_scans``; 0: never).
    endfire_alias : EndfireAlias or None
        The line array's grating-lobe alias of a held echo withheld (:meth:`_not_images`); None: not.
    ridge_window : tuple of float or None
        (bistatic range m, range rate m/s): a contact within both of a ridge echo the ridge map shows still is
        that echo's skirt or sidelobe image (clutter_map.py :func:`echo_images`; systems/active/cw_tracking.py
        ``cw_ridge_window``); None: only the contacts in the gate of the ridge map's known points.
    ridge_map : ClutterMap or None
        The clutter map of the echoes under a CW's ridge notch (:meth:`_ridge_clutter`, :func:`ridge_map_of`);
        None: the ridge echoes given to :meth:`step` are ignored. With ``clutter_map`` and ``ridge_window`` also set,
        the places where those echoes recur before the map shows them still (ridge_skirt.py) hold a slow track's
        new confirmation in their skirt until its speed shows it moving (``ridge_hold``, a second StillHold) and
        raise the clutter density its contacts there are scored against (:meth:`_skirt_density`).
    """

    def __init__(self, settings: PositionTrackerSettings, geometry: ActiveGeometry, gate_sigma: float | None,
                 rate_sd_mps: float, side_turn_deg: float | None = None, merge_probability: float | None = None,
                 max_range_rate_mps: float | None = None, turns=None, clutter_area_m2: float | None = None,
                 clutter_map=None, scan_interval_s: float | None = None, rejoin_s: float | None = None,
                 claims: str | None = None, keep_apart: bool = False, endfire_alias: EndfireAlias | None = None,
                 reunite_scans: int = 0, ridge_window: tuple[float, float] | None = None, ridge_map=None):
        from sonartrack.association.gating import gate_threshold
        from sonartrack.tracking.configurations import position_tracker
        from sonartrack.tracking.duplicates import DuplicateMerger

        self.settings, self.geometry, self.gate_sigma, self.rate_sd = settings, geometry, gate_sigma, rate_sd_mps
        self.side_turn = None if side_turn_deg is None else float(np.deg2rad(side_turn_deg))
        self.clutter_area, self._counts = clutter_area_m2, [0, 0]  # (contacts, scans) so far
        self.endfire_alias, self.claims = endfire_alias, claims
        if claims is not None:
            from sonartrack.tracking.associators import ClaimedPDA

            require(claims in ("confirmed", "all", "lm"), f"claims must be 'confirmed', 'all', 'lm' or None, not "
                                                           f"{claims!r}")
        self.tracker = position_tracker(settings, turns=turns, associator=None if claims is None else ClaimedPDA(
            linear_multitarget=claims == "lm"))
        _measurement_part(self.tracker, settings, rate_sd_mps, max_range_rate_mps)
        if settings.false_tracks_per_h is not None and scan_interval_s is not None:  # at the stated rate
            self.tracker.deleter = _rate_confirmation(settings, scan_interval_s)
        self.clutter_map, self.hold = clutter_map, None
        self.ridge_window, self.ridge_map, self.ridge_counts = ridge_window, ridge_map, [0, 0]  # counts: _ridge_clutter
        self._scan_lam = float(settings.clutter_density_per_m2)  # the scan's mean density (_skirt_density)
        if clutter_map is not None:  # a slow track on a recurring position waits for the map or its own speed
            from sonartrack.tracking.deleters import StillHold

            self.hold = self.tracker.deleter = StillHold(self.tracker.deleter, clutter_map.slow_mps,
                                                         gate_threshold(settings.gate_probability, 2))
        self.ridge_hold, self.ridge_places = None, None  # a slow track on a recurring hidden echo's skirt waits
        if clutter_map is not None and ridge_map is not None and ridge_window is not None:  # (ridge_skirt.py)
            self.ridge_places = RidgePlaces(ridge_window[0])
            self.ridge_hold = self.tracker.deleter = StillHold(self.tracker.deleter, clutter_map.slow_mps,
                                                               gate_threshold(settings.gate_probability, 2),
                                                               gate_threshold(RIDGE_HOLD_PROBABILITY, 2))
        if merge_probability is not None:
            self.tracker.deleter = DuplicateMerger(self.tracker.deleter, gate_threshold(merge_probability, 4),
                                                   settings.merge_confirmed_scans,
                                                   history_scans=settings.merge_history_scans,
                                                   keep_apart=keep_apart, reunite_scans=reunite_scans,
                                                   velocity_gamma=gate_threshold(merge_probability, 2))
        self.merger = self.tracker.deleter if merge_probability is not None else None
        self.rejoin_s, self.joins = rejoin_s, {}
        self.rejoin_gamma = gate_threshold(merge_probability or 0.99, 4)
        self._lost: dict[int, tuple[float, np.ndarray, np.ndarray]] = {}  # id -> (time s, x, P) at its last scan
        self._confirmed: dict[int, tuple[float, np.ndarray, np.ndarray]] = {}  # the last scan's confirmed tracks
        self.sides = SideTracker(settings.gate_probability, self.side_turn or 0.0, q=max(settings.q))
        self.ghosts = None
        if self.side_turn is not None:  # a track decided a ghost (its target's mirror) is deleted or reflected
            self.ghosts = self.tracker.deleter = GhostDeleter(self.tracker.deleter, self.sides)
        self._last_t: float | None = None
        self._rows: dict[str, list] = {k: [] for k in ("time_s", "track_id", "confirmed", "existence", "x", "P", "mu")}

    def _predicted_confirmed(self, t_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Confirmed tracks' combined states and covariances predicted to ``t_s`` (CV with the largest q), and
        their ids."""
        from sonartrack.tracking.tracks import TrackSnapshot

        T = self.tracker.tracks
        if not len(T) or not T.confirmed.any() or self._last_t is None:
            return np.zeros((0, 4)), np.zeros((0, 4, 4)), np.zeros(0, np.int64)
        snap = TrackSnapshot.of(self._last_t, T.select(T.confirmed))
        dt, q = t_s - self._last_t, max(self.settings.q)
        F = np.eye(4)
        F[0, 2] = F[1, 3] = dt
        Q = q * np.kron(np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]]), np.eye(2))
        return snap.x @ F.T, F @ snap.P @ F.T + Q, snap.track_id

    def _gates(self, t_s: float, contacts: Contacts) -> np.ndarray:
        """The range-rate gate and the resolved sides' mirror drop (True: the contact goes to the tracker)."""
        keep = np.ones(len(contacts), bool)
        if not len(contacts) or (self.gate_sigma is None and self.side_turn is None):
            return keep
        x, P, ids = self._predicted_confirmed(t_s)
        g, pg = self.geometry, self.settings.gate_probability
        if self.gate_sigma is not None:
            tx = (g.tx_at(t_s), g.velocity(t_s, "tx"))
            rx = (g.rx_at(t_s), g.velocity(t_s, "rx"))
            keep &= range_rate_gate(contacts, self.rate_sd, x, P, tx, rx, n_sigma=self.gate_sigma, gate_probability=pg)
        if self.side_turn is not None and len(ids):
            d = np.array([self.sides.decision(int(i)) for i in ids])
            keep &= resolve_mirrors(contacts, x[d > 0], P[d > 0], pg)
            if (d < 0).any():  # a ghost's contacts (unless a decided track holds them too) go to no track
                gate = in_position_gate(contacts, x, P, pg)
                keep &= ~(gate[d < 0].any(axis=0) & ~gate[d > 0].any(axis=0))
        return keep

    def _not_clutter(self, t_s: float, contacts: Contacts, ridge: Contacts | None = None) -> np.ndarray:
        """The clutter map's verdict (detection/clutter_map.py): a contact at a world position that recurs ping after
        ping, still, its mirror twin, the weaker contacts at a recurring contact's bistatic range (lobe images,
        clutter_map.py :func:`same_range`) and the grating images of a still one (:class:`EndfireAlias`
        ``clutter_range_m``; still, not recurring: a moving target's echo and its image both recur) go only to the
        confirmed tracks whose gate holds them (True: not withheld); and on a CW the contacts :meth:`_ridge_clutter`
        finds from the echoes under the ridge notch."""
        keep = np.ones(len(contacts), bool)
        if self.clutter_map is None:
            return keep
        cm = self.clutter_map
        clutter = cm.update(contacts.xy, contacts.R, float(t_s))
        r, still = cm.recurring, clutter.copy()
        if cm.image_range_m is not None:  # a still point's mirror twin, a recurring echo's lobe images (same_range)
            from sonartrack.detection.clutter_map import same_range

            g = self.geometry
            clutter = clutter | np.isin(contacts.detection, contacts.detection[clutter]) | same_range(
                contacts.xy, g.tx_at(t_s), g.rx_at(t_s), r, contacts.statistic, cm.image_range_m)
        if self.endfire_alias is not None and still.any():  # a still echo's grating image, whatever its strength
            g, al = self.geometry, self.endfire_alias
            clutter = clutter | al.of_contacts(contacts.xy, g.tx_at(t_s), g.rx_at(t_s), g.heading_at(t_s), still,
                                               al.clutter_range_m)
        if ridge is not None and self.ridge_map is not None:
            clutter = clutter | self._ridge_clutter(float(t_s), contacts, ridge)
        self.hold.recurring(contacts.xy[r], contacts.R[r])
        if self.ridge_hold is not None:
            self.ridge_hold.recurring(*self._ridge_places(float(t_s), ridge))
        if clutter.any():
            x, P, _ = self._predicted_confirmed(t_s)
            held = in_position_gate(contacts, x, P, self.settings.gate_probability).any(axis=0) if len(x) else False
            keep &= ~clutter | held
        return keep

    def _ridge_clutter(self, t_s: float, contacts: Contacts, ridge: Contacts) -> np.ndarray:
        """(m,) bool: the contacts a still point hidden under a CW's ridge notch explains. ``ridge`` (the ping's
        echoes under the notch, detection/cw_cells.py ``ridge_echoes``) feeds the ridge map (its own clutter map, so
        that the sea's ridge peaks and the tracker's contacts do not make hits for each other); a contact is clutter
        when it lies in the gate of a point that map knows still, or within ``ridge_window`` of an echo it shows still
        at this ping (clutter_map.py :func:`echo_images`: the echo's skirt past the notch and its sidelobe images).
        ``ridge_counts`` adds up the ridge contacts shown still and the contacts marked."""
        from sonartrack.detection.clutter_map import echo_images, mahalanobis2

        rm, g = self.ridge_map, self.geometry
        still = rm.update(ridge.xy, ridge.R, t_s)
        out = np.zeros(len(contacts), bool)
        kxy, kR, _ = rm.known
        if len(kxy) and len(contacts):
            out |= (mahalanobis2(contacts.xy, contacts.R, kxy, kR) <= rm.gamma).any(axis=1)
        if still.any() and self.ridge_window is not None:
            out |= echo_images(contacts.xy, contacts.range_rate_mps, g.tx_at(t_s), g.rx_at(t_s), ridge.xy[still],
                               ridge.range_rate_mps[still], *self.ridge_window)
        self.ridge_counts[0] += int(still.sum())
        self.ridge_counts[1] += int(out.sum())
        return out

    def _ridge_places(self, t_s: float, ridge: Contacts | None) -> tuple[np.ndarray, np.ndarray]:
        """The places where this CW's hidden ridge echoes recur, widened by their skirt (ridge_skirt.py
        :class:`RidgePlaces`): positions (k, 2) m and covariances (k, 2, 2) m^2."""
        rm, g = self.ridge_map, self.geometry
        recurring = rm.recurring if ridge is not None and len(rm.recurring) == len(ridge) else None
        return self.ridge_places.update(t_s, ridge, recurring, g.tx_at(t_s), g.rx_at(t_s), rm.span,
                                        getattr(rm, "_step_s", None) or 0.0)

    def _skirt_density(self, t_s: float, m, contacts: Contacts):
        """The measurement part ``m`` with each contact's own clutter density where it lies in a recurring hidden
        ridge echo's skirt (ridge_skirt.py :func:`skirt_density`) and in no confirmed track's gate (a confirmed
        track keeps its contacts' odds, as it keeps the clutter map's contacts: a target whose own echo sits on the
        ridge recurs there too; study active-chain trial 15 with its targets, the maneuvering target's held pings
        69 -> 43 without this exception); ``m`` itself where none does."""
        if not RIDGE_SKIRT_DENSITY or self.ridge_hold is None or not len(contacts):
            return m
        h = self.ridge_hold
        rho = skirt_density(contacts.xy, contacts.R, h.xy, h.R, float(m.clutter_density_per_m2), h.gamma)
        if rho is None:
            return m
        x, P, _ = self._predicted_confirmed(t_s)
        if len(x):
            held = in_position_gate(contacts, x, P, self.settings.gate_probability).any(axis=0)
            rho = np.where(held, float(m.clutter_density_per_m2), rho)
        return replace(m, clutter_density_per_m2=rho)

    def _not_images(self, t_s: float, contacts: Contacts) -> np.ndarray:
        """The lobe images of confirmed targets' echoes withheld (True: not withheld): a contact in no confirmed
        track's gate that starts and feeds no track when (a) it is weaker than a contact in a confirmed track's gate
        and within the clutter map's ``image_range_m`` of its bistatic range (clutter_map.py :func:`same_range`: a
        strong echo's images share its travel time), as the map does for recurring still echoes; measured on the
        default scene (LFM, seeds 1 and 2): crossing-b at 44 dB echo SNR near the aft endfire gave a false track of
        16 pings at the fore endfire, at its bistatic range within 8 m; or (b) it is the array's grating-lobe alias of
        such a held contact (:class:`EndfireAlias`), whatever its strength: on the default scene as CW (seed 1)
        crossing-b near the aft endfire (cone 160-195 deg) was heard at the fore endfire at 0.8-2.9 times its
        statistic and 2-97 m of its r_B (a 1 s CW's delay known to ~430 m), and the images made a false row of
        pings 100-119 that (a) did not withhold."""
        keep = np.ones(len(contacts), bool)
        tol = None if self.clutter_map is None else self.clutter_map.image_range_m
        if (tol is None and self.endfire_alias is None) or not len(contacts):
            return keep
        x, P, _ = self._predicted_confirmed(t_s)
        if not len(x):
            return keep
        from sonartrack.detection.clutter_map import same_range

        held = in_position_gate(contacts, x, P, self.settings.gate_probability).any(axis=0)
        g = self.geometry
        image = np.zeros(len(contacts), bool)
        if tol is not None:
            image |= same_range(contacts.xy, g.tx_at(t_s), g.rx_at(t_s), held, contacts.statistic, tol)
        if self.endfire_alias is not None:
            image |= self.endfire_alias.of_contacts(contacts.xy, g.tx_at(t_s), g.rx_at(t_s), g.heading_at(t_s), held)
        return ~(image & ~held)

    def _cw_pd(self, contacts: Contacts) -> None:
        """From the first scan whose contacts carry a measured range rate (a CW pulse's Doppler), the tracker's
        detection probability is the settings' ``pd_cw`` (when set): a CW echo is reverberation-limited, its Pd per
        detectable ping measured 0.30-0.64 on the default scene (ACTCW, seed 1, MFTD + strong single-ping), about
        half the LFM's, and with the LFM's pd each miss lowers a CW track's existence too far (IPDA's miss factor
        1 - pd P_G, Musicki, Evans, Stankovic 1994, eq. 29): its tracks coast out in the 2-4 ping gaps and restart."""
        pd = self.settings.pd_cw
        m = self.tracker.measurements
        if pd is None or m.pd == pd or not np.isfinite(contacts.range_rate_mps).any():
            return
        self.tracker.measurements = replace(m, pd=float(pd))

    def step(self, t_s: float, contacts: Contacts, ridge: Contacts | None = None) -> np.ndarray:
        """One ping's scan; returns the contacts' verdict (True: given to the tracker; False: refused by the
        range-rate gate or the mirror of a resolved side).

        Parameters
        ----------
        t_s : float
            The scan time (s), the ping's transmit time.
        contacts : Contacts
            The ping's mirror-pair contacts (positions m, covariances m^2).
        ridge : Contacts, optional
            The mirror-pair contacts of the ping's echoes hidden by a CW's ridge notch: for the ridge map only
            (:meth:`_ridge_clutter`), never the tracker.

        Returns
        -------
        numpy.ndarray
            (m,) bool verdict per contact (False also: a clutter-map contact outside every confirmed track's gate).
        """
        keep = (self._gates(t_s, contacts) & self._not_clutter(t_s, contacts, ridge)
                & self._not_images(t_s, contacts))
        self._cw_pd(contacts)
        if hasattr(self.tracker.measurements, "at_scan"):
            g, lam = self.geometry, None
            if self.clutter_area is not None:
                self._counts = [self._counts[0] + int(keep.sum()), self._counts[1] + 1]
                lam = (self._counts[0] + 1) / ((self._counts[1] + 1) * self.clutter_area)
            m = self.tracker.measurements
            if np.ndim(m.clutter_density_per_m2):  # last scan's per-contact densities: back to the scan's own
                m = replace(m, clutter_density_per_m2=self._scan_lam)
            m = m.at_scan((g.tx_at(t_s), g.velocity(t_s, "tx")), (g.rx_at(t_s), g.velocity(t_s, "rx")),
                          contacts.range_rate_mps[keep], lam)
            self._scan_lam = float(m.clutter_density_per_m2)
            self.tracker.measurements = self._skirt_density(t_s, m, contacts.rows(keep))
        if self.ghosts is not None:  # the axis a ghost is reflected about at this scan (sides.py GhostDeleter)
            self.ghosts.axis = (np.asarray(self.geometry.rx_at(t_s), float), float(self.geometry.heading_at(t_s)))
        if self.claims is not None:  # the ranks and claimers before the scan (tracking/associators.py ClaimedPDA)
            T = self.tracker.tracks
            if self.claims == "confirmed":  # confirmed over tentative only (confirmed tracks not ranked among them)
                self.tracker.associator.set_tracks(T.existence, T.confirmed.astype(float), T.mu, T.confirmed)
            else:
                self.tracker.associator.set_tracks(T.existence, 2.0 * T.confirmed + T.existence, T.mu,
                                                   np.ones(len(T), bool))
        if self.merger is not None:  # the scan's contacts, for a told-apart pair's reunion (duplicates.py)
            self.merger.contacts[:] = [contacts.xy[keep], contacts.R[keep]]
        amplitude = contacts.statistic[keep] if "amplitude" in self.tracker.measurements.scan_needs else None
        snap = self.tracker.step(t_s, contacts.xy[keep], contacts.R[keep], amplitude)
        self._last_t = float(t_s)
        c = snap.confirmed
        self.sides.update(float(t_s), float(self.geometry.heading_at(t_s)), contacts, snap.track_id[c], snap.x[c],
                          snap.P[c], self.geometry.side_of)
        if self.rejoin_s is not None:
            self._rejoin(float(t_s), snap)
        r = self._rows
        listed = listed_tracks(snap.confirmed, snap.existence, self.settings.listed_existence)  # the rows shown
        for k, v in (("track_id", snap.track_id), ("confirmed", listed), ("existence", snap.existence),
                     ("x", snap.x), ("P", snap.P), ("mu", snap.mu)):
            r[k].append(v)
        r["time_s"].append(np.full(len(snap.track_id), float(t_s)))
        return keep

    def _rejoin(self, t_s: float, snap) -> None:
        """Record the re-joins of this scan's newly confirmed tracks onto lost ones (``rejoin_s``, class doc)."""
        from sonartrack.systems.active.sides import _predict

        c = np.nonzero(snap.confirmed)[0]
        now = {int(snap.track_id[k]): (t_s, snap.x[k], snap.P[k]) for k in c}
        merged = self.merger.merged if self.merger is not None else {}
        for tid, state in self._confirmed.items():
            if tid not in now and tid not in merged and not self.sides.rejected(tid):
                self._lost[tid] = state
        self._lost = {k: v for k, v in self._lost.items() if t_s - v[0] <= self.rejoin_s}
        for tid, (_, x, P) in now.items():
            if tid in self._confirmed or not self._lost:
                continue
            best, d2_best = None, self.rejoin_gamma
            for old, (t0, x0, P0) in self._lost.items():
                xp, Pp = _predict(x0, P0, t_s - t0, min(self.settings.q))
                nu = x - xp
                d2 = float(nu @ np.linalg.solve(P + Pp, nu))
                if d2 < d2_best:
                    best, d2_best = old, d2
            if best is not None:
                self.joins[tid] = best
                self.sides.carry(tid, best)  # the lost segment's side evidence goes on with this one (sides.py)
                del self._lost[best]
        self._confirmed = now

    def result(self) -> ActiveTracks:
        """Every ping's live tracks (:class:`ActiveTracks`).

        Returns
        -------
        ActiveTracks
            The tracks of every scan so far (states [x, y, vx, vy] in m and m/s, covariances, mode probabilities) and
            the side decisions.
        """
        r, n_modes = self._rows, len(self.settings.q)

        def cat(k, empty):
            return np.concatenate(r[k]) if r[k] else empty

        P = cat("P", np.zeros((0, 4, 4)))
        tracks = PositionTracks(cat("time_s", np.zeros(0)), cat("track_id", np.zeros(0, np.int64)),
                                cat("confirmed", np.zeros(0, bool)), cat("existence", np.zeros(0)),
                                cat("x", np.zeros((0, 4))), np.sqrt(P[:, 0, 0]), np.sqrt(P[:, 1, 1]),
                                cat("mu", np.zeros((0, n_modes))))
        return ActiveTracks(tracks, P, self.sides.result(), self.join_links())

    def join_links(self) -> tuple[tuple[int, int], ...]:
        """Every (later track, earlier track) link of one target so far: the merges (a confirmed track deleted as
        the duplicate of another) and the re-joins (``rejoin_s``). A track can have both (re-joined onto a lost
        track, then merged into a third: seen on the default scene as CW, seed 2), so they are pairs, not a dict
        keyed by the later track, where one link would overwrite the other."""
        merged = self.merger.merged if self.merger is not None else {}
        return tuple(sorted({(int(a), int(b)) for a, b in (*merged.items(), *self.joins.items())}))

    def drop_scans(self, n: int) -> None:
        """Forget the rows of the oldest ``n`` scans (the live chain's bounded history, systems/live/active.py):
        :meth:`result` then holds the scans since; the live tracks and the side decisions are untouched."""
        for rows in self._rows.values():
            del rows[:max(int(n), 0)]


def _measurement_part(tracker, settings: PositionTrackerSettings, rate_sd_mps: float,
                      max_range_rate_mps: float | None) -> None:
    """The tracker's measurement part: range rate measured (CW) where a largest range rate is given, each contact's
    detection statistic weighed (tracking/amplitude_parts.py) where ``amplitude_aided`` says so."""
    if max_range_rate_mps is not None:
        from sonartrack.tracking.measurements import RangeRatePositionMeasurements

        m = tracker.measurements
        tracker.measurements = RangeRatePositionMeasurements(m.pd, m.gate_probability, m.clutter_density_per_m2,
                                                             rate_sd_mps, float(max_range_rate_mps))
    if settings.amplitude_aided:
        from sonartrack.tracking.amplitude_parts import with_amplitude

        with_amplitude(tracker, settings)


def _rate_confirmation(settings: PositionTrackerSettings, scan_interval_s: float):
    """Confirmation at the stated false-track rate (tracking/existence.py; one ping: no rate), after
    ``confirm_min_hits`` hits where more than one is asked."""
    from sonartrack.tracking.deleters import MinHits, RateConfirmation

    deleter = RateConfirmation(settings.false_tracks_per_h, scan_interval_s, settings.initial_existence,
                               settings.terminate_threshold, statistic=settings.confirm_statistic)
    return MinHits(deleter, settings.confirm_min_hits) if settings.confirm_min_hits > 1 else deleter

def rate_sd_of(cells_range_rate_mps) -> float:
    """Standard deviation of a measured range rate: one Doppler cell / sqrt(12) (uniform within the cell); 1 m/s
    when the pulse measures none (the gate then skips those contacts anyway).

    Parameters
    ----------
    cells_range_rate_mps : array
        Range rate (m/s) of each Doppler cell, evenly spaced; NaN or fewer than two cells when none is measured.

    Returns
    -------
    float
        Standard deviation (m/s).
    """
    v = np.asarray(cells_range_rate_mps, float)
    if len(v) < 2 or not np.all(np.isfinite(v)):
        return 1.0
    return float(abs(v[1] - v[0]) / np.sqrt(12.0))


def track_detections(detections: Detections, ping_time_s, geometry: ActiveGeometry, settings: ActiveSettings, *,
                     tracker: PositionTrackerSettings | None = None, rate_sd_mps: float = 1.0,
                     beam_step_deg: float | None = None, ping_numbers=None) -> tuple[Contacts, np.ndarray,
                                                                                      ActiveTracks]:
    """Stages 3-5 on stored detections: mirror contacts, range-rate gate, IMM-IPDA (module doc).

    Parameters
    ----------
    detections : Detections
        Detections of the pings, sorted by ping.
    ping_time_s : array
        Transmit time of each ping (s); every ping is a scan, with or without contacts.
    geometry : ActiveGeometry
        Source, receiver and array heading.
    settings : ActiveSettings
        The chain (sound speed, contact errors, gate, tracker).
    tracker : PositionTrackerSettings, optional
        Another tracker than ``settings``'s (e.g. one IPDA mode), without the settings' turn modes.
    rate_sd_mps : float
        Standard deviation of a measured range rate (m/s).
    beam_step_deg : float, optional
        The beams' cone-angle step (deg): the default cone-angle error of a contact.
    ping_numbers : array, optional
        The number of each ping (default 0, 1, 2, ...), as the detections' ``ping``.

    Returns
    -------
    tuple
        (contacts, gate verdict per contact, tracks).
    """
    t = np.asarray(ping_time_s, float)
    numbers = np.arange(len(t)) if ping_numbers is None else np.asarray(ping_numbers, np.int64)
    contacts = form_contacts(detections, t, geometry, settings.sound_speed_mps, settings.contacts, beam_step_deg,
                             numbers)
    trk = ContactTracker(tracker or settings.tracker_settings(), geometry, settings.range_rate_gate_sigma,
                         rate_sd_mps, settings.side_turn_deg, settings.merge_probability, settings.max_range_rate_mps,
                         turns=settings.turn_modes() if tracker is None else None,
                         clutter_area_m2=cw_clutter_area(detections, settings.sound_speed_mps),
                         clutter_map=clutter_map_of(settings),
                         scan_interval_s=float(np.median(np.diff(t))) if len(t) > 1 else None,
                         rejoin_s=settings.rejoin_s, claims=settings.contact_claims,
                         keep_apart=settings.merge_keep_apart, reunite_scans=settings.merge_reunite_scans)
    bounds = np.searchsorted(contacts.ping, np.append(numbers, numbers[-1] + 1 if len(numbers) else 0))
    keep = np.concatenate([trk.step(float(t[k]), contacts.rows(slice(bounds[k], bounds[k + 1])))
                           for k in range(len(t))]) if len(t) else np.zeros(0, bool)
    return contacts, keep, trk.result()


#: a ridge echo is a still point's only when its place recurs on this many of the ridge map's remembered pings (the
#: tracker's map: clutter_map_hits, 3): the sea's own ridge peaks above the threshold, 7-22 a ping (default scene as
#: CW; study trials 1, 15), recur by chance (with 3: 19 shown still on the default scene's seed 2, with 4: 13)
RIDGE_MAP_HITS = 4


def ridge_map_of(settings: ActiveSettings):
    """The clutter map of a CW's echoes under the ridge notch (:meth:`ContactTracker._ridge_clutter`): as
    :func:`clutter_map_of`'s, at least :data:`RIDGE_MAP_HITS` hits, no lobe-image window; None without a map."""
    cm = clutter_map_of(settings)
    if cm is None:
        return None
    from sonartrack.detection.clutter_map import ClutterMap

    return ClutterMap(cm.span, min(max(cm.min_hits, RIDGE_MAP_HITS), cm.span),
                      still_probability=settings.clutter_map_still_probability, slow_mps=cm.slow_mps,
                      image_range_m=None)


def clutter_map_of(settings: ActiveSettings):
    """The chain's clutter map (detection/clutter_map.py), or None when ``clutter_map_pings`` is not set.

    Parameters
    ----------
    settings : ActiveSettings
        ``clutter_map_pings`` and ``clutter_map_hits``.

    Returns
    -------
    ClutterMap or None
        A fresh map.
    """
    from sonartrack.detection.clutter_map import ClutterMap

    if settings.clutter_map_pings is None:
        return None
    return ClutterMap(settings.clutter_map_pings, min(settings.clutter_map_hits, settings.clutter_map_pings),
                      still_probability=settings.clutter_map_still_probability,
                      slow_mps=settings.clutter_map_slow_mps, image_range_m=settings.clutter_map_image_m)
