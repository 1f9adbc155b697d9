"""The hardware floor of one step: a pre-factored banded Cholesky solve (LAPACK dpbtrs),
called from a compiled loop, so that no Python overhead is counted."""
from __future__ import annotations

import ctypes
import time

import numpy as np
from numba import njit
from numba.extending import get_cython_function_address

_p = ctypes.c_void_p
_dpbtrs = ctypes.CFUNCTYPE(None, _p, _p, _p, _p, _p, _p, _p, _p, _p)(
    get_cython_function_address("scipy.linalg.cython_lapack", "dpbtrs"))


@njit
def _loop(ab, b, ints, uplo, steps):
    for _ in range(steps):
        _dpbtrs(uplo.ctypes, ints[0:].ctypes, ints[1:].ctypes, ints[2:].ctypes, ab.ctypes,
                ints[3:].ctypes, b.ctypes, ints[4:].ctypes, ints[5:].ctypes)
        b *= 0.5   # keep the data changing, as a time loop does


def banded_solve_floor(A, steps: int) -> float:
    """Seconds for ``steps`` solves with the banded Cholesky factor of A (LAPACK)."""
    from ..linalg import Banded
    band = Banded(A, factor=True)
    ab = band.lapack_band("chol")
    ints = np.array([band.n, band.kd, 1, band.kd + 1, band.n, 0], dtype=np.int32)
    uplo = np.array([ord("U")], dtype=np.int8)
    b = np.ones(band.n)
    _loop(ab, b, ints, uplo, 10)
    t0 = time.perf_counter()
    _loop(ab, b, ints, uplo, steps)
    return time.perf_counter() - t0
