"""A load given by its power spectral density: the realised record has that PSD."""
import re

import numpy as np
import pytest
from scipy import signal, stats

from skfem_beam.errors import InputError
from skfem_beam.timefunctions import from_psd, psd_from_csv

F = [5.0, 20.0, 60.0, 80.0]           # Hz: a rising, flat, falling spectrum
S = [0.0, 4.0, 4.0, 1.0]              # N²/m²/Hz


def test_mean_square_is_the_integral_of_the_psd():
    force = from_psd(F, S, seed=3, df=0.05)
    a = np.asarray(force.amplitudes)
    integral = np.trapezoid(S, F)           # linear S: the midpoint rule is exact but for kinks
    assert abs(np.sum(a**2 / 2) - integral) < 1e-3 * integral
    # over one whole period 1/df of the record the mean square is Σ a²/2 exactly
    t = np.arange(0, 20.0, 1 / 400)
    assert np.mean(force(t) ** 2) == pytest.approx(np.sum(a**2 / 2), rel=1e-9)


def test_realised_psd_lies_in_its_95_percent_band():
    """Welch's estimate with K averaged segments is S·χ²(ν)/ν, ν ≈ 2K: 95 % of the
    frequency bins inside the band [χ²(ν, 2.5 %)/ν, χ²(ν, 97.5 %)/ν]·S."""
    fs, T = 400.0, 20.0                 # one period of the record (df = 0.05 Hz)
    force = from_psd(F, S, seed=7, df=0.05)
    t = np.arange(0, T, 1 / fs)
    nperseg = 1024
    f, P = signal.welch(force(t), fs=fs, nperseg=nperseg, window="boxcar", noverlap=0)
    K = t.size // nperseg
    nu = 2 * K
    lo, hi = stats.chi2.ppf(0.025, nu) / nu, stats.chi2.ppf(0.975, nu) / nu
    inside = (f > 22) & (f < 58)        # the flat part, away from the table's kinks
    target = np.interp(f[inside], F, S)
    ratio = P[inside] / target
    assert np.mean((ratio >= lo) & (ratio <= hi)) >= 0.95
    assert abs(np.mean(ratio) - 1) < 0.1


def test_same_seed_same_record_other_seed_other_record():
    a, b, c = from_psd(F, S, seed=1), from_psd(F, S, seed=1), from_psd(F, S, seed=2)
    t = np.linspace(0, 1, 101)
    assert np.array_equal(a(t), b(t)) and not np.allclose(a(t), c(t))


@pytest.mark.parametrize("f, s, word", [
    ([1.0, 1.0, 2.0], [1, 1, 1], "f is not increasing at row 2"),
    ([1.0, 2.0], [1.0, -1.0], "S=-1 in row 2 must be a finite number ≥ 0"),
    ([1.0], [1.0], "at least 2 rows"),
])
def test_bad_tables_are_refused_in_one_line(f, s, word):
    with pytest.raises(InputError, match=word):
        from_psd(f, s)


def test_psd_from_csv_with_a_header(tmp_path):
    path = tmp_path / "psd.csv"
    path.write_text("f_Hz,S\n" + "".join(f"{f},{s}\n" for f, s in zip(F, S)))
    t = np.linspace(0, 2, 50)
    assert np.array_equal(psd_from_csv(path, seed=4)(t), from_psd(F, S, seed=4)(t))
    path.write_text("f,S\n1,2\nx,3\n")
    with pytest.raises(InputError, match="row 3 is not two numbers"):
        psd_from_csv(path)


@pytest.mark.parametrize("text, read, word", [
    # a blank line shifted the row named by one (row 5 for line 6)
    ("t,phi\n0,0\n\n0.05,0.001\n0.1,0.002\n0.15,x\n", "table", "row 6 is not two numbers"),
    # a third value was dropped without a word
    ("t,phi\n0,0\n0.05,0.001\n0.1,0.001,7\n", "table", "row 4 has 3 column(s), needs t, phi"),
    ("t,phi\n0,0\n\n0.1,nan\n", "table", "the second column is not a finite number in row 4"),
    # a PSD's rows were counted without the header (row 2 for line 3)
    ("f,S\n1,0.5\n5,-1\n10,0.5\n", "psd", "S=-1 in row 3 must be"),
    ("f,S\n1,0.5\n5,0.5\n5,0.5\n", "psd", "f is not increasing at row 4"),
])
def test_a_table_names_the_row_of_its_file(tmp_path, text, read, word):
    from skfem_beam.timefunctions import Table
    path = tmp_path / "t.csv"
    path.write_text(text)
    with pytest.raises(InputError, match=re.escape(word)):
        Table.from_csv(path) if read == "table" else psd_from_csv(path)
