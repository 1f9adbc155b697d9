"""Functions of time for support motions and loads, each vectorised in t (any array
shape) with the derivatives a prescribed motion needs: ``f(t)``, ``f.d(t)`` (first) and
``f.dd(t)`` (second).

- :class:`Sine` A sin(ωt + phase) (the default support motion);
- :class:`SumOfSines` Σ A_k sin(ω_k t + phase_k);
- :class:`Table` a table t_i, φ_i (e.g. a measured support motion, :meth:`Table.from_csv`)
  interpolated by a cubic spline;
- :func:`band_limited` a random sum of sines over a frequency band, reproducible by seed;
- :func:`from_psd`, :func:`psd_from_csv` a random force with a given power spectral density;
- :class:`Constant` c (a dead load; with :class:`Ramp` a slowly applied one).

**Why a cubic spline for tables.** The lifting turns a support motion φ into the load
−h φ'' (docs/design.md §1), so φ'' must exist and be piecewise continuous.  A cubic
spline is C² (φ'' piecewise linear, continuous), its φ'' converges like Δt_table² for
smooth data, and it reproduces cubics exactly.  End condition: *not-a-knot* (the first
two and the last two pieces are one cubic), so that no guess of the end slopes or
curvatures enters.  Outside [t_0, t_last] the table is held constant (φ' = φ'' = 0).
"""
from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .checks import check_count, check_finite, check_nonnegative, check_positive
from .errors import InputError


def _t(t) -> np.ndarray:
    return np.asarray(t, dtype=float)


class _FromEval:
    """φ(t), φ'(t), φ''(t) of a time function that evaluates any of them in ``_eval``."""

    def __call__(self, t):
        return self._eval(t, 0)

    def d(self, t):
        return self._eval(t, 1)

    def dd(self, t):
        return self._eval(t, 2)


@dataclass(frozen=True)
class Constant:
    """c, for every t (φ' = φ'' = 0)."""
    value: float = 1.0

    def __post_init__(self):
        object.__setattr__(self, "value", check_finite("value", self.value))

    def __call__(self, t):
        return np.full(np.shape(t), self.value)

    def d(self, t):
        return np.zeros(np.shape(t))

    dd = d


@dataclass(frozen=True)
class Ramp:
    """0 at t ≤ 0, rising smoothly to 1 at t ≥ duration (s = t/T: 3s² − 2s³, C¹)."""
    duration: float

    def __post_init__(self):
        object.__setattr__(self, "duration", check_positive("duration", self.duration))

    def __call__(self, t):
        s = np.clip(_t(t) / self.duration, 0.0, 1.0)
        return s * s * (3 - 2 * s)


@dataclass(frozen=True)
class Sine:
    """amplitude · sin(omega·t + phase)."""
    amplitude: float
    omega: float
    phase: float = 0.0

    def __post_init__(self):
        for name in ("amplitude", "omega", "phase"):
            object.__setattr__(self, name, check_finite(name, getattr(self, name)))

    def __call__(self, t):
        return self.amplitude * np.sin(self.omega * _t(t) + self.phase)

    def d(self, t):
        return self.amplitude * self.omega * np.cos(self.omega * _t(t) + self.phase)

    def dd(self, t):
        return -self.omega ** 2 * self(t)


@dataclass(frozen=True)
class Scaled:
    """factor · f(t) (a support or a load along one plane's share of a direction)."""
    f: object
    factor: float

    def __call__(self, t):
        return self.factor * np.asarray(self.f(t), dtype=float)

    def d(self, t):
        return self.factor * np.asarray(derivative(self.f, 1)(t), dtype=float)

    def dd(self, t):
        return self.factor * np.asarray(derivative(self.f, 2)(t), dtype=float)


@dataclass(frozen=True)
class SumOfSines(_FromEval):
    """Σ_k amplitudes[k] · sin(omegas[k]·t + phases[k])."""
    amplitudes: tuple[float, ...]
    omegas: tuple[float, ...]
    phases: tuple[float, ...] | None = None

    def __post_init__(self):
        a = tuple(check_finite(f"amplitudes[{i}]", v) for i, v in enumerate(self.amplitudes))
        w = tuple(check_finite(f"omegas[{i}]", v) for i, v in enumerate(self.omegas))
        p = (0.0,) * len(a) if self.phases is None else \
            tuple(check_finite(f"phases[{i}]", v) for i, v in enumerate(self.phases))
        if not a or len(w) != len(a) or len(p) != len(a):
            raise InputError(f"SumOfSines needs as many omegas ({len(w)}) and phases "
                             f"({len(p)}) as amplitudes ({len(a)}), at least one")
        object.__setattr__(self, "amplitudes", a)
        object.__setattr__(self, "omegas", w)
        object.__setattr__(self, "phases", p)

    def _eval(self, t, derivative):
        t = _t(t)
        out = np.zeros(t.shape)
        for a, w, p in zip(self.amplitudes, self.omegas, self.phases):
            arg = w * t + p     # only the one term needed (each costs a sine of every t)
            out += a * w ** derivative * (np.cos(arg) if derivative == 1 else
                                          -np.sin(arg) if derivative == 2 else np.sin(arg))
        return out


