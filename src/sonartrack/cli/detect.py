"""``sonartrack detect``: multi-frame track-before-detect (paper P1) on a user's range-Doppler frames.

Input: a K x Nr x Nd stack of square-law cell values (``--frames``, .npy or .npz, io/frames.py).
Settings (``--config`` TOML, flat keys = the fields of :func:`detect_config_model`): the cell
geometry (pulse, carrier, sound speed, plane origin), the design SNR, sigma_a, N, and the decision
threshold, either given (``threshold``) or calibrated for a false-alarm probability ``pfa`` by
running the same detector on ``calibration_trials`` noise-only stacks of the same shape (seeded).

By default cell values are normalised so that their median matches the noise model's (2 ln 2 for
exponential cells of mean 2, eq. 8): robust to a target occupying a few cells, and it makes the
design SNR mean what it says whatever the receiver's gain.

Outputs (atomic): ``detection.csv`` (the best track, a row per frame), ``detection.png`` (the
frames with the best track drawn over them) and a one-line decision.
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Annotated

import typer

CSV_NAME = "detection.csv"
PNG_NAME = "detection.png"


@functools.lru_cache(maxsize=1)
def detect_config_model():
    from typing import Literal

    from pydantic import BaseModel, ConfigDict, Field

    class DetectConfig(BaseModel):
        """Settings of ``sonartrack detect``; defaults are the paper's (P1, sec. V) and the mftd study's."""

        model_config = ConfigDict(frozen=True, extra="forbid")

        snr_db: float = 5.0
        sigma_a_mps2: float = Field(1.0, gt=0)
        n_tracks: int = Field(10, ge=1)
        period_s: float = Field(2.0, gt=0)
        pulse_s: float = Field(0.125, gt=0)
        carrier_hz: float = Field(30e3, gt=0)
        sound_speed_mps: float = Field(1500.0, gt=0)
        range_min_m: float = 0.0
        range_rate_min_mps: float | None = None
        prior_density: Literal["smoothed", "centre"] = "smoothed"
        normalisation: Literal["median", "none"] = "median"
        threshold: float | None = None
        pfa: float = Field(1e-2, gt=0, lt=1)
        calibration_trials: int = Field(2000, ge=10)
        seed: int = 0

    return DetectConfig


def register(app: typer.Typer) -> None:
    app.command("detect")(detect_cmd)


def detect_cmd(
    frames: Annotated[Path, typer.Option(help="K x Nr x Nd square-law frames (.npy, or .npz with key 'frames').")],
    config: Annotated[Path | None, typer.Option(help="TOML settings (keys: DetectConfig in sonartrack/cli/detect.py).")] = None,
    threshold: Annotated[float | None, typer.Option(help="Decision threshold on the log statistic (default: calibrated).")] = None,
    pfa: Annotated[float | None, typer.Option(help="False-alarm probability for the calibrated threshold (default 0.01).")] = None,
    out: Annotated[Path, typer.Option(help="Output folder.")] = Path("detect-results"),
) -> None:
    """Multi-frame track-before-detect: frames -> decision, statistic, best track (CSV and PNG)."""
    from sonartrack.io import toml as toml_io

    data = toml_io.load(config) if config is not None else {}
    data.update({k: v for k, v in {"threshold": threshold, "pfa": pfa}.items() if v is not None})
    cfg = toml_io.validate(detect_config_model(), data, source="detect config" if config is None else f"detect config {config}")
    typer.echo(run_detect(frames, cfg, out))


def calibrate_threshold(detector, shape, pfa: float, trials: int, seed: int) -> float:
    """Threshold with P(S > t | noise only) = pfa from ``trials`` seeded noise stacks of ``shape``."""
    import numpy as np

    from sonartrack.core.errors import require
    from sonartrack.core.random import trial_rng
    from sonartrack.metrics.roc import thresholds
    from sonartrack.models.swerling import sample_cells

    require(pfa * trials >= 5, f"pfa {pfa:g} needs at least {int(np.ceil(5 / pfa))} calibration trials "
                               f"(have {trials}): raise calibration_trials or give a threshold")
    stats = np.array([detector.detect(sample_cells(trial_rng(seed, i), shape), checked=True).statistic
                      for i in range(trials)])
    return float(thresholds(stats, pfa)[0])


def run_detect(frames_path, cfg, out: Path) -> str:
    import numpy as np

    from sonartrack.detection.mftd import MftdDetector
    from sonartrack.io.frames import read_frames
    from sonartrack.models.range_doppler import RangeDopplerGrid
    from sonartrack.models.swerling import NOISE_MEAN

    y = read_frames(frames_path)
    K, nr, nd = y.shape
    if cfg.normalisation == "median":
        med = float(np.median(y))
        from sonartrack.core.errors import require

        require(med > 0, "the median cell value is 0: cannot normalise; set normalisation = 'none' in the config")
        y = y * (NOISE_MEAN * np.log(2.0) / med)
    grid = RangeDopplerGrid.cw(nr, nd, cfg.pulse_s, cfg.carrier_hz, cfg.sound_speed_mps, cfg.range_min_m,
                               cfg.range_rate_min_mps)
    det = MftdDetector(grid, snr_db=cfg.snr_db, period_s=cfg.period_s, sigma_a_mps2=cfg.sigma_a_mps2,
                       n_tracks=cfg.n_tracks, prior_density=cfg.prior_density)
    res = det.detect(y, checked=True)
    if cfg.threshold is not None:
        thr, how = float(cfg.threshold), "given"
    else:
        thr = calibrate_threshold(det, y.shape, cfg.pfa, cfg.calibration_trials, cfg.seed)
        how = f"Pfa {cfg.pfa:g} from {cfg.calibration_trials} noise-only trials"
    present = res.statistic > thr
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    best = res.tracks[0]
    centres = grid.centres()[best[:, 0] * nd + best[:, 1]]
    import pandas as pd

    table = pd.DataFrame({"frame": np.arange(1, K + 1), "range_index": best[:, 0], "doppler_index": best[:, 1],
                          "range_m": centres[:, 0], "range_rate_mps": centres[:, 1],
                          "cell_value": y[np.arange(K), best[:, 0], best[:, 1]]})
    from sonartrack.io.atomic import write_csv

    csv_path = write_csv(table, out / CSV_NAME, float_format="%.10g")
    png_path = _picture(out / PNG_NAME, y, grid, best, res.statistic, thr, present)
    verdict = "TARGET PRESENT" if present else "no target"
    return (f"detect: {verdict}: statistic {res.statistic:.3f} vs threshold {thr:.3f} ({how}); {K} frames of {nr} x {nd} "
            f"cells; best track from range {centres[0, 0]:.0f} m, {centres[0, 1]:+.2f} m/s to {centres[-1, 0]:.0f} m, "
            f"{centres[-1, 1]:+.2f} m/s; wrote {csv_path} and {png_path}")


def _picture(path: Path, y, grid, best, stat, thr, present) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    K = y.shape[0]
    r0, r1, v0, v1 = grid.extent()
    fig, axes = plt.subplots(1, K, figsize=(2.3 * K, 3.6), sharey=True, squeeze=False)
    c = grid.centres()[best[:, 0] * grid.n_doppler + best[:, 1]]
    for k, ax in enumerate(axes[0]):
        ax.imshow(y[k].T, origin="lower", aspect="auto", extent=(r0, r1, v0, v1), cmap="viridis")
        ax.plot(c[: k + 1, 0], c[: k + 1, 1], "w-", lw=0.8)
        ax.plot(*c[k], "rs", mfc="none", ms=9)
        ax.set(title=f"frame {k + 1}", xlabel="range (m)")
    axes[0, 0].set_ylabel("range-rate (m/s)")
    fig.suptitle(f"{'target present' if present else 'no target'}: statistic {stat:.2f}, threshold {thr:.2f}; "
                 "red: best track", fontsize=9)
    fig.tight_layout()
    from sonartrack.io.atomic import save_figure

    return save_figure(fig, path, dpi=100)
