"""Quiet targets on signal-level scenes: at what level each front end of the passive chain holds a quiet target beside
louder traffic, whether the default scene's submarine is held and solved, and how many false targets all the front
ends together raise (our own study).

Scenes (the passive simulator, sim/array_signals.py, spherical spreading; the default 16-element towed array at 4 kHz,
ambient 73 dB re 1 uPa^2/Hz), each with its own seed:

* **sweep scenes**, one per level of the grid (``sweep_duration_s``; ownship north at 6 kn without a turn): two loud
  ships at both ends of the sector (:data:`TRAFFIC`: broadband +3 dB per hydrophone at cone angle 20 deg and 0 dB at
  160 deg, tonals 120 and 90 Hz) and ONE quiet target at cone angle uniform in ``cone_range_deg`` on a random side,
  ``target_range_m`` away at mid-scene, course north +- ``course_spread_deg`` at ``target_speed_kn``. Its levels:
  broadband SNR per hydrophone ``levels_db[j]`` (its received spectral level over the ambient's at one element) and
  tonal SNR per hydrophone ``tonal_db[j]`` (the tonal's received power over the ambient power in 1 Hz at one element)
  at ``tonal_hz``. Source levels are set so that these hold at mid-scene (:func:`placed_ship`: the simulator's own
  transmission loss), the range changes by a few per cent over a scene. One quiet target per scene, because the front
  end's statistic is normalised across bearing (median and MAD over all beams): several targets at the upper levels
  raise each other's background (measured: five quiet targets at -12..0 dB, the 0 dB one reached z = 3.7 < 4);
* a **noise-only scene** (``noise_duration_s``, no ship);
* the **default scene** of ``sonartrack simulate`` (``default_duration_s``; its quiet submarine: broadband about -20
  dB per hydrophone, tonal 140 dB at 200 Hz, about -8 dB per hydrophone).

Each scene runs through the chain of ``sonartrack passive`` (:func:`study_chain`: its defaults with ALL front ends
on: ``[narrowband] enabled``, ``[btr_mftd] enabled``). Three front ends are judged on the same run:

* **broadband** (the chain's default, single-window thresholds): the peaks of the bearing-time record tracked again
  without the MFTD's detections (tracking/run.py :func:`track_peaks` with the chain's tracker): what the chain with
  ``[btr_mftd]`` off tracks;
* **MFTD** (paper P1 on the bearing-time record): the chain's tracks, started also on the MFTD's detections;
* **narrowband**: the confirmed line tracks of the chain's line sources (matched in frequency too), whatever the chain
  made of them: a narrowband target (``result.narrowband_target_ids``, a source no bearing track explains), a bearing
  track's tonal, or a source left alone;
* supporting: the single-window peaks with tracks started at z >= the detection threshold 4 instead of the tracker's
  ``init_amplitude`` 6 (:data:`JUDGED`): the MFTD's detections enter the tracker at z = ``init_amplitude``, so they
  start tracks on their own; this row shows what the lower start threshold alone buys, and at what false-track rate.

Held: a front end holds the quiet target in a window when a confirmed row of it (a bearing track's row of that
window; a line's row of the integration period holding the window) lies within ``match_beamwidths`` broadside
beamwidths 0.89 c / (f N d) (at the band centre for bearing tracks: 7.3 deg; at the tonal's frequency for lines,
capped at ``max_match_deg``) of the target's true cone angle (a line also within ``freq_tol_hz`` of its received
frequency). Judged windows: from ``settle_s`` to the end (a line confirms after 3 of 4 periods of 16 s, a bearing
track after 8 of 10 windows), where no other ship lies within the bearing tracks' tolerance (its track would count).
Detection level: the level where the held fraction (pooled over trials) first reaches 0.8, linear between grid points
(:func:`level_at`); 95 % interval: two-stage bootstrap (:func:`held_level`: each level's trials resampled, then the
``block_s`` blocks of judged windows within each drawn trial; with one trial only the blocks, which are correlated
through the scene's tracks: the quick interval is too narrow). MFTD gain: broadband level minus MFTD
level (paired: the same resampled blocks), each front end's false-track rate (confirmed tracks following no ship, per
hour of all recordings) beside it: both run at the chain's settings, not tuned to equal rates.

Default scene: the submarine is held (>= 80 % of its judged windows by some front end), and its longest target has
its side right, its range determined and its final batch-ML position error within 2x the CRB
(studies/passive_chain.py :func:`~sonartrack.studies.passive_chain.target_errors`). False targets: the chain's
targets (bearing and narrowband) following no ship, per hour of all recordings, <= 1.

Supporting rows on synthetic cells (:class:`CellConfig`, ``cells.trials`` cell trials per trial): paper P1's MFTD
gain over the single window at equal pfa, the sliding MFTD's false rate, the LOFAR integration gain, and the MFTD
per narrowband line's gain over the single period on LOFAR-statistic cells (F-distributed in noise).

config -> run_trial -> summarize -> claims; figures in report/figures/quiet_target.py (cell rows).
"""

