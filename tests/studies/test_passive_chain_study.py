"""Study passive-chain: its scoring helpers on hand-made tracks, and one short trial through the contract."""

import numpy as np

from sonartrack.studies import passive_chain as pc
from sonartrack.tracking.run import BearingTracks


def _tracks(rows):
    """BearingTracks from (time, id, cone, confirmed) rows."""
    t, tid, cone, conf = (np.array(c) for c in zip(*rows, strict=True))
    zeros = np.zeros(len(t))
    return BearingTracks(time_s=t.astype(float), track_id=tid.astype(int), bearing_deg=cone.astype(float),
                         bearing_rate_deg_s=zeros, bearing_std_deg=zeros, strength=zeros, confirmed=conf.astype(bool))


def test_held_only_by_a_confirmed_track_near_the_ship():
    tw = np.array([0.5, 1.5, 2.5])
    cone = np.array([[40.0, 41.0, 42.0]])
    tracks = _tracks([(0.5, 1, 40.5, True), (1.5, 1, 45.0, True), (2.5, 2, 42.1, False)])
    assert pc.held_by_track(tracks, tw, cone, 3.0).tolist() == [[True, False, False]]


def test_identity_kept_and_swapped():
    tw = np.arange(0.5, 10.5)
    a = np.linspace(40, 60, 10)
    b = np.linspace(60, 40, 10)  # cross at the middle
    cone = np.stack([a, b])
    keep, swap = [], []
    for k, t in enumerate(tw):
        keep += [(t, 1, a[k], True), (t, 2, b[k], True)]
        first, second = (a[k], b[k]) if k < 5 else (b[k], a[k])  # the tracks jump to the other ship
        swap += [(t, 1, first, True), (t, 2, second, True)]
    assert pc.identity_kept(_tracks(keep), tw, cone, (0, 1), 4.0, 1.0) == 1.0
    assert pc.identity_kept(_tracks(swap), tw, cone, (0, 1), 4.0, 1.0) == 0.0


def test_running_median_removes_a_lone_peak():
    x = np.zeros((1, 30))
    x[0, 10] = 50.0
    assert pc.running_median(x, 11).max() == 0.0


def test_a_short_trial_fills_the_contract():
    scene = {"duration_s": 240.0, "ownship": {"turn_start_s": 20.0}}
    config = pc.Config.model_validate({"runs": 1, "scene": scene})
    trial = pc.run_trial(config, np.random.default_rng(5))
    n_ships = len(config.scene.ships)
    assert trial["hold"].shape == (n_ships,) and trial["identity_kept"].shape == (2,)
    stacked = {k: v[None] for k, v in trial.items()}
    summary = pc.summarize(stacked, config)
    claims = pc.claims(summary, config)
    assert [c.id for c in claims] == ["ships-held", "side-resolved", "ml-near-crb", "crossing-identities",
                                      "false-targets"]
    # the loud merchant is above the threshold and held; no target follows nothing in 4 minutes of noise
    assert summary["hold"]["merchant"][0] > 0.8
    assert summary["false_targets"] == 0
