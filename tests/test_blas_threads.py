"""acid's numbers do not depend on the BLAS thread count (acid/_blas.py).

OpenBLAS starts one thread per core; with two threads its QR, SVD and least squares sum in
another order than with one, and the subspace yardstick (PO-MOESP) gave other digits. The
yardsticks, the validation and the fit run with one BLAS thread whatever the machine, and give
the caller's thread count back afterwards.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest
from threadpoolctl import threadpool_info, threadpool_limits

from acid._blas import BLAS_THREADS, fixed_blas, fixed_threads
from acid.ident.yardsticks import evaluate

# a fixed record of a 4-state system with 4 outputs and 3 inputs (piecewise-constant random
# inputs, white output noise): large enough that OpenBLAS splits the QR of PO-MOESP's Hankel
# matrices between two threads; the subspace yardstick predicts 20 windows of 60 steps
RECORD = """
import json
import numpy as np
from threadpoolctl import threadpool_info
from acid.ident.yardsticks import evaluate
rng = np.random.default_rng(7)
n, ny, nu, N = 4, 4, 3, 1440
A = np.diag([0.97, 0.9, 0.8, 0.6]) + 0.02 * rng.normal(size=(n, n))
B, C = rng.normal(size=(n, nu)), rng.normal(size=(ny, n))
u = np.repeat(rng.normal(size=(N // 12, nu)), 12, axis=0)
x, y = np.zeros(n), np.empty((N, ny))
for k in range(N):
    y[k] = C @ x
    x = A @ x + B @ u[k]
y += 0.05 * rng.normal(size=y.shape)
k0 = np.arange(800, 1360, 28)
out = evaluate(y, u, np.zeros(N, dtype=int), k0, 60, np.zeros(nu, dtype=bool), (0, 720),
               names=("subspace",))
p = out["subspace"].predicted
print(json.dumps({"threads": max(i["num_threads"] for i in threadpool_info()
                                 if i["user_api"] == "blas"),
                  "order": out["subspace"].settings["order"], "bytes": p.tobytes().hex()}))
"""


def _run(code: str, threads: int) -> dict:
    env = {**os.environ, "OPENBLAS_NUM_THREADS": str(threads)}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=env, timeout=60, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_the_subspace_yardstick_is_bit_identical_with_one_and_two_blas_threads():
    one, two = _run(RECORD, 1), _run(RECORD, 2)
    assert one["threads"] == 1
    # outside acid's entry points the caller's count stands (2, or fewer on a 1-core machine)
    assert two["threads"] == min(2, os.cpu_count() or 1)
    assert one["order"] == two["order"]
    assert one["bytes"] == two["bytes"], "subspace predictions differ between 1 and 2 threads"


def _blas_threads() -> list[int]:
    return [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]


def test_fixed_threads_holds_one_thread_inside_and_gives_the_count_back():
    seen = []

    @fixed_blas
    def inner():
        seen.append(_blas_threads())

    with threadpool_limits(limits=2, user_api="blas"):   # the caller's setting
        before = _blas_threads()
        with fixed_threads():
            inner()                  # nested: still one thread, and not given back early
            seen.append(_blas_threads())
        after = _blas_threads()
    assert len(seen) == 2 and all(t == [BLAS_THREADS] * len(before) for t in seen)
    assert after == before


def test_the_acid_command_sets_one_thread_for_its_process_and_its_children():
    """The console script (``app()`` in standalone mode) sets one thread at start: in the
    BLAS already loaded and, through the environment, in the processes it starts."""
    code = ("import atexit, os\nfrom threadpoolctl import threadpool_info\n"
            "atexit.register(lambda: print('BLAS', os.environ['OPENBLAS_NUM_THREADS'], sorted("
            "{i['num_threads'] for i in threadpool_info() if i['user_api'] == 'blas'}), "
            "flush=True))\n"
            "from acid_cli.main import app\napp(['--version'])\n")
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "2"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=env, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.splitlines()[-1] == "BLAS 1 [1]", out.stdout


def test_a_warning_of_a_wrapped_entry_point_names_its_caller():
    """The wrapper is one more frame: the yardsticks' and the validation's warnings still point
    at the line that called them, not into acid/_blas.py."""
    y, u = np.zeros((200, 1)), np.ones((200, 1))
    with pytest.warns(UserWarning, match="left out") as rec:
        evaluate(y, u, np.zeros(200, dtype=int), np.array([100]), 10, np.zeros(1, bool),
                 (0, 20))
    assert [w.filename for w in rec] == [__file__]