from __future__ import annotations

import numpy as np
from pydantic import model_validator

from sonartrack.core.settings import Settings, setting
from sonartrack.detection.btr_mftd import (
    BtrMftdSettings,
)
from sonartrack.sim.scene import PassiveSceneSettings, ShipSettings
from sonartrack.studies.quiet_target_cells import CellConfig, run_cells
from sonartrack.studies.quiet_target_claims import FRONT_ENDS, JUDGED
from sonartrack.systems.passive.settings import PassiveSettings

STUDY_ID = "quiet-target"
TITLE = "Quiet targets: broadband, MFTD and narrowband front ends on simulated scenes (our own study)"
PAPER = "sonartrack's own: paper P1 (MFTD) on the bearing-time record, LOFAR lines, the passive chain"
TRIAL_VERSION = 3
#: Monte Carlo size of the full run (``Config.runs``) and of ``Config.quick()``: literals, so that
#: ``sonartrack studies`` reads them from this file's source without importing it
RUNS = 8
QUICK_RUNS = 1
#: one trial per stored chunk: a trial is 11 scenes through the chain (about 50-85 s at full size)
CHUNK_SIZE = 1

#: the loud traffic of the sweep scenes: (name, cone deg, side +1 starboard, range m, course deg, speed kn, broadband
#: SNR per hydrophone dB, tonal Hz, tonal SNR per hydrophone dB): as loud as the top quiet levels (a quiet level
#: 24 dB below them at the bottom), at both ends of the sector the quiet target sits in
TRAFFIC = (("merchant", 20.0, 1.0, 6000.0, 200.0, 12.0, 3.0, 120.0, 20.0),
           ("tanker", 160.0, -1.0, 9000.0, 30.0, 13.0, 0.0, 90.0, 15.0))


def study_chain() -> PassiveSettings:
    """The chain of ``sonartrack passive`` with its defaults and every front end on (narrowband pass and the MFTD on
    the bearing-time record)."""
    s = PassiveSettings()
    return s.model_copy(update={"narrowband": s.narrowband.model_copy(update={"enabled": True}),
                                "btr_mftd": s.btr_mftd.model_copy(update={"enabled": True})})


def _no_turn_scene() -> PassiveSceneSettings:
    s = PassiveSceneSettings(ships=[])
    return s.model_copy(update={"ownship": s.ownship.model_copy(update={"turn_deg": 0.0})})


#: the level grid (broadband SNR per hydrophone, dB): 3 dB steps over the narrowband front end's transition (pilot
#: runs: lines held 0.09 at -21, 1.0 at -18) and the broadband and MFTD front ends' (MFTD held from -6, broadband
#: from 0); -12 left out, between them
LEVELS_DB = (-24.0, -21.0, -18.0, -15.0, -9.0, -6.0, -3.0, 0.0, 3.0)
#: the quiet target's tonal over its broadband spectral level, as the default scene's submarine's (140 - 127 dB): the
#: tonal SNR per hydrophone of each level is the broadband one plus this
TONAL_OFFSET_DB = 13.0


