"""``sonartrack tma``: target motion analysis of a user's bearing (and frequency) record.

One command for every TMA method:

* sequential filters (tma/sequential_bf.py, paper P2): ``ekf``, ``mgekf``, ``imm-ekf``, ``imm-mgekf``,
  on bearings, or on bearings + frequency with ``--frequency``;
* batch estimators (tma/batch.py, paper P3): ``ml``, ``em-map``, optionally with a propagation model
  (``--env``, ``--sl``).

File formats: io/tma_files.py. Every method ends in the same outputs, written atomically into
``--out``: ``tma_solution.csv`` (the target solution over time with standard deviations) and
``tactical_picture.png`` (ownship track, bearing lines, estimated target track with 95 % ellipses),
plus a one-line summary on stdout.

Settings come from, in increasing priority: the defaults of ``TmaConfig`` (:func:`tma_config_model`),
a ``--config`` TOML file (flat keys, the fields of ``TmaConfig``), and the command-line options.
"""

from __future__ import annotations

import functools
import os
from pathlib import Path
from typing import Annotated, Literal

import typer

from sonartrack.core.errors import InputError, require

SEQUENTIAL = ("ekf", "mgekf", "imm-ekf", "imm-mgekf")
BATCH = ("ml", "em-map")
CSV_NAME = "tma_solution.csv"
PNG_NAME = "tactical_picture.png"


@functools.lru_cache(maxsize=1)
def tma_config_model():
    """The settings model of ``sonartrack tma`` (built on first use: pydantic is a slow import)."""
    from pydantic import BaseModel, ConfigDict, Field

    class TmaConfig(BaseModel):
        """Settings of ``sonartrack tma`` (TOML keys). Sequential-filter tuning defaults are the bftma-imm
        study's choices; batch defaults are those of ``solve_batch``."""

        model_config = ConfigDict(frozen=True, extra="forbid")

        method: Literal["ekf", "mgekf", "imm-ekf", "imm-mgekf", "ml", "em-map"] = "imm-mgekf"
        frequency: bool = False
        sigma_bearing_deg: float = Field(1.0, gt=0)
        sigma_freq_hz: float = Field(0.1, gt=0)
        # sequential filters
        q_values: list[float] = [1e-5, 1e-3, 1e-1]
        q_single: float = Field(1e-3, ge=0)
        transition_diagonal: float = Field(0.99, gt=0, le=1)
        q_f0: float = Field(1e-8, ge=0)
        initial_range_m: float = Field(10_000.0, gt=0)
        sigma_range_m: float = Field(5_000.0, gt=0)
        sigma_target_velocity_mps: float = Field(5.0, gt=0)
        sigma_f0_hz: float | None = Field(None, gt=0)
        sound_speed_mps: float = Field(1500.0, gt=0)
        # input checks
        max_nav_gap_s: float = Field(120.0, gt=0)
        check_radians: bool = True
        # batch methods
        env: str | None = None
        sl_db: float | None = None
        sigma_snr_db: float = Field(1.0, gt=0)
        freq_hz: float = Field(200.0, gt=0)
        depth_m: float | None = None
        nl_db: float = 73.0
        di_db: float = 12.5
        r_min_m: float = Field(500.0, gt=0)
        r_max_m: float = Field(60_000.0, gt=0)
        batch_window_s: float | None = Field(None, gt=0)
        ekf_q_m2_s3: float = Field(1e-4, ge=0)
        # picture
        ellipses: int = Field(8, ge=0)

    return TmaConfig


def register(app: typer.Typer) -> None:
    app.command("tma")(tma_cmd)


def tma_cmd(
    bearings: Annotated[Path, typer.Option(help="Bearings file (CSV/Parquet): time_s, bearing_deg[, frequency_hz, snr_db].")],
    ownship: Annotated[Path, typer.Option(help="Ownship navigation file (CSV/Parquet): time_s, x_m, y_m.")],
    frequency: Annotated[bool | None, typer.Option("--frequency/--no-frequency",
                                                      help="Use frequency_hz too (sequential methods).")] = None,
    method: Annotated[str | None, typer.Option(help="ekf | mgekf | imm-ekf | imm-mgekf | ml | em-map (default imm-mgekf).")] = None,
    sigma_bearing_deg: Annotated[float | None, typer.Option(help="Bearing noise std (deg; default 1.0).")] = None,
    sigma_freq_hz: Annotated[float | None, typer.Option(help="Frequency noise std (Hz; default 0.1).")] = None,
    env: Annotated[str | None, typer.Option(help="em-map propagation model: a shipped environment (east-summer, ..., see sonartrack tl --list) or a profile file (.toml or .csv).")] = None,
    sl: Annotated[float | None, typer.Option("--sl", help="Source level in dB (ml, em-map).")] = None,
    config: Annotated[Path | None, typer.Option(help="TOML file with settings (keys: the TmaConfig fields in sonartrack/cli/tma.py).")] = None,
    out: Annotated[Path, typer.Option(help="Output folder.")] = Path("tma-results"),
) -> None:
    """Target motion analysis: bearings (+ frequency) and ownship navigation -> target solution CSV and picture."""
    from sonartrack.io import toml as toml_io

    data = toml_io.load(config) if config is not None else {}
    cli = {"method": method, "frequency": frequency, "sigma_bearing_deg": sigma_bearing_deg,
           "sigma_freq_hz": sigma_freq_hz, "env": env, "sl_db": sl}
    data.update({k: v for k, v in cli.items() if v is not None})
    if "method" in data and data["method"] not in SEQUENTIAL + BATCH:
        raise InputError(f"unknown --method '{data['method']}': choose one of {', '.join(SEQUENTIAL + BATCH)}")
    cfg = toml_io.validate(tma_config_model(), data, source="tma config" if config is None else f"tma config {config}")
    line = run_tma(bearings, ownship, cfg, out)
    typer.echo(line)