def band_limited(rms: float, f_low: float, f_high: float, seed: int = 0,
                 count: int = 64) -> SumOfSines:
    """A random motion with its power spread evenly over [f_low, f_high] Hz: ``count``
    sines at equally spaced frequencies with random phases (``numpy.random.default_rng
    (seed)``), scaled so that its mean square over a long time is rms²."""
    rms = check_nonnegative("rms", rms)
    f_low, f_high = check_positive("f_low", f_low), check_positive("f_high", f_high)
    if f_high <= f_low:
        raise InputError(f"f_high={f_high:g} must exceed f_low={f_low:g}")
    count = check_count("count", count)
    rng = np.random.default_rng(check_count("seed", seed, least=0))
    f = np.linspace(f_low, f_high, count)
    a = np.full(count, rms * np.sqrt(2.0 / count))      # Σ a²/2 = rms²
    return SumOfSines(tuple(a), tuple(2 * np.pi * f), tuple(rng.uniform(0, 2 * np.pi, count)))


def from_psd(f, S, seed: int = 0, df: float | None = None,
             source: str = "psd", rows=None) -> SumOfSines:
    """A random force (or motion) with the one-sided power spectral density S(f): ``f`` in
    Hz (increasing, ≥ 0), ``S`` in unit²/Hz (≥ 0; e.g. N²/m²/Hz for a force per length),
    linear between the table's points and zero outside.  The spectral representation
    (Shinozuka): one sine at the middle of each band of width ``df`` over [f₀, f_last]
    with amplitude √(2 S(f_k) df) and a random phase (``numpy.random.default_rng(seed)``),
    so its mean square is Σ S(f_k) df, the table's ∫S df to the midpoint rule.  The
    record repeats after 1/df s: ``df`` defaults to (f_last − f₀)/512; take df ≤ 1/T for a
    run of length T that must not see the repetition.  ``rows``: each value's row in the
    file it came from, for the error lines (default: 1, 2, ...)."""
    f, S = np.asarray(f, dtype=float), np.asarray(S, dtype=float)

    def row(i: int) -> int:
        return rows[i] if rows is not None else i + 1
    if f.ndim != 1 or f.shape != S.shape or f.size < 2:
        raise InputError(f"{source}: needs matching columns f, S of at least 2 rows "
                         f"(got {f.size} and {S.size})")
    for name, col in (("f", f), ("S", S)):
        bad = ~np.isfinite(col) | (col < 0)
        if bad.any():
            i = int(np.argmax(bad))
            raise InputError(f"{source}: {name}={col[i]:g} in row {row(i)} must be a finite "
                             "number ≥ 0")
    if (np.diff(f) <= 0).any():
        i = int(np.argmax(np.diff(f) <= 0)) + 1
        raise InputError(f"{source}: f is not increasing at row {row(i)} "
                         f"(f={f[i]:g} Hz after {f[i - 1]:g})")
    width = f[-1] - f[0]
    df = width / 512 if df is None else check_positive("df", df)
    count = max(1, int(round(width / df)))
    if count > 100_000:
        raise InputError(f"{source}: df={df:g} Hz gives {count} sines over "
                         f"[{f[0]:g}, {f[-1]:g}] Hz; at most 100000 (raise df)")
    df = width / count
    fk = f[0] + (np.arange(count) + 0.5) * df
    a = np.sqrt(2.0 * np.interp(fk, f, S) * df)
    rng = np.random.default_rng(check_count("seed", seed, least=0))
    return SumOfSines(tuple(a), tuple(2 * np.pi * fk), tuple(rng.uniform(0, 2 * np.pi, count)))


def psd_from_csv(path, seed: int = 0, df: float | None = None) -> SumOfSines:
    """:func:`from_psd` of a CSV table of two columns f (Hz), S (unit²/Hz); a first line
    that is not numeric is taken as a header."""
    f, S, lines = _two_columns(Path(path), "f, S")
    return from_psd(f, S, seed, df, source=str(path), rows=lines)


