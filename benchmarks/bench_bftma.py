"""Benchmarks for bearing + frequency TMA (paper P2).

Prints one line per figure:
* one IMM-MGEKF step with 3 modes (numba kernel) against the NumPy reference of the same step and
  against FilterPy (three ExtendedKalmanFilter predict+update calls, i.e. the mode-matched filters
  alone, without IMM mixing -- a lower bound on a FilterPy IMM-EKF step);
* one single-model EKF step against FilterPy's ExtendedKalmanFilter;
* a whole 1201-measurement record through the compiled IMM-MGEKF (no Python between steps), per step;
* the full bftma-imm study (default config, 100 runs) with 2 local workers, from an empty folder
  (``--no-study`` skips it).
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _timing import best_of  # noqa: E402


def _step_case(r: int = 3):
    """A 3-mode IMM state, measurement and model (the same numbers in every run of the benchmark)."""
    from sonartrack.tma.imm_mgekf import ImmBfModel, transition_matrix

    rng = np.random.default_rng(0)
    x = np.array([[3000.0, 9000, -4, -3, 300.2]] * r) + rng.normal(size=(r, 5)) * [100, 100, 0.5, 0.5, 0.1]
    A = rng.normal(size=(r, 5, 5))
    P = A @ A.transpose(0, 2, 1) + np.diag([1e5, 1e5, 1, 1, 0.01])
    mu = np.array([0.5, 0.3, 0.2])
    qs = np.array([1e-5, 1e-3, 1e-1])
    z = np.array([0.33, 300.5])
    u = np.r_[rng.normal(size=4) * [1, 1, 0.1, 0.1], 0.0]
    model = ImmBfModel(qs, transition_matrix(3, 0.99), np.deg2rad(1.0), 0.1, q_f0=1e-8, modified=True)
    return x, P, mu, z, u, model


def bench_steps() -> None:
    from filterpy.kalman import ExtendedKalmanFilter

    from sonartrack.models.passive import bf_jacobian, bf_measurement, bf_residual
    from sonartrack.models.relative_motion import relative_process_noise, relative_transition
    from sonartrack.tma.imm_mgekf import ImmBfModel, imm_bf_step, imm_bf_step_reference

    x, P, mu, z, u, model = _step_case()
    r, R = len(mu), model.R
    out = (np.empty((r, 5)), np.empty((r, 5, 5)), np.empty(r), np.empty(5), np.empty((5, 5)))
    imm_bf_step(x, P, mu, z, u, 2.0, model, out=out)  # compile / load cache
    ours = best_of(lambda: imm_bf_step(x, P, mu, z, u, 2.0, model, out=out), 20000)
    ref = best_of(lambda: imm_bf_step_reference(x, P, mu, z, u, 2.0, model.qs, model.Pi, R, modified=True,
                                                q_f0=1e-8), 300)
    ekfs = []
    for j in range(r):
        e = ExtendedKalmanFilter(dim_x=5, dim_z=2, dim_u=5)
        e.F, e.Q, e.B, e.R = relative_transition(2.0), relative_process_noise(2.0, model.qs[j], 1e-8), -np.eye(5), R
        ekfs.append(e)

    def filterpy(filters):
        for j, e in enumerate(filters):
            e.x, e.P = x[j].copy(), P[j].copy()
            e.predict(u=u)
            e.update(z, HJacobian=bf_jacobian, Hx=bf_measurement, residual=bf_residual)

    peer = best_of(lambda: filterpy(ekfs), 300)
    print(f"IMM-MGEKF step, 3 modes: ours {ours * 1e6:.1f} us (numba), peer {ref * 1e6:.1f} us (our NumPy reference), "
          f"ratio {ref / ours:.0f} x (target <= 50 us)")
    print(f"IMM-MGEKF step, 3 modes: ours {ours * 1e3:.4f} ms, peer {peer * 1e3:.4f} ms (FilterPy: 3 x EKF "
          f"predict+update, no mixing), ratio {peer / ours:.0f} x (target: ours <= 0.05 ms)")
    one = (np.empty((1, 5)), np.empty((1, 5, 5)), np.empty(1), np.empty(5), np.empty((5, 5)))
    ekf = ImmBfModel(model.qs[:1], None, np.deg2rad(1.0), 0.1, modified=False)
    x1, P1, mu1 = x[:1].copy(), P[:1].copy(), np.ones(1)
    ours1 = best_of(lambda: imm_bf_step(x1, P1, mu1, z, u, 2.0, ekf, out=one), 20000)
    peer1 = best_of(lambda: filterpy(ekfs[:1]), 1000)
    print(f"EKF step (bearing + frequency): ours {ours1 * 1e3:.4f} ms, peer {peer1 * 1e3:.4f} ms (FilterPy "
          f"ExtendedKalmanFilter), ratio {peer1 / ours1:.0f} x (target: faster than FilterPy)")


def bench_record() -> None:
    """The bftma-imm scenario's 1201 measurements through run_imm_bf (the study's inner loop)."""
    from sonartrack.models.passive import bf_measurement
    from sonartrack.models.relative_motion import observer_inputs
    from sonartrack.studies.bftma_imm import Config, case_model
    from sonartrack.tma.imm_mgekf import run_imm_bf

    cfg = Config()
    t = cfg.times_s()
    po, vo, _ = cfg.observer().state(t)
    pt, vt, _ = cfg.target().state(t)
    z = bf_measurement(np.column_stack([pt - po, vt - vo, np.full(len(t), cfg.f0_hz)]))
    z = z + np.random.default_rng(0).normal(size=z.shape) * [np.deg2rad(1.0), 0.1]
    u = observer_inputs(t, po, vo)
    x0 = np.r_[9000 * np.sin(z[0, 0]), 9000 * np.cos(z[0, 0]), 0.0, 0.0, z[0, 1]]
    P0 = np.diag([3e6, 3e6, 25.0, 25.0, 1.0])
    model = case_model(cfg, "mgekf", cfg.imm.q_values)
    run_imm_bf(t, z[:, 0], z[:, 1], u, x0, P0, model)  # compile / load cache
    per_step = best_of(lambda: run_imm_bf(t, z[:, 0], z[:, 1], u, x0, P0, model), 1, repeat=40) / (len(t) - 1)
    print(f"IMM-MGEKF record, 3 modes, {len(t)} measurements: {per_step * 1e6:.2f} us per step (compiled loop)")


def bench_study() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        proc = subprocess.run([sys.executable, "-m", "sonartrack.cli", "reproduce", "bftma-imm", "--workers", "2",
                               "--out", str(Path(tmp) / "r")], capture_output=True, text=True)
        dt = time.perf_counter() - t0
    if proc.returncode != 0:
        err = proc.stderr.strip()
        print(f"bftma-imm study: FAILED ({err.splitlines()[-1] if err else proc.returncode})")
        sys.exit(1)
    print(f"bftma-imm study, 100 runs, 2 workers: {dt:.1f} s (target <= 60 s)")


def main() -> None:
    bench_steps()
    bench_record()
    if "--no-study" not in sys.argv[1:]:
        bench_study()


if __name__ == "__main__":
    main()
