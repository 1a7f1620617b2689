"""Benchmarks for bearing + frequency TMA (issue 5, paper P2).

Prints one line per figure:
* one IMM-MGEKF step with 3 modes (numba kernel) against the NumPy reference of the same step and
  against FilterPy (three ExtendedKalmanFilter predict+update calls, i.e. the mode-matched filters
  alone, without IMM mixing -- a lower bound on a FilterPy IMM-EKF step);
* one single-model EKF step against FilterPy's ExtendedKalmanFilter;
* the full bftma-imm study (default config, 100 runs) with 2 local workers, from an empty folder.
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


def main() -> None:
    from filterpy.kalman import ExtendedKalmanFilter

    from sonartrack.filters.imm_ekf import imm_bf_step, imm_bf_step_reference, transition_matrix
    from sonartrack.models.passive import bf_jacobian, bf_measurement, bf_residual
    from sonartrack.models.relative_motion import relative_process_noise, relative_transition

    rng = np.random.default_rng(0)
    r = 3
    x = np.array([[3000.0, 9000, -4, -3, 300.2]] * r) + rng.normal(size=(r, 5)) * [100, 100, 0.5, 0.5, 0.1]
    A = rng.normal(size=(r, 5, 5))
    P = A @ A.transpose(0, 2, 1) + np.diag([1e5, 1e5, 1, 1, 0.01])
    mu = np.array([0.5, 0.3, 0.2])
    Pi = transition_matrix(3, 0.99)
    qs = np.array([1e-5, 1e-3, 1e-1])
    z = np.array([0.33, 300.5])
    u = np.r_[rng.normal(size=4) * [1, 1, 0.1, 0.1], 0.0]
    sb2, sf2 = np.deg2rad(1.0) ** 2, 0.01
    R = np.diag([sb2, sf2])
    out = (np.empty((r, 5)), np.empty((r, 5, 5)), np.empty(r), np.empty(5), np.empty((5, 5)))
    imm_bf_step(x, P, mu, z, u, 2.0, qs, Pi, sb2, sf2, modified=True, out=out)  # compile / load cache
    ours = best_of(lambda: imm_bf_step(x, P, mu, z, u, 2.0, qs, Pi, sb2, sf2, modified=True, q_f0=1e-8, out=out), 20000)
    ref = best_of(lambda: imm_bf_step_reference(x, P, mu, z, u, 2.0, qs, Pi, R, modified=True, q_f0=1e-8), 300)

    ekfs = []
    for j in range(r):
        e = ExtendedKalmanFilter(dim_x=5, dim_z=2, dim_u=5)
        e.F, e.Q, e.B, e.R = relative_transition(2.0), relative_process_noise(2.0, qs[j], 1e-8), -np.eye(5), R
        ekfs.append(e)

    def filterpy_modes():
        for j, e in enumerate(ekfs):
            e.x, e.P = x[j].copy(), P[j].copy()
            e.predict(u=u)
            e.update(z, HJacobian=bf_jacobian, Hx=bf_measurement, residual=bf_residual)

    peer = best_of(filterpy_modes, 300)
    print(f"IMM-MGEKF step, 3 modes: ours {ours * 1e6:.1f} us (numba), peer {ref * 1e6:.1f} us (our NumPy reference), "
          f"ratio {ref / ours:.0f} x (target <= 50 us)")
    print(f"IMM-MGEKF step, 3 modes: ours {ours * 1e3:.4f} ms, peer {peer * 1e3:.4f} ms (FilterPy: 3 x EKF "
          f"predict+update, no mixing), ratio {peer / ours:.0f} x (target: ours <= 0.05 ms)")

    one = (np.empty((1, 5)), np.empty((1, 5, 5)), np.empty(1), np.empty(5), np.empty((5, 5)))
    Pi1, q1, mu1 = np.ones((1, 1)), qs[:1].copy(), np.ones(1)
    x1, P1 = x[:1].copy(), P[:1].copy()
    ours1 = best_of(lambda: imm_bf_step(x1, P1, mu1, z, u, 2.0, q1, Pi1, sb2, sf2, modified=False, out=one), 20000)
    e = ekfs[0]

    def filterpy_one():
        e.x, e.P = x[0].copy(), P[0].copy()
        e.predict(u=u)
        e.update(z, HJacobian=bf_jacobian, Hx=bf_measurement, residual=bf_residual)

    peer1 = best_of(filterpy_one, 1000)
    print(f"EKF step (bearing + frequency): ours {ours1 * 1e3:.4f} ms, peer {peer1 * 1e3:.4f} ms (FilterPy "
          f"ExtendedKalmanFilter), ratio {peer1 / ours1:.0f} x (target: faster than FilterPy)")

    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        proc = subprocess.run([sys.executable, "-m", "sonartrack.cli", "reproduce", "bftma-imm", "--workers", "2",
                               "--out", str(Path(tmp) / "r")], capture_output=True, text=True)
        dt = time.perf_counter() - t0
        if proc.returncode != 0:
            print(f"bftma-imm study: FAILED ({proc.stderr.strip().splitlines()[-1] if proc.stderr.strip() else proc.returncode})")
            sys.exit(1)
        else:
            print(f"bftma-imm study, 100 runs, 2 workers: {dt:.1f} s (target <= 60 s)")


if __name__ == "__main__":
    main()