class Config(Settings):
    """The sweep, noise-only and default scenes (module doc). Full size: 8 trials, each 9 sweep scenes of 240 s (one
    per level: 1920 s a level, 176 s of judged windows per scene), a 600 s noise-only scene and the 1200 s default
    scene (1.1 h of recording a trial, 8.8 h in all for the false-target rate); measured 680 s on one worker on the
    shared machine (about 85 s a trial)."""

    runs: int = setting(RUNS, "Monte Carlo trials (each: a sweep scene per level, a noise-only scene, the default "
                              "scene)", unit="1", ge=1)
    levels_db: list[float] = setting(
        default_factory=lambda: list(LEVELS_DB),
        doc="broadband SNR per hydrophone of the quiet target, one sweep scene each (received spectral level over the "
            "ambient's, one element; LEVELS_DB)", unit="dB", min_length=2)
    tonal_db: list[float] = setting(
        default_factory=lambda: [x + TONAL_OFFSET_DB for x in LEVELS_DB],
        doc="tonal SNR per hydrophone of each level (tonal power over the ambient in 1 Hz, one element): the broadband "
            "level + 13 dB, the default submarine's offset (its own broadband masks a weaker tonal in its beam)",
        unit="dB", min_length=2)
    tonal_hz: float = setting(200.0, "tonal frequency of the quiet target (the default submarine's; inside the "
                                     "narrowband pass's band, apart from the traffic's)", unit="Hz", gt=0)
    cone_range_deg: list[float] = setting(default_factory=lambda: [45.0, 135.0], doc="the quiet target's cone angle "
                                          "at mid-scene: uniform in this range (between the traffic's)", unit="deg",
                                          min_length=2, max_length=2)
    target_range_m: float = setting(8000.0, "range of the quiet target at mid-scene (the default submarine's is about "
                                             "5.4 km; the range sets only the bearing rate, the levels are stated per "
                                             "hydrophone)", unit="m", gt=0)
    target_speed_kn: float = setting(5.0, "speed of the quiet target (the default submarine's)", unit="kn", ge=0)
    course_spread_deg: float = setting(20.0, "the quiet targets' courses: north +- this (uniform); with the ownship's "
                                             "6 kn north their cone angles drift a few degrees over the scene",
                                       unit="deg", ge=0)
    sweep_duration_s: float = setting(240.0, "length of a sweep scene (15 narrowband periods; 176 s judged)",
                                      unit="s", gt=0)
    noise_duration_s: float = setting(600.0, "length of the noise-only scene (0: none)", unit="s", ge=0)
    default_duration_s: float = setting(1200.0, "length of the default scene (its own, 1200 s; the turn is centred)",
                                        unit="s", gt=0)
    settle_s: float = setting(64.0, "windows before this are not judged (a line track confirms after 3 of 4 "
                                    "16-s periods; a bearing track after 8 of 10 windows)", unit="s", ge=0)
    block_s: float = setting(32.0, "bootstrap block of judged windows (2 narrowband periods)", unit="s", gt=0)
    match_beamwidths: float = setting(2.0, "match tolerance in broadside beamwidths", unit="1", gt=0)
    max_match_deg: float = setting(11.0, "the match tolerance is capped at this (a line's beam is 19 deg wide at "
                                         "100 Hz)", unit="deg", gt=0)
    freq_tol_hz: float = setting(1.0, "a line matches a target's tonal within this (1 Hz bins)", unit="Hz", gt=0)
    bootstrap: int = setting(300, "bootstrap resamples for the level intervals", unit="1", ge=10)
    scene: PassiveSceneSettings = setting(default_factory=_no_turn_scene, doc="the sweep and noise scenes' ownship, "
                                          "array and noise (no turn; ships are placed by the study)")
    chain: PassiveSettings = setting(default_factory=study_chain, doc="the chain of sonartrack passive with every "
                                                                      "front end on (study_chain)")
    cells: CellConfig = setting(default_factory=CellConfig, doc="supporting rows on synthetic cells")

    @classmethod
    def quick(cls) -> Config:
        """Demo preset: one trial of four 180 s sweep scenes (levels -21, -18, -3, +3 dB: one each side of the
        narrowband and the broadband transitions), a 120 s noise-only scene and the default scene cut to 600 s (its
        turn still centred); 10 cell trials with the MFTD thresholds on 500 noise tiles."""
        cells = CellConfig(trials=10, btr=BtrMftdSettings(frames=8, tile_beams=64, calibration_trials=500))
        levels = [-21.0, -18.0, -3.0, 3.0]
        return cls(runs=QUICK_RUNS, levels_db=levels, tonal_db=[x + TONAL_OFFSET_DB for x in levels],
                   sweep_duration_s=180.0, noise_duration_s=120.0, default_duration_s=600.0, bootstrap=100,
                   cells=cells)

    @model_validator(mode="after")
    def _paired(self):
        if len(self.tonal_db) != len(self.levels_db):
            raise ValueError(f"tonal_db has {len(self.tonal_db)} levels, levels_db {len(self.levels_db)}: give one "
                             "tonal level per broadband level")
        if list(self.levels_db) != sorted(self.levels_db) or list(self.tonal_db) != sorted(self.tonal_db):
            raise ValueError("levels_db and tonal_db must increase")
        return self

    def hours(self) -> float:
        """Hours of recording per trial."""
        return (len(self.levels_db) * self.sweep_duration_s + self.noise_duration_s + self.default_duration_s) / 3600.0