def run_tma(bearings_path, ownship_path, cfg, out: Path) -> str:
    """Read, solve, write the outputs; return the one-line summary."""
    import numpy as np

    from sonartrack.io.tma_files import check_coverage, read_bearings, read_ownship, write_solution_csv

    record = read_bearings(bearings_path, check_radians=cfg.check_radians)
    own = read_ownship(ownship_path)
    check_coverage(record, own, cfg.max_nav_gap_s)
    sigma_b = float(np.deg2rad(cfg.sigma_bearing_deg))
    extra = ""
    if cfg.method in SEQUENTIAL:
        require(cfg.env is None and cfg.sl_db is None,
                f"--env and --sl apply to the batch methods (ml, em-map), not to '{cfg.method}'")
        from sonartrack.tma.sequential_bf import SequentialOptions, solve_sequential

        opts = SequentialOptions(q_values=tuple(cfg.q_values), q_single=cfg.q_single,
                                 transition_diagonal=cfg.transition_diagonal, q_f0=cfg.q_f0,
                                 initial_range_m=cfg.initial_range_m, sigma_range_m=cfg.sigma_range_m,
                                 sigma_target_velocity_mps=cfg.sigma_target_velocity_mps, sigma_f0_hz=cfg.sigma_f0_hz,
                                 sound_speed_mps=cfg.sound_speed_mps)
        solution, track = solve_sequential(record, own, cfg.method, sigma_bearing_rad=sigma_b,
                                           sigma_freq_hz=cfg.sigma_freq_hz, use_frequency=cfg.frequency, options=opts)
        if cfg.frequency:
            extra = f", f0 {track.rel_state[-1, 4]:.2f} ± {np.sqrt(track.rel_cov[-1, 4, 4]):.2f} Hz"
        if cfg.method.startswith("imm"):
            mu = track.mode_prob[-1]
            extra += ", mode probabilities " + "/".join(f"{m:.2f}" for m in mu)
    else:
        require(not cfg.frequency, f"--frequency applies to the sequential methods ({', '.join(SEQUENTIAL)}), "
                                   f"not to '{cfg.method}'")
        try:
            from sonartrack.tma.batch import solve_batch
        except ImportError:
            raise InputError(f"method '{cfg.method}' is not available in this installation") from None
        import warnings

        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            batch_record = record
            if cfg.batch_window_s is not None:
                from sonartrack.tma.records import BearingRecord

                first = record.time_s <= float(record.time_s[0]) + cfg.batch_window_s
                require(0 < first.sum() < len(first), f"batch_window_s = {cfg.batch_window_s:g} s must leave bearings for "
                                                      "both the batch and the EKF")
                batch_record = BearingRecord(record.time_s[first], record.bearing_rad[first], None,
                                             None if record.snr_db is None else record.snr_db[first])
            solution = solve_batch(batch_record, own, cfg.method, sigma_bearing_rad=sigma_b, sigma_snr_db=cfg.sigma_snr_db,
                                   env=cfg.env, sl_db=cfg.sl_db, freq_hz=cfg.freq_hz, depth_m=cfg.depth_m,
                                   r_min_m=cfg.r_min_m, r_max_m=cfg.r_max_m, nl_db=cfg.nl_db, di_db=cfg.di_db)
        for w in caught:
            typer.echo(f"warning: {w.message}", err=True)
        if cfg.batch_window_s is not None:
            # batch on the first window only, then a sequential EKF takes over for the rest (paper P3)
            from sonartrack.tma.batch import ekf_from_batch
            from sonartrack.tma.batch_ml import BatchEstimate
            from sonartrack.tma.records import TmaSolution

            start = BatchEstimate(solution.state[-1], solution.covariance[-1], float(solution.time_s[-1]), 0, True, 0.0,
                                  solution.method)
            ekf = ekf_from_batch(record, own, start, start_s=start.t0_s, sigma_bearing_rad=sigma_b, q_m2_s3=cfg.ekf_q_m2_s3)
            solution = TmaSolution(np.concatenate([solution.time_s, ekf.time_s[1:]]),
                                   np.concatenate([solution.state, ekf.state[1:]]),
                                   np.concatenate([solution.covariance, ekf.covariance[1:]]), ekf.method)
            extra = f", batch on the first {cfg.batch_window_s:g} s then a sequential EKF"
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    csv_path = write_solution_csv(out / CSV_NAME, solution, own)
    png_path = write_tactical_picture(out / PNG_NAME, record, own, solution, cfg.ellipses,
                                      title=f"TMA ({cfg.method}{', bearings + frequency' if cfg.frequency else ''})")
    return _summary(record, own, solution, cfg, extra, csv_path, png_path)


