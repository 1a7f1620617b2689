"""Study passive-chain: the scene family draws valid, deterministic scenes with the events it promises; the judging
functions on hand-made truth and tracks (each can fail); one short trial through the contract."""

import numpy as np
import pytest

from sonartrack.core.units import KNOT_MPS
from sonartrack.sim.passive_scene import scene_geometry
from sonartrack.studies import passive_chain as pc
from sonartrack.tracking.run import BearingTracks


def _tracks(rows):
    """BearingTracks from (time, id, cone, confirmed) rows."""
    t, tid, cone, conf = (np.array(c) for c in zip(*rows, strict=True))
    zeros = np.zeros(len(t))
    return BearingTracks(time_s=t.astype(float), track_id=tid.astype(int), bearing_deg=cone.astype(float),
                         bearing_rate_deg_s=zeros, bearing_std_deg=zeros, strength=zeros, confirmed=conf.astype(bool))


# ---- the family ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("seed", [0, 1, 2, 3, 4, 5])
def test_family_scenes_are_valid_deterministic_and_hold_their_events(seed):
    config = pc.Config()
    f = config.family
    scene = pc.draw_scene(config, seed)
    assert scene == pc.draw_scene(config, seed)
    assert scene.array.elements in f.elements and scene.spacing_m in f.spacing_m
    assert scene.sample_rate_hz in f.sample_rate_hz and scene.duration_s == f.duration_s and scene.seed == seed
    assert [s.name for s in scene.ships] == list(pc.FAMILY_SHIPS)
    near, far, crosser = scene.ships[:3]
    # the pair: at one time at the same cone angle (and bearing), at two ranges, their cone-angle rates apart
    t_c = near.at_time_s
    assert far.at_time_s == t_c and far.at_relative_bearing_deg == near.at_relative_bearing_deg
    g = scene_geometry(scene, np.array([t_c - 5.0, t_c, t_c + 5.0]))
    assert g.cone_rad[0, 1] == pytest.approx(g.cone_rad[1, 1], abs=1e-9)
    assert g.range_m[1, 1] > 1.7 * g.range_m[0, 1]
    rates = np.rad2deg(g.cone_rad[:2, 2] - g.cone_rad[:2, 0]) / 10.0
    assert abs(rates[0] - rates[1]) >= pc.MIN_CROSSING_RATE_DEG_S
    # the crosser: on the axis at its time, on the other side after it
    g = scene_geometry(scene, np.array([crosser.at_time_s - 20.0, crosser.at_time_s, crosser.at_time_s + 20.0]))
    cone = np.rad2deg(g.cone_rad[2, 1])
    assert min(cone, 180.0 - cone) < 1e-6
    side = np.sin(g.bearing_rad[2] - g.array_heading_rad)
    assert side[0] * side[2] < 0
    # the ownship's turns end inside the recording
    assert scene.turn_start_s + scene.ownship.maneuver_s <= 0.9 * scene.duration_s + 1e-6


def test_family_draws_differ_and_cover_the_choices():
    config = pc.Config()
    scenes = [pc.draw_scene(config, s) for s in range(40)]
    assert len({(s.array.elements, s.spacing_m, s.sample_rate_hz) for s in scenes}) > 10
    assert {s.ownship.zigzag_turns for s in scenes} >= {1, 2, 3}
    assert {np.sign(s.ownship.turn_deg) for s in scenes} == {-1.0, 1.0}
    assert {s.ships[2].at_relative_bearing_deg for s in scenes} == {0.0, 180.0}


def test_quick_family_stays_on_the_cheap_arrays():
    config = pc.Config.quick()
    for seed in range(10):
        s = pc.draw_scene(config, seed)
        assert s.sample_rate_hz == 4000.0 and s.array.elements <= 24 and s.duration_s <= 300.0


# ---- truth events ----------------------------------------------------------------------------------------------

def test_crossing_events_are_runs_within_a_beam():
    a = np.linspace(40.0, 60.0, 21)  # 1 deg per window
    b = np.linspace(60.0, 40.0, 21)
    c = np.full(21, 120.0)
    events = pc.crossing_events(np.stack([a, b, c]), 4.0)
    # about 50 deg the beam is 4 / sin(50) = 5.2 deg wide in cone angle: |cos a - cos b| (by hand) is 0.0534 at
    # k = 8 (48 vs 52 deg), below 4 deg = 0.0698 rad, and 0.0802 at k = 7 (47 vs 53 deg), above it
    assert events == [(0, 1, 8, 12)]
    assert pc.crossing_events(np.stack([a, b]), 0.5) == [(0, 1, 10, 10)]