def _two_columns(path: Path, names: str) -> tuple[list, list, list]:
    """The two numeric columns of a CSV file (a non-numeric first line is a header; blank
    lines are skipped) and each value's row, its line in the file; one error line naming
    the file and the row otherwise."""
    try:    # -sig: a byte-order mark (Excel's "CSV UTF-8") made the first row a header
        with open(path, newline="", encoding="utf-8-sig") as fh:
            reader = csv.reader(fh)
            rows = [(reader.line_num, r) for r in reader if r and any(c.strip() for c in r)]
    except OSError as e:
        raise InputError(f"cannot read the table {path}: {e.strerror}") from None
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a UTF-8 text file (a CSV of numbers)") from None
    if rows:
        try:
            float(rows[0][1][0])
        except ValueError:
            rows = rows[1:]
    first, second = [], []
    for line, r in rows:
        if len(r) != 2:     # a third value was dropped without a word
            raise InputError(f"{path}: row {line} has {len(r)} column(s), needs {names}")
        try:
            first.append(float(r[0]))
            second.append(float(r[1]))
        except ValueError:
            raise InputError(f"{path}: row {line} is not two numbers: "
                             f"{','.join(r)!r}") from None
    return first, second, [line for line, _ in rows]


@dataclass(frozen=True)
class Table(_FromEval):
    """φ(t) given at times ``t`` (strictly increasing) by values ``phi``, interpolated by
    a not-a-knot cubic spline (module docstring); constant outside the table."""
    t: tuple[float, ...]
    phi: tuple[float, ...]
    source: str = "table"

    def __post_init__(self):
        t = np.asarray(self.t, dtype=float)
        v = np.asarray(self.phi, dtype=float)
        if t.ndim != 1 or t.shape != v.shape or t.size < 4:
            raise InputError(f"{self.source}: needs matching columns t, phi of at least 4 rows "
                             f"(got {t.size} and {v.size})")
        for name, col in (("t", t), ("phi", v)):
            bad = ~np.isfinite(col)
            if bad.any():
                raise InputError(f"{self.source}: {name} is not a finite number in row "
                                 f"{int(np.argmax(bad)) + 1}")
        steps = np.diff(t)
        if (steps <= 0).any():
            i = int(np.argmax(steps <= 0)) + 1
            raise InputError(f"{self.source}: t is not increasing at row {i + 1} "
                             f"(t={t[i]:g} after {t[i - 1]:g})")
        object.__setattr__(self, "t", tuple(t))
        object.__setattr__(self, "phi", tuple(v))
        from scipy.interpolate import CubicSpline   # 0.15 s: only a tabulated φ needs it
        object.__setattr__(self, "_spline", CubicSpline(t, v, bc_type="not-a-knot"))

    @classmethod
    def from_csv(cls, path) -> "Table":
        """Two columns t, phi; a first line that is not numeric is taken as a header.
        Rows are counted as in the file (the header is row 1)."""
        path = Path(path)
        t, phi, lines = _two_columns(path, "t, phi")
        t_arr = np.asarray(t)
        for name, col in (("the first column", t_arr), ("the second column", np.asarray(phi))):
            nan = np.flatnonzero(~np.isfinite(col))
            if nan.size:    # named by its row in the file
                raise InputError(f"{path}: {name} is not a finite number in row "
                                 f"{lines[int(nan[0])]}")
        bad = np.flatnonzero(np.diff(t_arr) <= 0) if t_arr.size > 1 else []
        if len(bad):
            j = int(bad[0]) + 1
            raise InputError(f"{path}: t is not increasing at row {lines[j]} "
                             f"(t={t_arr[j]:g} after {t_arr[j - 1]:g})")
        return cls(tuple(t), tuple(phi), source=str(path))

    def _eval(self, t, derivative):
        t = _t(t)
        lo, hi = self.t[0], self.t[-1]
        inside = self._spline(np.clip(t, lo, hi), derivative)
        if derivative:
            return np.where((t < lo) | (t > hi), 0.0, inside)
        return inside


def derivative(f, order: int):
    """f.d / f.dd when f has them, otherwise a centred difference (4th order for φ',
    φ''), with a step small next to every time scale a run resolves."""
    name = ("d", "dd")[order - 1]
    if hasattr(f, name):
        return getattr(f, name)
    step = 1e-4
    if order == 1:
        return lambda t: (f(_t(t) - 2 * step) - 8 * f(_t(t) - step) + 8 * f(_t(t) + step)
                          - f(_t(t) + 2 * step)) / (12 * step)
    return lambda t: (-f(_t(t) - 2 * step) + 16 * f(_t(t) - step) - 30 * f(_t(t))
                      + 16 * f(_t(t) + step) - f(_t(t) + 2 * step)) / (12 * step**2)