# --- scenes ------------------------------------------------------------------------------------------------------


def placed_ship(scene: PassiveSceneSettings, name: str, cone_deg: float, side: float, range_m: float,
                course_deg: float, speed_kn: float, snr_db: float, tonal_hz: float, tonal_snr_db: float,
                t_ref_s: float) -> ShipSettings:
    """A ship at ``range_m`` and cone angle ``cone_deg`` (``side`` +1 starboard, -1 port) from the array centre at
    ``t_ref_s``, with source levels that give the stated broadband and tonal SNRs per hydrophone there.

    SL = SNR + NL + TL(r), with TL the simulator's own (sim/passive_scene.py :func:`received_levels` of the ship with
    0 dB source levels at ``t_ref_s``), so the levels land where stated whatever the propagation setting.

    Parameters
    ----------
    scene : PassiveSceneSettings
        The scene (ownship, array, noise level, propagation); its ships are ignored.
    name : str
        Ship name.
    cone_deg, side, range_m : float
        Cone angle (deg from the array's axis), side (+1 starboard, -1 port), range (m) at ``t_ref_s``.
    course_deg, speed_kn : float
        Constant course (deg clockwise from north) and speed (kn).
    snr_db, tonal_snr_db : float
        Broadband spectral SNR and tonal SNR in 1 Hz per hydrophone at ``t_ref_s`` (dB).
    tonal_hz : float
        Tonal frequency (Hz).
    t_ref_s : float
        The time the geometry and levels refer to (s).

    Returns
    -------
    ShipSettings
        The ship.
    """
    from sonartrack.core.units import KNOT_MPS
    from sonartrack.sim.passive_scene import received_levels, scene_geometry

    g = scene_geometry(scene.model_copy(update={"ships": []}), np.array([t_ref_s]))
    brg = float(g.array_heading_rad[0]) + side * np.deg2rad(cone_deg)
    pos = g.array_xy[0] + range_m * np.array([np.sin(brg), np.cos(brg)])
    vel = speed_kn * KNOT_MPS * np.array([np.sin(np.deg2rad(course_deg)), np.cos(np.deg2rad(course_deg))])
    x0 = pos - vel * t_ref_s
    ship = ShipSettings(name=name, x_m=float(x0[0]), y_m=float(x0[1]), course_deg=course_deg, speed_kn=speed_kn,
                        source_level_db=0.0, tonal_hz=tonal_hz, tonal_level_db=0.0)
    one = scene.model_copy(update={"ships": [ship]})
    lv = received_levels(one, scene_geometry(one, np.array([t_ref_s])))
    nl = scene.noise_level_db
    return ship.model_copy(update={"source_level_db": float(snr_db + nl - lv.broadband_db[0, 0]),
                                   "tonal_level_db": float(tonal_snr_db + nl - lv.tonal_db[0, 0])})