def test_ships_near_endfire_share_a_beam_that_broadside_would_split():
    # 3 deg apart: resolved at broadside by a 2 deg beam, not at 175 deg, where the beam is 2 / sin(5) = 23 deg wide
    broadside = np.stack([np.full(5, 90.0), np.full(5, 93.0)])
    endfire = np.stack([np.full(5, 172.0), np.full(5, 175.0)])
    assert pc.crossing_events(broadside, 2.0) == []
    assert pc.crossing_events(endfire, 2.0) == [(0, 1, 0, 4)]
    assert pc.direction_separation(90.0, 93.0) == pytest.approx(np.sin(np.deg2rad(3.0)), rel=1e-12)


def test_axis_crossings_where_the_side_changes():
    heading = np.zeros(5)
    bearing = np.deg2rad(np.array([[170.0, 175.0, 179.0, -179.0, -175.0],   # crosses astern at window 3
                                   [80.0, 85.0, 90.0, 95.0, 100.0]]))       # stays to starboard
    assert pc.axis_crossings(bearing, heading) == [(0, 3)]


# ---- judging ---------------------------------------------------------------------------------------------------

def test_held_only_by_a_confirmed_track_near_the_ship():
    tw = np.array([0.5, 1.5, 2.5])
    cone = np.array([[40.0, 41.0, 42.0]])
    tracks = _tracks([(0.5, 1, 40.5, True), (1.5, 1, 45.0, True), (2.5, 2, 42.1, False)])
    assert pc.held_by_track(tracks, tw, cone, 3.0).tolist() == [[True, False, False]]


def _crossing_case():
    tw = np.arange(0.0, 100.0)
    a = np.linspace(40.0, 60.0, 100)
    b = np.linspace(60.0, 40.0, 100)  # cross at t = 49.5
    return tw, a, b


def test_identity_kept_swapped_lost_and_not_judged():
    tw, a, b = _crossing_case()
    before, after = tw < 45, tw > 55
    keep = [(tw, a), (tw, b)]
    assert pc.identity_through(keep, tw, a, b, 45.0, 55.0, 30.0, 1.0) == 1.0
    swap = [(tw, np.where(tw < 50, a, b)), (tw, np.where(tw < 50, b, a))]
    assert pc.identity_through(swap, tw, a, b, 45.0, 55.0, 30.0, 1.0) == 0.0
    jumped = [(tw, np.where(tw < 50, a, b)), (tw[before], b[before])]  # a's target goes on with b, b's ends
    assert pc.identity_through(jumped, tw, a, b, 45.0, 55.0, 30.0, 1.0) == 0.0
    new_target = [(tw[before], a[before]), (tw, b), (tw[after], a[after])]  # a's target breaks: a new one after
    assert pc.identity_through(new_target, tw, a, b, 45.0, 55.0, 30.0, 1.0) == 0.0
    one_only = [(tw, a)]
    assert np.isnan(pc.identity_through(one_only, tw, a, b, 45.0, 55.0, 30.0, 1.0))
    lost = [(tw, a), (tw[before], b[before])]  # b's target ends at the crossing and nothing follows b
    outcomes = [pc.crossing_outcome(m, tw, a, b, 45.0, 55.0, 30.0, 1.0) for m in (keep, swap, jumped, lost,
                                                                                    new_target)]
    assert [pc.OUTCOMES[int(c)] for c in outcomes] == ["kept", "swapped", "jumped", "lost", "new target"]


def _fake_result(targets, beamwidth_deg):
    from types import SimpleNamespace

    tgs = [SimpleNamespace(track=SimpleNamespace(time_s=t, cone_deg=c)) for t, c in targets]
    return SimpleNamespace(targets=tgs, stages=SimpleNamespace(min_separation_deg=beamwidth_deg))


def test_crossings_too_near_the_recording_end_are_not_judged():
    tw, a, b = _crossing_case()  # cross at t = 49.5, within 2 deg (one beamwidth) from t = 45 to 54
    result = _fake_result([(tw, a), (tw, b)], 2.0)
    detect = np.ones((2, len(tw)), bool)
    config = pc.Config(crossing_window_s=30.0)
    out = pc._crossing_outputs(config, result, tw, np.stack([a, b]), detect)
    assert out["crossing_outcome"][0] == 1.0 and out["crossing_crossed"][0] == 1.0
    assert np.isnan(out["crossing_outcome"][1:]).all()
    late = pc.Config(crossing_window_s=60.0)  # the span after the crossing runs past the recording's end
    assert np.isnan(pc._crossing_outputs(late, result, tw, np.stack([a, b]), detect)["crossing_outcome"]).all()
    undetectable = detect.copy()
    undetectable[1, 55:] = False  # b not detectable after: not judged
    assert np.isnan(pc._crossing_outputs(config, result, tw, np.stack([a, b]), undetectable)["crossing_outcome"]).all()


