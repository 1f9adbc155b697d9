"""The input checks every object uses where it is built: one clear InputError naming
the value and what is allowed.  The Python API and the command line share them."""
from __future__ import annotations

import math

import numpy as np

from .errors import InputError


def check_finite(name: str, value) -> float:
    if isinstance(value, (str, bytes)):     # float("0.2") would take it: the API's numbers
        raise InputError(f"{name}={value!r} is a string: give a number")   # are numbers
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name}={value!r} is not a number") from None
    if not math.isfinite(value):
        raise InputError(f"{name}={value} must be a finite number")
    return value


def check_bound(name: str, value, of: str) -> None:
    """An obstacle's bound: a number (±inf: none; not NaN, not complex) or a vectorised
    function (of ``of``), else one line naming it."""
    if callable(value):
        return
    try:
        ok = not isinstance(value, (str, bytes)) and not np.iscomplexobj(value) \
            and not math.isnan(float(value))
    except (TypeError, ValueError):
        ok = False
    if not ok:
        value = value.item() if isinstance(value, np.generic) else value
        raise InputError(f"{name}={value!r} must be a number (m; ±inf: no bound) or a "
                         f"vectorised function of {of}")


def check_positive(name: str, value) -> float:
    value = check_finite(name, value)
    if value <= 0:
        raise InputError(f"{name}={value:g} must be > 0")
    return value


def check_nonnegative(name: str, value) -> float:
    value = check_finite(name, value)
    if value < 0:
        raise InputError(f"{name}={value:g} must be ≥ 0")
    return value


def check_ratio(name: str, zeta) -> float:
    """A damping ratio: 0 ≤ ζ < 1."""
    zeta = check_nonnegative(name, zeta)
    if zeta >= 1:
        raise InputError(f"{name}={zeta:g} must be below 1: it is a ratio of critical damping "
                         "(0.02 for 2 %)")
    return zeta


def check_beta(beta) -> float:
    beta = check_finite("beta", beta)
    if not 0.0 <= beta <= 0.5:
        raise InputError(f"beta={beta:g} must lie in [0, 1/2]")
    return beta


def check_restitution(e, name: str = "restitution=") -> float:
    """A Newton coefficient of restitution e ∈ [0, 1]; ``name``: the key or flag as the
    user wrote it ("restitution=", "--restitution ")."""
    e = check_finite(name.rstrip("= "), e)
    if not 0.0 <= e <= 1.0:
        raise InputError(f"{name}{e:g} must lie in [0, 1]")
    return e


def check_count(name: str, value, least: int = 1, most: int | None = None,
                beyond: str = "more than a machine's memory holds") -> int:
    """A whole number ≥ ``least`` (bools refused; a float of a whole value, TOML's ``1e3``
    or ``40.0``, taken), ≤ ``most`` when given (``beyond``: why)."""
    if isinstance(value, (float, np.floating)) and np.isfinite(value) and value == int(value):
        value = int(value)
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < least:
        raise InputError(f"{name}={value!r} must be a whole number ≥ {least}")
    if most is not None and value > most:
        raise InputError(f"{name}={value!r} must be at most {most:,}: {beyond}")
    return int(value)


MAX_ELEMENTS = 10_000_000     # along one direction: beyond it numpy raised from inside


def check_choice(name: str, value, allowed) -> str:
    if value not in allowed:
        raise InputError(f"{name}={value!r} is not one of: {', '.join(allowed)}")
    return value
