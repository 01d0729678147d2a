"""One BLAS thread for acid's numbers, whatever the machine's core count.

OpenBLAS (numpy's and scipy's) starts one thread per core and splits a product or a
factorisation between them; the split changes the order of the floating-point sums, so a QR,
an SVD or a least-squares solve gives other last digits with one thread than with two (the
subspace yardstick's figures moved by up to 1 % between one and two threads on a 2-core
machine). acid's numerical entry points that lean on BLAS (the yardsticks' fits, the
validation, the fit and its HAC covariance) therefore run inside :func:`fixed_threads`, which
holds every loaded BLAS at :data:`BLAS_THREADS` thread for their duration and gives the
caller's setting back afterwards: ``import acid`` changes nothing in the caller's process.

The ``acid`` command is acid's own process: :func:`fix_process` sets the count once at start
for the whole run (and, through the environment, for the BLAS libraries loaded later and the
processes it starts, e.g. Dask workers). On a busy machine the idle threads of a
multi-threaded BLAS spin: on 2 cores at load 5, ``acid validate`` of the walk-through took
5.0-5.5 CPU-s with two threads against 3.9-4.1 CPU-s with one (6.1-7.4 against 3.9-4.2 beside
a CPU hog).
"""

from __future__ import annotations

import functools
import os
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TypeVar

from threadpoolctl import threadpool_limits

#: BLAS threads acid computes with, on every machine.
BLAS_THREADS = 1
#: Environment variables read by the BLAS libraries when they load (OpenBLAS, MKL, BLIS).
BLAS_ENV = ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS")

F = TypeVar("F", bound=Callable)

_lock = threading.Lock()
_depth = 0          # callers inside fixed_threads, all threads together
_limits = None      # the threadpoolctl limiter while _depth > 0
_process = False    # fix_process has run: nothing left to set or give back


@contextmanager
def fixed_threads() -> Iterator[None]:
    """Every BLAS loaded in the process at :data:`BLAS_THREADS` thread(s) inside the block.

    Nested and concurrent blocks share one setting: the first to enter sets it, the last to
    leave gives the original counts back (the count is per process, not per thread)."""
    global _depth, _limits
    with _lock:
        if _depth == 0 and not _process:
            _limits = threadpool_limits(limits=BLAS_THREADS, user_api="blas")
        _depth += 1
    try:
        yield
    finally:
        with _lock:
            _depth -= 1
            if _depth == 0 and _limits is not None:
                _limits.restore_original_limits()
                _limits = None


def fixed_blas(func: F) -> F:
    """``func`` run inside :func:`fixed_threads`."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with fixed_threads():
            return func(*args, **kwargs)

    return wrapper  # type: ignore[return-value]


def fix_process() -> None:
    """For acid's own process (the ``acid`` command): :data:`BLAS_THREADS` for the rest of
    the run, in the BLAS libraries loaded now, those loaded later and the child processes."""
    global _process, _limits
    for name in BLAS_ENV:
        os.environ[name] = str(BLAS_THREADS)
    with _lock:
        threadpool_limits(limits=BLAS_THREADS, user_api="blas")
        _process, _limits = True, None  # a block open now gives nothing back on leaving