def test_follower_needs_enough_peaks_near_the_ship():
    tw, a, _ = _crossing_case()
    few = [(tw[:4], a[:4])]  # 4 peaks < MIN_FOLLOW_SCANS
    assert pc.follower(few, tw, a, 0.0, 50.0, 1.0) is None
    off = [(tw, a + 2.0)]
    assert pc.follower(off, tw, a, 0.0, 50.0, 1.0) is None
    assert pc.follower([(tw, a + 2.0), (tw, a + 0.5)], tw, a, 0.0, 50.0, 1.0) == 1


def test_bearing_error_after_an_axis_crossing_sees_the_mirror_side():
    t = np.arange(0.0, 200.0)
    truth = np.deg2rad(np.linspace(170.0, 200.0, 200))  # through 180 deg: wraps to -160
    right = np.angle(np.exp(1j * (truth + np.deg2rad(0.3))))
    heading = 0.0
    mirror = np.angle(np.exp(1j * (2 * heading - truth)))  # the other side's bearing
    assert pc.bearing_error_after(t, right, t, np.angle(np.exp(1j * truth)), 120.0, 200.0) == pytest.approx(0.3)
    # true bearings ~190-200 deg, mirror ~160-170 deg: errors 20-40 deg
    assert pc.bearing_error_after(t, mirror, t, np.angle(np.exp(1j * truth)), 120.0, 200.0) > 20.0
    assert np.isnan(pc.bearing_error_after(t, right, t, truth, 300.0, 400.0))


def test_diverged_solutions():
    array_xy = np.array([0.0, 0.0])
    P = np.eye(4)
    assert not pc.diverged([3000.0, 4000.0, 5.0, 0.0], P, array_xy, 5000.0)
    assert pc.diverged([30000.0, 40000.0, 5.0, 0.0], P, array_xy, 5000.0)  # 50 km for 5 km: 10x
    assert pc.diverged([3000.0, 4000.0, 40.0, 0.0], P, array_xy, 5000.0)  # 78 kn
    assert pc.diverged([3000.0, np.nan, 5.0, 0.0], P, array_xy, 5000.0)
    assert pc.diverged([3000.0, 4000.0, 5.0, 0.0], np.full((4, 4), np.inf), array_xy, 5000.0)
    assert pytest.approx(60.0 * KNOT_MPS) == pc.DIVERGED_SPEED_MPS


def test_normalised_errors_by_hand():
    P = np.diag([100.0**2, 400.0**2, 1.0, 4.0])
    nees, sds = pc.normalised_errors([300.0, -800.0, 1.0, 2.0], P, [0.0, 0.0, 0.0, 0.0])
    # (300/100)^2 + (800/400)^2 + 1 + 1 = 9 + 4 + 2 = 15; position: sqrt(9 + 4)
    assert nees == pytest.approx(15.0)
    assert sds == pytest.approx(np.sqrt(13.0))


def test_side_correct_per_segment_between_axis_crossings():
    from sonartrack.tma.sides import SideDecision

    t = np.arange(0.0, 100.0)
    truth = np.where(t < 50.0, "starboard", "port")
    crossing = SideDecision("starboard", 5.0, 0.01, None, None, crossings_s=(50.0,))
    assert pc.side_correct(crossing, t, truth) == 1.0
    no_crossing = SideDecision("starboard", 5.0, 0.01, None, None)  # one side for its whole life: half wrong
    assert pc.side_correct(no_crossing, t, truth) == 0.0
    assert np.isnan(pc.side_correct(SideDecision("unresolved", 0.0, 0.01, None, None), t, truth))


def test_running_median_removes_a_lone_peak():
    x = np.zeros((1, 30))
    x[0, 10] = 50.0
    assert pc.running_median(x, 11).max() == 0.0