def sweep_scene(config: Config, level: int, rng: np.random.Generator) -> PassiveSceneSettings:
    """A sweep scene: the traffic (:data:`TRAFFIC`) and one quiet target at level ``level`` of the grid, at a cone
    angle uniform in ``cone_range_deg`` on a random side, at ``target_range_m`` at mid-scene (module doc)."""
    base = config.scene.model_copy(update={"duration_s": config.sweep_duration_s,
                                           "seed": int(rng.integers(0, 2**31 - 1))})
    t_mid = 0.5 * config.sweep_duration_s
    ships = [placed_ship(base, *row, t_mid) for row in TRAFFIC]
    cone = rng.uniform(*config.cone_range_deg)
    side = float(rng.choice([-1.0, 1.0]))
    course = float(rng.uniform(-config.course_spread_deg, config.course_spread_deg))
    ships.append(placed_ship(base, "quiet", cone, side, config.target_range_m, course, config.target_speed_kn,
                             config.levels_db[level], config.tonal_hz, config.tonal_db[level], t_mid))
    return base.model_copy(update={"ships": ships})


def run_scene(config: Config, scene: PassiveSceneSettings):
    """The study's chain on ``scene`` (studies/passive_chain.py :func:`~sonartrack.studies.passive_chain.run_chain`
    with the scene's array). Returns (result, navigation)."""
    from sonartrack.studies.passive_chain import Config as ChainConfig
    from sonartrack.studies.passive_chain import run_chain

    return run_chain(ChainConfig(runs=1, scene=scene, chain=config.chain), scene)


# --- judging -----------------------------------------------------------------------------------------------------


def held_windows(rows_t, rows_cone, tw, cone_true, half_s: float, tol_deg: float, rows_f=None, f_true=None,
                 f_tol_hz: float = np.inf) -> np.ndarray:
    """(T,) True where a row lies within ``half_s`` of window time tw[k] and within ``tol_deg`` of the true cone angle
    there (and, when frequencies are given, within ``f_tol_hz`` of the true frequency).

    Parameters
    ----------
    rows_t, rows_cone : array_like (n,)
        The front end's confirmed rows: time (s) and cone angle (deg).
    tw, cone_true : array_like (T,)
        Window centres (s) and the target's true cone angle there (deg).
    half_s : float
        A row covers the windows within this of its time (s): half a window for bearing tracks, half an integration
        period for lines.
    tol_deg : float
        Cone-angle match tolerance (deg).
    rows_f, f_true : array_like, optional
        Row frequencies (n,) and the target's received frequency (T,) (Hz).
    f_tol_hz : float
        Frequency match tolerance (Hz).

    Returns
    -------
    ndarray of bool, shape (T,)
        Held per window.
    """
    rt, rc, tw, ct = (np.asarray(x, float) for x in (rows_t, rows_cone, tw, cone_true))
    if not rt.size:
        return np.zeros(tw.shape, bool)
    ok = (np.abs(rt[:, None] - tw[None]) <= half_s) & (np.abs(rc[:, None] - ct[None]) <= tol_deg)
    if rows_f is not None and f_true is not None:
        ok &= np.abs(np.asarray(rows_f, float)[:, None] - np.asarray(f_true, float)[None]) <= f_tol_hz
    return ok.any(axis=0)


