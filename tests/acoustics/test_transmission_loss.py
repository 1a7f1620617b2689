"""RAM wrapper: inputs untouched, cache identical, and TL against an analytic Pekeris waveguide."""

import numpy as np
import pytest
from scipy.optimize import brentq

from sonartrack.acoustics.environment import Environment
from sonartrack.acoustics.transmission_loss import smooth_tl, thorp_absorption_db_per_km, tl_field, transmission_loss
from sonartrack.core.errors import InputError
from sonartrack.io.environment import TLDiskCache, cached_tl_field

D, CW, CB, RHOB, F = 100.0, 1500.0, 1700.0, 1.8, 100.0


def pekeris():
    return Environment("pekeris", "isovelocity 100 m over a fast fluid bottom", D, np.array([0.0, D]),
                       np.array([CW, CW]), CB, RHOB, 0.0)


def pekeris_tl(r, zs, zr):
    """Normal-mode TL of the Pekeris waveguide (trapped modes; Jensen et al., Computational Ocean
    Acoustics, eqs. 5.14 and 2.191-2.193): pressure-release surface, fluid half-space bottom."""
    kw, kb = 2 * np.pi * F / CW, 2 * np.pi * F / CB
    kz_max = np.sqrt(kw**2 - kb**2)

    def g(kz):
        gam = np.sqrt(max(kz_max**2 - kz**2, 0.0))
        return np.sin(kz * D) * gam + RHOB * kz * np.cos(kz * D)

    grid = np.linspace(1e-9, kz_max * (1 - 1e-12), 20000)
    vals = np.array([g(k) for k in grid])
    roots = [brentq(g, grid[i], grid[i + 1]) for i in np.nonzero(np.sign(vals[:-1]) != np.sign(vals[1:]))[0]]
    p = np.zeros_like(r, dtype=complex)
    for kz in roots:
        kr = np.sqrt(kw**2 - kz**2)
        gam = np.sqrt(kz_max**2 - kz**2)
        norm = (D / 2 - np.sin(2 * kz * D) / (4 * kz)) / 1.0 + np.sin(kz * D) ** 2 / (RHOB * 2 * gam)
        a2 = 1.0 / norm
        p += a2 * np.sin(kz * zs) * np.sin(kz * zr) * np.exp(1j * kr * r) / np.sqrt(kr)
    p *= 1j / np.sqrt(8 * np.pi * r) * np.exp(-1j * np.pi / 4)
    return -20 * np.log10(4 * np.pi * np.abs(p)) + thorp_absorption_db_per_km(F) * r / 1e3


def test_ram_agrees_with_the_pekeris_mode_sum_after_1km_averaging(tmp_path):
    f = tl_field(pekeris(), F, 50.0, rmax_m=21_000.0, store=TLDiskCache(tmp_path))
    ram = smooth_tl(f.ranges_m, f.at_depth(50.0), 1000.0)
    exact = smooth_tl(f.ranges_m, pekeris_tl(f.ranges_m, 50.0, 50.0), 1000.0)
    sel = (f.ranges_m > 3000) & (f.ranges_m < 20000)
    assert np.max(np.abs(ram[sel] - exact[sel])) < 1.0
    # and the TL grows with range as a cylindrical-spreading waveguide should
    assert exact[sel][-1] - exact[sel][0] == pytest.approx(10 * np.log10(20 / 3), abs=3.0)


def test_wrapper_does_not_mutate_inputs_and_cache_is_identical(tmp_path):
    env = pekeris()
    before = (env.depth_m.copy(), env.sound_speed_mps.copy())
    a = tl_field(env, F, 30.0, rmax_m=3000.0, store=TLDiskCache(tmp_path))
    np.testing.assert_array_equal(env.depth_m, before[0])
    np.testing.assert_array_equal(env.sound_speed_mps, before[1])
    files = list(tmp_path.glob("*.npz"))
    assert len(files) == 1
    b = tl_field(env, F, 30.0, rmax_m=3000.0, store=TLDiskCache(tmp_path))
    np.testing.assert_array_equal(a.tl_db, b.tl_db)
    np.testing.assert_array_equal(a.ranges_m, b.ranges_m)
    # any changed input is another field
    tl_field(env, F, 31.0, rmax_m=3000.0, store=TLDiskCache(tmp_path))
    assert len(list(tmp_path.glob("*.npz"))) == 2
    # without a store the field is computed again, and is the same to the last bit (always single precision)
    c = tl_field(env, F, 30.0, rmax_m=3000.0)
    np.testing.assert_array_equal(a.tl_db, c.tl_db)
    line = transmission_loss(env, F, 30.0, 40.0, [0.5, 100.0, 2000.0], rmax_m=3000.0, store=TLDiskCache(tmp_path))
    assert line[0] == pytest.approx(20 * np.log10(1.0))  # below the first step: spherical spreading
    assert 30 < line[1] < line[2]


def test_damaged_cache_file_is_recomputed_and_replaced(tmp_path, monkeypatch):
    env = pekeris()
    a = cached_tl_field(env, F, 30.0, rmax_m=3000.0, cache=tmp_path)
    (path,) = tmp_path.glob("*.npz")
    path.write_bytes(b"not an npz file")
    b = cached_tl_field(env, F, 30.0, rmax_m=3000.0, cache=tmp_path)
    np.testing.assert_array_equal(a.tl_db, b.tl_db)
    assert TLDiskCache(tmp_path).load(path.stem) is not None  # replaced by a readable file
    assert not list(tmp_path.glob(".*"))  # no temporary file left behind
    # and the default folder follows $SONARTRACK_CACHE_DIR
    monkeypatch.setenv("SONARTRACK_CACHE_DIR", str(tmp_path / "elsewhere"))
    cached_tl_field(env, F, 30.0, rmax_m=3000.0)
    assert len(list((tmp_path / "elsewhere" / "tl").glob("*.npz"))) == 1


def test_bad_depths(tmp_path):
    with pytest.raises(InputError, match="inside the water column"):
        tl_field(pekeris(), F, 150.0, rmax_m=3000.0, store=TLDiskCache(tmp_path))
    with pytest.raises(InputError, match="outside the water column"):
        tl_field(pekeris(), F, 30.0, rmax_m=3000.0, store=TLDiskCache(tmp_path)).at_depth(500.0)