def test_summary_shares_and_claims_on_made_up_trials():
    n = 2
    nan8 = np.full((n, pc.MAX_EVENTS), np.nan)
    sol = np.full((n, pc.MAX_SOLUTIONS), np.nan)
    det = sol.copy()
    det[:, :3] = [[1.0, 1.0, 0.0], [1.0, 1.0, 1.0]]
    err, crb = sol.copy(), sol.copy()
    err[:, :3], crb[:, :3] = 100.0, 100.0
    err[1, 2] = 500.0  # 5 determined: 4 within 2x CRB
    sds = sol.copy()
    sds[:, :3] = 1.0
    zeros = np.where(np.isfinite(det), 0.0, np.nan)
    ident = nan8.copy()
    ident[:, :2] = [[1.0, 0.0], [1.0, 1.0]]
    trials = {"hold": np.array([[0.95, 0.9, np.nan, 1.0], [0.85, 1.0, 0.9, np.nan]]),
              "scene": np.zeros((n, 4)), "crossing_outcome": np.where(ident == 0.0, 2.0, ident),
              "crossing_crossed": np.where(np.isfinite(ident), 1.0, np.nan),
              "axis_error_deg": nan8, "axis_one_target": nan8, "beamwidth_deg": np.full((n, 1), 3.0),
              "side_correct": np.where(np.isfinite(det), 1.0, np.nan),
              "determined": det, "pos_err_m": err, "crb_sd_m": crb, "pos_sds": sds, "ml_nees": sds * 4.0,
              "ml_diverged": zeros, "imm_printed": zeros, "imm_diverged": zeros, "imm_nees": zeros,
              "ospa_cone_deg": np.ones((n, 1)), "gospa_cone_deg": np.ones((n, 1)), "gospa_switches": np.ones((n, 1)),
              "ospa_position_m": np.ones((n, 1)), "segments": np.ones((n, 4)), "switches": np.zeros((n, 4)),
              "false_targets_ships": np.zeros((n, 1)), "false_targets_noise": np.array([[1.0], [0.0]]),
              "hours": np.full((n, 1), 0.5), "narrowband_targets": np.zeros((n, 1))}
    config = pc.Config(runs=n)
    summary = pc.summarize(trials, config)
    assert summary["identity"]["k"] == 3 and summary["identity"]["n"] == 4
    assert summary["crossing_outcomes"] == {"kept": 3, "swapped": 1, "jumped": 0, "lost": 0, "new target": 0}
    assert summary["crb"]["k"] == 4 and summary["crb"]["n"] == 5
    assert summary["hold_all"][0] == pytest.approx(np.mean([0.95, 0.9, 1.0, 0.85, 1.0, 0.9]))
    assert summary["false_per_hour"] == pytest.approx(1.0 / 2.0)
    assert summary["ml_nees"]["n"] == 5 and summary["ml_nees"]["anees"] == pytest.approx(4.0)
    assert summary["side_correct"]["k"] == 6 and summary["side_unresolved"] == 0
    verdicts = {c.id: c.holds for c in pc.claims(summary, config)}
    assert verdicts == {"ships-held": True, "crossing-identities": False, "axis-bearing": False,
                        "ml-near-crb": False, "no-diverged": True, "false-targets": True}


# ---- one trial -------------------------------------------------------------------------------------------------

def test_a_short_trial_fills_the_contract():
    family = {"elements": [16], "spacing_m": [2.5], "sample_rate_hz": [4000.0], "duration_s": 240.0}
    config = pc.Config.model_validate({"runs": 1, "family": family})
    trial = pc.run_trial(config, np.random.default_rng(5))
    assert trial["hold"].shape == (4,) and trial["crossing_outcome"].shape == (pc.MAX_EVENTS,)
    assert trial["determined"].shape == (pc.MAX_SOLUTIONS,) and trial["scene"].tolist()[:3] == [16, 2.5, 4000.0]
    summary = pc.summarize({k: v[None] for k, v in trial.items()}, config)
    claims = pc.claims(summary, config)
    assert [c.id for c in claims] == ["ships-held", "crossing-identities", "axis-bearing", "ml-near-crb",
                                      "no-diverged", "false-targets"]
    assert np.nanmax(trial["hold"]) > 0.5  # some ship is held on a 16 x 2.5 m array
    assert trial["false_targets_noise"][0] == 0  # no target in 4 minutes of noise