def track_rows(tracks) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(time s, cone deg, track id) of the confirmed rows of :class:`~sonartrack.tracking.run.BearingTracks`."""
    c = np.asarray(tracks.confirmed).astype(bool)
    return (np.asarray(tracks.time_s, float)[c], np.asarray(tracks.bearing_deg, float)[c],
            np.asarray(tracks.track_id)[c])


def narrowband_rows(result) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(time s, cone deg, frequency Hz, line id) of the narrowband front end's confirmed rows: the confirmed line
    tracks of the chain's line sources, whatever the chain made of them (a narrowband target, a bearing track's
    tonal, or a source left alone)."""
    in_source = {k for s in result.line_sources for k in s.track_ids}
    lines = [ln for ln in result.line_tracks if ln.confirmed and ln.track_id in in_source]
    cat = [np.concatenate([np.asarray(getattr(ln, f), float) for ln in lines]) if lines else np.zeros(0)
           for f in ("time_s", "cone_deg", "frequency_hz")]
    ids = np.concatenate([np.full(len(ln.time_s), ln.track_id) for ln in lines]) if lines else np.zeros(0, int)
    return cat[0], cat[1], cat[2], ids


def _tolerances(config: Config, result, tonal_hz) -> tuple[float, np.ndarray]:
    """(bearing-track tolerance deg, per-ship line tolerance deg) from the broadside beamwidths (module doc)."""
    st = result.stages
    bb = min(config.match_beamwidths * st.array.beamwidth_deg(st.band.centre_hz), config.max_match_deg)
    nb = np.array([min(config.match_beamwidths * st.array.beamwidth_deg(f), config.max_match_deg)
                   if np.isfinite(f) else config.max_match_deg for f in tonal_hz])
    return bb, nb


def _truth(scene: PassiveSceneSettings, result, tol_deg: float):
    """(window times (T,), true cone deg (S, T), received tonal Hz (S, T), alone (S, T) bool: no other ship within
    ``tol_deg``, where another ship's track would count as holding this one)."""
    from sonartrack.sim.passive_scene import received_levels, scene_geometry

    tw = np.asarray(result.record.time_s, float)
    g = scene_geometry(scene, tw)
    cone = np.rad2deg(g.cone_rad)
    f = received_levels(scene, g).tonal_hz
    sep = np.abs(cone[:, None] - cone[None])
    sep[np.arange(len(cone)), np.arange(len(cone))] = np.inf
    alone = sep.min(axis=1) > tol_deg if len(cone) > 1 else np.ones(cone.shape, bool)
    return tw, cone, f, alone


def bearing_front_ends(result) -> dict:
    """The bearing tracks of the bearing-track front ends: ``broadband`` (the single-window peaks tracked again with
    the chain's tracker), ``mftd`` (the chain's tracks), ``broadband_low_init`` (the single-window peaks, tracks
    started at z >= the detection threshold)."""
    from sonartrack.tracking.run import track_peaks

    pk, tracker = result.record.peaks, result.stages.tracker
    low = tracker.model_copy(update={"init_amplitude": float(result.settings.threshold)})
    return {"broadband": track_peaks(pk.time_s, pk.bearing_deg, pk.amplitude, tracker), "mftd": result.tracks,
            "broadband_low_init": track_peaks(pk.time_s, pk.bearing_deg, pk.amplitude, low)}


def front_end_held(config: Config, scene: PassiveSceneSettings, result) -> dict:
    """Per front end (:data:`JUDGED`), (S, T) held per ship and window; "judged" (S, T); "_tracks": the bearing
    tracks of :func:`bearing_front_ends`."""
    tol_bb, tol_nb = _tolerances(config, result, [s.tonal_hz or np.nan for s in scene.ships])
    tw, cone, f, alone = _truth(scene, result, tol_bb)
    tracks = bearing_front_ends(result)
    w = result.settings.window_s
    nt, nc, nf, _ = narrowband_rows(result)
    half_nb = 0.5 * result.settings.narrowband.integration * w
    out = {}
    for name, tr in tracks.items():
        t, c, _ = track_rows(tr)
        out[name] = np.array([held_windows(t, c, tw, cone[s], 0.5 * w, tol_bb) for s in range(len(cone))])
    out["narrowband"] = np.array([held_windows(nt, nc, tw, cone[s], half_nb, tol_nb[s], nf, f[s], config.freq_tol_hz)
                                  for s in range(len(cone))])
    out["judged"] = alone & (tw >= config.settle_s)[None]
    out["_tracks"] = tracks
    return out


