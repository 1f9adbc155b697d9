"""The soak in small: runs killed at random instants and at the phases of their end,
resumed (and the resumes killed) until done, every file equal to the uninterrupted run's
(docs/soak.md has the 1,000-cycle run)."""
from skfem_beam.bench import soak


def test_a_small_soak_has_no_hang_no_stuck_folder_no_difference(capsys):
    assert soak.main(["--cycles", "4", "--seed", "7"]) == 0
    out = capsys.readouterr().out
    assert "hangs, stuck folders, differences: 0" in out