def test_target_errors_judge_the_scans_the_ml_was_fitted_to_at_its_last_row():
    """A target whose ML record holds only the first half of its track's scans (as the bearings + frequency ML's
    record does): the CRB is over those scans, with the noise of its peaks there (+-0.2 deg alternating: sd 0.2 deg
    exactly; the second half's +-1.5 deg must not count), carried to the record's last time, and the error is
    measured against the ship at that time (the solution is put 30 m east and 40 m north of it: 50 m)."""
    from types import SimpleNamespace

    from sonartrack.tma.batch_ml import crb_position_sd_m

    scene = pc.draw_scene(pc.Config(), 3)
    nav = pc.navigation(scene_geometry(scene, np.arange(0.0, 601.0)))
    t = np.arange(10.0, 590.0, 2.0)  # 290 scans
    half = len(t) // 2  # 145 scans: use an even count so that the alternating offsets have mean 0
    half -= half % 2
    ship = 0
    g = scene_geometry(scene, t)
    offset = np.where(np.arange(len(t)) % 2 == 0, 1.0, -1.0) * np.where(np.arange(len(t)) < half, 0.2, 1.5)
    track = SimpleNamespace(time_s=t, cone_deg=np.rad2deg(g.cone_rad[ship]) + offset)
    t_rec = t[:half]
    end = scene_geometry(scene, t_rec[-1:])
    state = np.zeros((half, 4))
    state[-1, :2] = end.ship_xy[ship, 0] + np.array([30.0, 40.0])
    solution = SimpleNamespace(time_s=t_rec, state=state, range_flags=lambda: np.ones(half, bool))
    tg = SimpleNamespace(track=track, ml=SimpleNamespace(record=SimpleNamespace(time_s=t_rec), solution=solution))
    err, crb_m, sigma_deg, det = pc.target_errors(tg, scene, ship, nav)
    assert err == pytest.approx(50.0, abs=1e-6)
    assert sigma_deg == pytest.approx(0.2, rel=1e-6)
    x0 = np.concatenate([g.ship_xy[ship, 0], g.ship_velocity[ship, 0]])
    xy, _ = nav.array_at(t_rec)
    expected = crb_position_sd_m(x0, t_rec - t_rec[0], xy, np.deg2rad(0.2), t_rec[-1] - t_rec[0])
    assert np.isfinite(expected) and crb_m == pytest.approx(expected, rel=1e-9)
    # over the whole track at its end (the judging before): another number
    whole = crb_position_sd_m(x0, t - t[0], nav.array_at(t)[0], np.deg2rad(np.std(offset)), t[-1] - t[0])
    assert crb_m != pytest.approx(whole, rel=0.05)
    assert det == 1.0
    # alternating offsets are anti-correlated: rho is clipped to 0 and the correlated reading is the white CRB
    assert pc.correlated_crb_sd_m(tg, scene, ship, nav) == pytest.approx(crb_m, rel=1e-9)


def test_the_correlated_crb_reading_widens_the_bound_for_slow_errors():
    """Offsets that drift slowly (a sine of period 200 s, sd 0.2 deg, as a second ship in the beam makes them) have a
    lag-1 correlation near 1 (clipped at 0.95): the reading is the AR(1) bound at that rho, more than twice the
    white one of the same sd (sqrt((1 + rho) / (1 - rho)) = 6.2 times where the geometry varies slowly against the
    errors)."""
    from types import SimpleNamespace

    from sonartrack.tma.batch_ml import crb_position_sd_m

    scene = pc.draw_scene(pc.Config(), 3)
    nav = pc.navigation(scene_geometry(scene, np.arange(0.0, 601.0)))
    t = np.arange(10.0, 590.0, 2.0)
    ship = 0
    g = scene_geometry(scene, t)
    offset = 0.2 * np.sqrt(2.0) * np.sin(2 * np.pi * t / 200.0)
    track = SimpleNamespace(time_s=t, cone_deg=np.rad2deg(g.cone_rad[ship]) + offset)
    solution = SimpleNamespace(time_s=t, state=np.zeros((len(t), 4)), range_flags=lambda: np.ones(len(t), bool))
    tg = SimpleNamespace(track=track, ml=SimpleNamespace(record=SimpleNamespace(time_s=t), solution=solution))
    _, white, _, _ = pc.target_errors(tg, scene, ship, nav)
    got = pc.correlated_crb_sd_m(tg, scene, ship, nav)
    x0 = np.concatenate([g.ship_xy[ship, 0], g.ship_velocity[ship, 0]])
    sigma = np.std(np.deg2rad(offset))
    want = crb_position_sd_m(x0, t - t[0], nav.array_at(t)[0], sigma, t[-1] - t[0], rho=0.95)
    assert got == pytest.approx(want, rel=1e-9) and got > 2.0 * white