def _summary(record, own, solution, cfg, extra, csv_path, png_path) -> str:
    from sonartrack.io.tma_files import solution_columns

    cols = solution_columns(solution, own)
    i = len(cols["time_s"]) - 1
    n = len(record.time_s)
    what = "bearings + frequencies" if cfg.frequency else "bearings"
    return (f"tma {cfg.method}: {n} {what} over {record.time_s[0]:g}..{record.time_s[-1]:g} s; at {cols['time_s'][i]:g} s "
            f"the target is at range {cols['range_m'][i] / 1e3:.2f} ± {cols['range_std_m'][i] / 1e3:.2f} km, bearing "
            f"{cols['bearing_deg'][i]:.1f} ± {cols['bearing_std_deg'][i]:.1f} deg, course {cols['course_deg'][i]:.0f} ± "
            f"{cols['course_std_deg'][i]:.0f} deg, speed {cols['speed_kn'][i]:.1f} ± {cols['speed_std_kn'][i]:.1f} kn"
            f"{extra}; wrote {csv_path} and {png_path}")


def write_tactical_picture(path, record, own, solution, n_ellipses: int = 8, title: str = "TMA") -> Path:
    """Ownship track, measured bearing lines, estimated target track and its 95 % position ellipses."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    from matplotlib.patches import Ellipse

    t = np.asarray(solution.time_s, float)
    X = np.asarray(solution.state, float)
    P = np.asarray(solution.covariance, float)
    op = own.position_at(record.time_s)
    fig, ax = plt.subplots(figsize=(7, 7))
    est_range = np.hypot(*(X[:, :2] - own.position_at(t)).T)
    length = 1.3 * float(np.nanmax(est_range)) if np.isfinite(est_range).any() else 10_000.0
    step = max(1, len(record.time_s) // 40)
    for k in range(0, len(record.time_s), step):
        b = record.bearing_rad[k]
        ax.plot([op[k, 0] / 1e3, (op[k, 0] + length * np.sin(b)) / 1e3],
                [op[k, 1] / 1e3, (op[k, 1] + length * np.cos(b)) / 1e3], color="0.8", lw=0.6, zorder=1)
    ax.plot([], [], color="0.8", lw=0.6, label="measured bearings")
    ax.plot(np.asarray(own.x_m) / 1e3, np.asarray(own.y_m) / 1e3, "b-", lw=1.5, label="ownship", zorder=3)
    ax.plot(own.x_m[0] / 1e3, own.y_m[0] / 1e3, "bo", zorder=3)
    ax.plot(X[:, 0] / 1e3, X[:, 1] / 1e3, "r-", lw=1.5, label="target (estimated)", zorder=3)
    ax.plot(X[-1, 0] / 1e3, X[-1, 1] / 1e3, "r^", ms=8, zorder=4)
    k95 = np.sqrt(5.991)  # chi-square(2) 95 % quantile
    idx = np.unique(np.linspace(0, len(t) - 1, n_ellipses).round().astype(int)) if n_ellipses > 0 else []
    for j, k in enumerate(idx):
        w, V = np.linalg.eigh(P[k, :2, :2])
        if not np.all(np.isfinite(w)):
            continue
        w = np.maximum(w, 0.0)
        ang = np.degrees(np.arctan2(V[1, 1], V[0, 1]))
        ax.add_patch(Ellipse((X[k, 0] / 1e3, X[k, 1] / 1e3), 2 * k95 * np.sqrt(w[1]) / 1e3, 2 * k95 * np.sqrt(w[0]) / 1e3,
                             angle=ang, fill=False, color="r", lw=0.8, alpha=0.7, zorder=2,
                             label="95 % position ellipses" if j == 0 else None))
    ax.set(xlabel="x east (km)", ylabel="y north (km)", aspect="equal", title=title)
    ax.legend(fontsize=8, loc="best")
    p = Path(path)
    tmp = p.with_name(f".{p.stem}.{os.getpid()}.tmp.png")
    try:
        fig.savefig(tmp, dpi=110, bbox_inches="tight")
        os.replace(tmp, p)
    finally:
        plt.close(fig)
        if tmp.exists():
            tmp.unlink()
    return p
