"""What the last bits of a run depend on, besides the code: the machine's fingerprint.

numba compiles the kernels for the host CPU (its name and features, or NUMBA_CPU_NAME /
NUMBA_CPU_FEATURES), OpenBLAS picks its kernels at run time (its architecture, or
OPENBLAS_CORETYPE, and its thread count), numpy dispatches its loops on the CPU's features
(less NPY_DISABLE_CPU_FEATURES), and each library's version changes its arithmetic.  Two
machines with the same fingerprint give the same bits (tests/reference/pins.py records
them); two with different ones give the same numbers to a tolerance (tests/reference/
compare.py).  docs/tests.md says what is checked where."""
from __future__ import annotations

import hashlib
import json
import platform
import subprocess
import sys
from importlib.metadata import version

PACKAGES = ("numpy", "scipy", "numba", "llvmlite", "scikit-fem", "osqp", "daqp", "meshio")


def _cpu_model() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _numba_target() -> dict:
    import llvmlite.binding as ll
    from numba.core import config
    return {"cpu": config.CPU_NAME or ll.get_host_cpu_name(),
            "features": config.CPU_FEATURES if config.CPU_NAME
            else ll.get_host_cpu_features().flatten()}


# numpy's and scipy's BLAS as a fresh interpreter loads them: not whatever else this
# process has loaded by now (cvxopt brings an OpenBLAS of its own) or limited since
_BLAS = """
import json, numpy, scipy.linalg
from threadpoolctl import threadpool_info
print(json.dumps(sorted(f"{i['internal_api']} {i.get('version')} {i.get('architecture')} "
                        f"threads={i['num_threads']}" for i in threadpool_info())))
"""


def _blas() -> list:
    out = subprocess.run([sys.executable, "-c", _BLAS], capture_output=True, text=True,
                         check=True)
    return json.loads(out.stdout)


def _numpy_dispatch() -> list:
    from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__
    return [f for f in __cpu_dispatch__ if __cpu_features__.get(f)]


def fingerprint() -> dict:
    return {"cpu": _cpu_model(), "machine": platform.machine(),
            "python": platform.python_version(), "numba_target": _numba_target(),
            "blas": _blas(), "numpy_dispatch": _numpy_dispatch(),
            "versions": {p: version(p) for p in PACKAGES}}


def label(fp: dict) -> str:
    """A short name for a fingerprint: the file name of its pins."""
    return hashlib.sha256(json.dumps(fp, sort_keys=True).encode()).hexdigest()[:12]


def differences(a: dict, b: dict) -> list[str]:
    """The fingerprint's entries that differ, for the line that says why bits are not checked."""
    return [k for k in sorted(set(a) | set(b)) if a.get(k) != b.get(k)]


if __name__ == "__main__":
    fp = fingerprint()
    print(label(fp))
    print(json.dumps(fp, indent=1))
