"""The live active chain's bounded state: on many cheap pings (an 8-element array, a 3 s listening window, an echo
written here from the geometry, not by our simulator) the rows it keeps stop growing at ``history_s``, and what it
keeps is the newest part of what an unbounded chain keeps (pruning forgets rows only, never the tracker's state)."""

from __future__ import annotations

from datetime import UTC, datetime

import numpy as np
import pytest

from sonartrack.io.stream.types import PingBlock, StreamHeader
from sonartrack.systems.active.contacts import ActiveGeometry
from sonartrack.systems.active.settings import ActiveSettings
from sonartrack.systems.live.active import LiveActive

C_MPS, FC_HZ, BW_HZ, PULSE_S, FS_HZ, WINDOW_S, INTERVAL_S = 1500.0, 1500.0, 400.0, 0.1, 1000.0, 3.0, 4.0
ELEMENTS, SPACING_M, HISTORY_S, PINGS = 8, 0.5, 40.0, 40
SETTINGS = ActiveSettings(spacing_m=SPACING_M, sound_speed_mps=C_MPS)
HEADER = StreamHeader(ELEMENTS, FS_HZ, "float32", datetime(2026, 1, 1, tzinfo=UTC))


def _geometry() -> ActiveGeometry:
    """Source and array at rest 100 m apart along the x axis, the array heading along it."""
    t = np.array([-10.0, PINGS * INTERVAL_S + 10.0])
    return ActiveGeometry(t, np.array([[100.0, 0.0]] * 2), np.zeros((2, 2)), np.zeros(2))


def _pings() -> list[PingBlock]:
    """Complex noise and one target's echo: a baseband LFM from 1500 m abeam of the array, closing 1 m/s (the
    narrowband plane wave across the elements, the delay source -> target -> array)."""
    rng = np.random.default_rng(7)
    n, m = int(WINDOW_S * FS_HZ), np.arange(ELEMENTS) - 0.5 * (ELEMENTS - 1)
    t_pulse = np.arange(int(PULSE_S * FS_HZ)) / FS_HZ
    pulse = np.exp(1j * np.pi * (BW_HZ / PULSE_S) * (t_pulse - 0.5 * PULSE_S) ** 2)
    out = []
    for k in range(PINGS):
        target = np.array([0.0, 1500.0 - 1.0 * k * INTERVAL_S])
        delay_s = (np.hypot(*(target - [100.0, 0.0])) + np.hypot(*target)) / C_MPS
        cos = target[0] / np.hypot(*target)  # cone angle from the array axis (+x)
        x = (rng.standard_normal((ELEMENTS, n)) + 1j * rng.standard_normal((ELEMENTS, n))) / np.sqrt(2)
        i0 = int(round(delay_s * FS_HZ))
        x[:, i0:i0 + len(pulse)] += 3.0 * np.exp(2j * np.pi * FC_HZ * m[:, None] * SPACING_M * cos / C_MPS) * pulse
        out.append(PingBlock(k + 1, k * INTERVAL_S, FC_HZ, BW_HZ, PULSE_S, FS_HZ, x.astype(np.complex64)))
    return out


@pytest.fixture(scope="module")
def runs():
    """(bounded chain, its kept rows after each ping, its result; the unbounded chain's result)."""
    pings, out = _pings(), []
    bounded = LiveActive(SETTINGS, HEADER, nav=_geometry(), history_s=HISTORY_S)
    whole = LiveActive(SETTINGS, HEADER, nav=_geometry(), history_s=1e9)
    kept = []
    for p in pings:
        out += bounded.push_ping(p)
        whole.push_ping(p)
        c = bounded.chain
        kept.append(None if c is None else (len(c.times), len(c.contacts), len(c.single), len(c.gate),
                                            len(c.tracker._rows["time_s"]), len(c.bscan)))
    return bounded, kept, bounded.finish()[0], whole.finish()[0]


def test_the_kept_rows_stop_growing_at_the_history(runs):
    _, kept, result, _ = runs
    per_history = int(HISTORY_S / INTERVAL_S) + 1  # pings within history_s of the newest, both ends in
    assert kept[0] is None and kept[5][0] == 6  # the first ping ran with the second (its interval)
    assert all(k[:5] == (per_history,) * 5 for k in kept[per_history + 1:]), kept
    assert max(k[0] for k in kept if k is not None) == per_history
    t = result.tracks.tracks.time_s
    assert t.size and t.min() >= result.ping_time_s[-1] - HISTORY_S


def test_the_bounded_result_is_the_newest_part_of_the_whole(runs):
    _, _, part, whole = runs
    a, b = part.tracks.tracks, whole.tracks.tracks
    assert b.confirmed.any() and b.time_s.min() < a.time_s.min()  # a track, and rows forgotten
    tail = b.time_s >= a.time_s.min()
    for f in ("time_s", "track_id", "confirmed", "existence", "x"):
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f)[tail], err_msg=f)
    np.testing.assert_array_equal(part.tracks.P, whole.tracks.P[tail])
    first = np.searchsorted(whole.ping_time_s, part.ping_time_s[0])
    np.testing.assert_array_equal(part.ping_time_s, whole.ping_time_s[first:])
    keep = whole.contacts.time_s >= part.ping_time_s[0]
    np.testing.assert_array_equal(part.contacts.xy, whole.contacts.xy[keep])
    shift = whole.contacts.detection[keep][0] - part.contacts.detection[0] if keep.any() else 0
    np.testing.assert_array_equal(part.contacts.detection + shift, whole.contacts.detection[keep])
    assert part.contacts.detection.min() >= 0
