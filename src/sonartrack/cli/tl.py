"""``sonartrack tl``: transmission loss of a shipped environment or a user profile (paper P3's acoustics).

Computes the RAM TL field for a source at ``--zs`` (cached on disk, acoustics/transmission_loss.py),
the TL and the passive SNR = SL - TL + DI - NL against range at ``--zr`` (1 km averaged), the detection
ranges and convergence zones, and writes atomically into ``--out``: ``tl_field.png`` (the field),
``tl_range.png`` (TL and SNR against range, detection ranges shaded) and ``tl.csv`` (range_m, tl_db,
tl_avg_db, snr_db). ``--list`` prints the shipped environments.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from sonartrack.core.errors import InputError, require


def register(app: typer.Typer) -> None:
    app.command("tl")(tl_cmd)


def tl_cmd(
    env: Annotated[str | None, typer.Option(help="Shipped environment (see --list).")] = None,
    profile: Annotated[Path | None, typer.Option(help="User profile: TOML, or CSV with depth_m and sound_speed_mps "
                                                        "(or temperature_c and salinity_psu).")] = None,
    freq: Annotated[float, typer.Option(help="Frequency (Hz).")] = 200.0,
    zs: Annotated[float, typer.Option(help="Source (target) depth (m).")] = 50.0,
    zr: Annotated[float | None, typer.Option(help="Receiver depth (m; default = zs).")] = None,
    rmax: Annotated[float, typer.Option(help="Maximum range (km).")] = 50.0,
    water_depth: Annotated[float | None, typer.Option(help="Water depth (m) for a CSV profile (default: its last depth).")] = None,
    sl: Annotated[float, typer.Option("--sl", help="Source level (dB).")] = 140.0,
    nl: Annotated[float, typer.Option("--nl", help="Noise level (dB).")] = 73.0,
    di: Annotated[float, typer.Option("--di", help="Directivity index (dB).")] = 12.5,
    threshold: Annotated[float, typer.Option(help="Detection threshold on the SNR (dB).")] = 0.0,
    list_: Annotated[bool, typer.Option("--list", help="List the shipped environments and exit.")] = False,
    out: Annotated[Path, typer.Option(help="Output folder.")] = Path("tl-results"),
) -> None:
    """Transmission loss (RAM), SNR against range, detection ranges and convergence zones."""
    from sonartrack.acoustics.environment import list_environments, load_environment, read_profile

    if list_:
        for name in list_environments():
            e = load_environment(name)
            typer.echo(f"{name}: {e.description}")
        return
    if (env is None) == (profile is None):
        raise InputError("give exactly one of --env NAME or --profile FILE (see sonartrack tl --list)")
    require(rmax > 0, f"--rmax must be positive (km), got {rmax:g}")
    require(rmax <= 500, f"--rmax {rmax:g} km: the range is in kilometres, not metres")
    e = load_environment(env) if env is not None else read_profile(profile, water_depth)
    typer.echo(run_tl(e, freq, zs, zs if zr is None else zr, rmax * 1e3, sl, nl, di, threshold, out))


def run_tl(env, freq, zs, zr, rmax_m, sl, nl, di, threshold, out: Path) -> str:

    from sonartrack.acoustics.sonar_equation import convergence_zones, detection_ranges, passive_snr_db
    from sonartrack.acoustics.transmission_loss import smooth_tl, tl_field

    require(0 < zr < env.water_depth_m, f"receiver depth {zr:g} m must lie inside the water column (0..{env.water_depth_m:g} m)")
    f = tl_field(env, freq, zs, rmax_m=rmax_m)
    line = f.at_depth(zr)
    avg = smooth_tl(f.ranges_m, line, 1000.0)
    snr = passive_snr_db(sl, avg, di, nl)
    det = detection_ranges(f.ranges_m, snr, threshold)
    czs = convergence_zones(f.ranges_m, snr, threshold)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    import pandas as pd

    from sonartrack.io.atomic import write_csv

    csv = write_csv(pd.DataFrame({"range_m": f.ranges_m, "tl_db": line, "tl_avg_db": avg, "snr_db": snr}),
                    out / "tl.csv", float_format="%.4f")
    _pictures(out, env, f, zr, line, avg, snr, det, threshold)
    fmt = ", ".join(f"{a / 1e3:.1f}-{b / 1e3:.1f} km" for a, b in det[:6]) or "none"
    cz = f"; convergence zones at {', '.join(f'{a / 1e3:.1f}-{b / 1e3:.1f} km' for a, b in czs[:4])}" if czs else ""
    return (f"tl {env.name}: {freq:g} Hz, source {zs:g} m, receiver {zr:g} m, to {rmax_m / 1e3:g} km; SNR > {threshold:g} dB "
            f"(SL {sl:g}, DI {di:g}, NL {nl:g}) at {fmt}{cz}; wrote {csv}, {out / 'tl_field.png'} and {out / 'tl_range.png'}")


def _save(fig, path: Path) -> None:
    from sonartrack.io.atomic import save_figure

    save_figure(fig, path, dpi=100, bbox_inches="tight")


def _pictures(out, env, f, zr, line, avg, snr, det, threshold) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(13, 4.5), gridspec_kw={"width_ratios": [1, 4]})
    ax0.plot(env.sound_speed_mps, env.depth_m)
    ax0.invert_yaxis()
    ax0.set(xlabel="c (m/s)", ylabel="depth (m)", title="sound speed")
    im = ax1.pcolormesh(f.ranges_m / 1e3, f.depths_m, f.tl_db, vmin=40, vmax=110, cmap="jet_r", shading="auto")
    ax1.invert_yaxis()
    ax1.set(xlabel="range (km)", title=f"TL {env.name}, {f.freq_hz:g} Hz, source {f.source_depth_m:g} m (RAM)")
    fig.colorbar(im, ax=ax1, label="TL (dB)")
    _save(fig, out / "tl_field.png")

    fig, ax = plt.subplots(figsize=(10, 4.5))
    r = f.ranges_m / 1e3
    ax.plot(r, line, color="0.7", lw=0.6, label=f"TL at {zr:g} m")
    ax.plot(r, avg, "b", label="TL, 1 km average")
    ax.invert_yaxis()
    ax.set(xlabel="range (km)", ylabel="TL (dB)")
    ax2 = ax.twinx()
    ax2.plot(r, snr, "r", label="SNR")
    ax2.axhline(threshold, color="r", ls=":", lw=0.8)
    ax2.set_ylabel("SNR (dB)", color="r")
    for a, b in det:
        ax.axvspan(a / 1e3, b / 1e3, color="g", alpha=0.12)
    ax.legend(loc="lower left", fontsize=8)
    ax.set_title(f"{env.name}: TL and SNR against range (green: SNR above {threshold:g} dB)")
    _save(fig, out / "tl_range.png")