def false_count(rows_t, rows_cone, ids, scene: PassiveSceneSettings, tol_deg) -> int:
    """Confirmed tracks (rows grouped by id) whose median offset from every ship's true cone angle is above the
    tolerance (all of them in a scene without ships).

    Parameters
    ----------
    rows_t, rows_cone, ids : array_like (n,)
        Rows: time (s), cone angle (deg), track id.
    scene : PassiveSceneSettings
        The scene (its ships' truth).
    tol_deg : float or array_like (S,)
        Match tolerance (deg), one or per ship.

    Returns
    -------
    int
        Tracks following no ship.
    """
    from sonartrack.sim.passive_scene import scene_geometry

    rows_t, rows_cone, ids = np.asarray(rows_t, float), np.asarray(rows_cone, float), np.asarray(ids)
    n = 0
    for k in np.unique(ids):
        m = ids == k
        if not scene.ships:
            n += 1
            continue
        cone = np.rad2deg(scene_geometry(scene, rows_t[m]).cone_rad)
        off = np.median(np.abs(cone - rows_cone[m][None]), axis=1)
        n += int(not np.any(off <= np.broadcast_to(np.asarray(tol_deg, float), off.shape)))
    return n


def false_tracks(config: Config, scene: PassiveSceneSettings, result, tracks: dict) -> np.ndarray:
    """Confirmed tracks following no ship per front end (:data:`JUDGED`; narrowband: confirmed line tracks of
    sources), then the chain's targets following no ship (bearing and narrowband targets; on a chain without
    narrowband targets, its bearing targets plus the false line tracks: an upper bound, two harmonics count twice).
    ``tracks``: :func:`bearing_front_ends`."""
    tol_bb, tol_nb = _tolerances(config, result, [s.tonal_hz or np.nan for s in scene.ships])
    nt, nc, _, nid = narrowband_rows(result)
    counts = {fe: false_count(*track_rows(tr), scene, tol_bb) for fe, tr in tracks.items()}
    counts["narrowband"] = false_count(nt, nc, nid, scene, tol_nb if scene.ships else tol_bb)
    has_nb = getattr(result, "narrowband_target_ids", None) is not None
    rows = [(np.asarray(t.track.time_s, float), np.asarray(t.track.cone_deg, float), np.full(len(t.track.time_s), i))
            for i, t in enumerate(result.targets)]
    n_tg = false_count(*(np.concatenate(v) for v in zip(*rows, strict=True)), scene, tol_bb) if rows else 0
    return np.array([counts[fe] for fe in JUDGED] + [n_tg if has_nb else n_tg + counts["narrowband"]], float)


# --- one trial ---------------------------------------------------------------------------------------------------


def _blocks(held: np.ndarray, judged: np.ndarray, tw: np.ndarray, config: Config, duration_s: float
            ) -> tuple[np.ndarray, np.ndarray]:
    """(held windows, judged windows) per ``block_s`` block from ``settle_s`` on (:func:`n_blocks_of`): (S, n_blocks)
    each."""
    n_blocks = n_blocks_of(config, duration_s)
    b = np.floor((tw - config.settle_s) / config.block_s).astype(int)
    ok = (b >= 0) & (b < n_blocks)
    h, j = np.zeros((held.shape[0], n_blocks)), np.zeros((held.shape[0], n_blocks))
    for s in range(held.shape[0]):
        np.add.at(h[s], b[ok], (held[s] & judged[s])[ok])
        np.add.at(j[s], b[ok], judged[s][ok])
    return h, j


def n_blocks_of(config: Config, duration_s: float) -> int:
    """Bootstrap blocks of a scene: ``block_s`` blocks from ``settle_s`` to the end, the last one partial (at least
    one)."""
    return max(int(np.ceil((duration_s - config.settle_s) / config.block_s)), 1)


