"""Shared timing helpers of the benchmark scripts."""

import os
import subprocess
import threading
import time

import numpy as np


def best_of(fn, n, repeat=5):
    """Best mean time of ``n`` calls over ``repeat`` repetitions (s): the least disturbed by other load."""
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(n):
            fn()
        best = min(best, (time.perf_counter() - t0) / n)
    return best


def _descendants(pid: int) -> list[int]:
    """``pid`` and every process below it (Linux /proc)."""
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        out.append(p)
        try:
            for tid in os.listdir(f"/proc/{p}/task"):
                with open(f"/proc/{p}/task/{tid}/children") as f:
                    todo += [int(x) for x in f.read().split()]
        except OSError:
            pass
    return out


def _cpu_s(pid: int) -> float | None:
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
    except OSError:
        return None
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")  # utime + stime


def run_timed(argv: list[str], **kwargs) -> tuple[subprocess.CompletedProcess, float, float]:
    """Run ``argv`` (stdout and stderr captured as text); (result, wall time, CPU time) in s.

    The CPU time (user + system) is summed over the process and all its descendants, sampled from /proc every
    0.2 s (the worker processes of a study are not children we can wait for, so ``RUSAGE_CHILDREN`` misses
    them). On a machine shared with other work it is the figure to compare: the wall time grows with the
    load, the CPU time hardly. NaN where /proc is missing."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kwargs)
    seen: dict[int, float] = {}  # pid -> its CPU time when last seen
    outputs: list = []
    reader = threading.Thread(target=lambda: outputs.append(proc.communicate()), daemon=True)
    reader.start()
    while reader.is_alive():
        for p in _descendants(proc.pid):
            c = _cpu_s(p)
            if c is not None:
                seen[p] = max(seen.get(p, 0.0), c)
        reader.join(0.2)
    wall = time.perf_counter() - t0
    out, err = outputs[0]
    cpu = sum(seen.values()) if os.path.isdir("/proc") else float("nan")
    return subprocess.CompletedProcess(argv, proc.returncode, out, err), wall, cpu
