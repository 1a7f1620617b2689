"""Acoustics pictures: a TL field beside its sound-speed profile; TL and SNR against range.

The figure functions return matplotlib Figures; :func:`save_tl_pictures` draws both for
``sonartrack tl`` and saves them atomically.
"""

from __future__ import annotations

from pathlib import Path

from sonartrack.core.units import KM_M
from sonartrack.io.atomic import save_figure

#: colour scale of TL pictures (dB): 40 dB (close) .. 110 dB (far, shadow)
TL_COLOUR_RANGE_DB = (40.0, 110.0)


def tl_field_figure(env, field):
    """Sound speed against depth (left) and the TL field in range and depth (right)."""
    import matplotlib.pyplot as plt

    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(13, 4.5), gridspec_kw={"width_ratios": [1, 4]})
    ax0.plot(env.sound_speed_mps, env.depth_m)
    ax0.invert_yaxis()
    ax0.set(xlabel="c (m/s)", ylabel="depth (m)", title="sound speed")
    im = ax1.pcolormesh(field.ranges_m / KM_M, field.depths_m, field.tl_db, vmin=TL_COLOUR_RANGE_DB[0],
                        vmax=TL_COLOUR_RANGE_DB[1], cmap="jet_r", shading="auto")
    ax1.invert_yaxis()
    ax1.set(xlabel="range (km)", title=f"TL {env.name}, {field.freq_hz:g} Hz, source {field.source_depth_m:g} m (RAM)")
    fig.colorbar(im, ax=ax1, label="TL (dB)")
    return fig


def tl_range_figure(env_name: str, perf):
    """TL (raw and range-averaged) and SNR against range; detection ranges shaded green."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(10, 4.5))
    r = perf.ranges_m / KM_M
    ax.plot(r, perf.tl_db, color="0.7", lw=0.6, label=f"TL at {perf.receiver_depth_m:g} m")
    ax.plot(r, perf.tl_avg_db, "b", label="TL, range average")
    ax.invert_yaxis()
    ax.set(xlabel="range (km)", ylabel="TL (dB)")
    ax2 = ax.twinx()
    ax2.plot(r, perf.snr_db, "r", label="SNR")
    ax2.axhline(perf.threshold_db, color="r", ls=":", lw=0.8)
    ax2.set_ylabel("SNR (dB)", color="r")
    for a, b in perf.detection_ranges_m:
        ax.axvspan(a / KM_M, b / KM_M, color="g", alpha=0.12)
    ax.legend(loc="lower left", fontsize=8)
    ax.set_title(f"{env_name}: TL and SNR against range (green: SNR above {perf.threshold_db:g} dB)")
    return fig


def save_tl_pictures(out: Path, env, field, perf) -> tuple[Path, Path]:
    """``out/tl_field.png`` and ``out/tl_range.png``, written atomically."""
    import matplotlib

    matplotlib.use("Agg")
    out = Path(out)
    a = save_figure(tl_field_figure(env, field), out / "tl_field.png", dpi=100, bbox_inches="tight")
    b = save_figure(tl_range_figure(env.name, perf), out / "tl_range.png", dpi=100, bbox_inches="tight")
    return a, b