def _sweep_trial(config: Config, rng) -> dict[str, np.ndarray]:
    """One sweep scene per level: held and judged windows of the quiet target per level and block, and the false
    tracks and targets of all the sweep scenes."""
    held_fe = {fe: [] for fe in JUDGED}
    judged, false = [], np.zeros(len(JUDGED) + 1)
    for level in range(len(config.levels_db)):
        scene = sweep_scene(config, level, rng)
        result, _ = run_scene(config, scene)
        held = front_end_held(config, scene, result)
        tw = np.asarray(result.record.time_s, float)
        for fe in JUDGED:
            h, j = _blocks(held[fe][-1:], held["judged"][-1:], tw, config, scene.duration_s)
            held_fe[fe].append(h[0])
        judged.append(j[0])
        false += false_tracks(config, scene, result, held["_tracks"])
    out = {f"held_{fe}": np.array(v) for fe, v in held_fe.items()}
    out["judged"] = np.array(judged)
    out["false_sweep"] = false
    return out


def _default_trial(config: Config, seed: int) -> dict[str, np.ndarray]:
    """The default scene: the submarine's held fraction per front end and any, and its solution."""
    from sonartrack.studies.passive_chain_measures import longest_per_ship, match_targets, target_errors

    scene = PassiveSceneSettings(seed=seed, duration_s=config.default_duration_s)
    result, nav = run_scene(config, scene)
    held = front_end_held(config, scene, result)
    sub = [s.name for s in scene.ships].index("submarine")
    judged = held["judged"][sub]
    frac = [held[fe][sub][judged].mean() if judged.any() else np.nan for fe in FRONT_ENDS]
    anyfe = np.any([held[fe][sub] for fe in FRONT_ENDS], axis=0)
    frac.append(anyfe[judged].mean() if judged.any() else np.nan)
    tol_bb, _ = _tolerances(config, result, [np.nan])
    best = longest_per_ship(result, match_targets(result, scene, tol_bb), len(scene.ships))[sub]
    solved = np.full(6, np.nan)  # side right, range determined, error m, CRB sd m, bearing sd deg, side decided
    if best is not None:
        from sonartrack.sim.passive_scene import scene_geometry

        tg = result.targets[best]
        g = scene_geometry(scene, np.asarray(result.record.time_s, float)[-1:])
        side = "starboard" if np.sin(g.bearing_rad[sub, -1] - g.array_heading_rad[-1]) >= 0 else "port"
        err, crb_sd, sigma, det = target_errors(tg, scene, sub, nav)
        solved[:] = [float(tg.side.side == side), det, err, crb_sd, sigma, float(tg.side.side != "unresolved")]
    return {"sub_held": np.array(frac), "sub_solved": solved,
            "false_default": false_tracks(config, scene, result, held["_tracks"])}


def run_trial(config: Config, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """A sweep scene per level, a noise-only scene and the default scene, each with its own seed from ``rng``; and
    ``cells.trials`` synthetic cell trials."""
    seeds = rng.integers(0, 2**31 - 1, size=2)
    out = _sweep_trial(config, rng)
    out["false_noise"] = np.zeros(len(JUDGED) + 1)
    if config.noise_duration_s > 0:
        noise = config.scene.model_copy(update={"duration_s": config.noise_duration_s, "seed": int(seeds[0]),
                                                "ships": []})
        result, _ = run_scene(config, noise)
        held = front_end_held(config, noise, result)
        out["false_noise"] = false_tracks(config, noise, result, held["_tracks"])
    out.update(_default_trial(config, int(seeds[1])))
    cells = [run_cells(config.cells, rng) for _ in range(config.cells.trials)]
    out.update({k: np.stack([c[k] for c in cells]) for k in cells[0]})
    return out


# --- supporting rows on synthetic cells --------------------------------------------------------------------------


# --- summary -----------------------------------------------------------------------------------------------------


# --- claims ------------------------------------------------------------------------------------------------------


def __getattr__(name: str):
    """The summary's and the cells' names (studies/quiet_target_claims.py, quiet_target_cells.py), also readable
    here, as the study's other names are (lazily: those modules do not import this one at run time)."""
    from sonartrack.studies import quiet_target_cells, quiet_target_claims

    for module in (quiet_target_claims, quiet_target_cells):
        if hasattr(module, name):
            return getattr(module, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
