"""Shared test fixtures."""

import os

import matplotlib

matplotlib.use("Agg")
# numba-compiled kernels cache into the package; keep test runs from fighting over it
os.environ.setdefault("NUMBA_CACHE_DIR", os.path.join(os.path.dirname(__file__), "..", ".numba-cache"))


def _cpu_s() -> float:
    """CPU time of this process and its waited-for children (a test's subprocesses count), in s."""
    import resource

    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


if os.environ.get("SONARTRACK_TEST_CPU_LOG"):
    # Opt-in: each test's CPU time (setup + call + teardown) and the part of it numba spent compiling, one line a
    # test (CPU s, node id, compile CPU s), appended to the file named by the variable (one file a worker with -n).
    # On a shared machine CPU time, not wall time, says what a test costs; with an empty numba cache (a fresh
    # clone) compiling is much of it.
    import time

    import pytest
    from numba.core import event

    class _CompileCPU(event.Listener):
        """CPU time inside numba's outermost compile events of this process."""

        def __init__(self):
            self.depth, self.start, self.total_s = 0, 0.0, 0.0

        def on_start(self, ev):
            self.depth += 1
            if self.depth == 1:
                self.start = time.process_time()

        def on_end(self, ev):
            self.depth -= 1
            if self.depth == 0:
                self.total_s += time.process_time() - self.start

    _COMPILE = _CompileCPU()
    event.register("numba:compile", _COMPILE)

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_protocol(item, nextitem):
        start, compile_start = _cpu_s(), _COMPILE.total_s
        yield
        worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
        with open(f"{os.environ['SONARTRACK_TEST_CPU_LOG']}.{worker}", "a") as log:
            log.write(f"{_cpu_s() - start:.3f}\t{item.nodeid}\t{_COMPILE.total_s - compile_start:.3f}\n")
