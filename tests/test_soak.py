"""The soak in small: runs killed at random instants and at the phases of their end, or
stopped by a nearly full disk, resumed (and the resumes killed) until done, every file
equal to the uninterrupted run's (docs/soak.md has the 1,000-cycle run)."""
import os
import re

import pytest

from skfem_beam.bench import soak

# the commands draw their charts: a kill may land while they are drawn
pytestmark = pytest.mark.usefixtures("charts")


def test_a_small_soak_has_no_hang_no_stuck_folder_no_difference(capsys):
    assert soak.main(["--cycles", "4", "--seed", "7"]) == 0
    out = capsys.readouterr().out
    assert "hangs, stuck folders, differences, crashes: 0" in out


def test_nearly_full_disks_stop_runs_that_resume_to_the_same_files(capsys):
    """Three runs on a tmpfs holding 55–100 % of what they write: exit 3 (or they fit),
    then resumed with a little more room and with room enough: no crash, no stuck
    folder, the uninterrupted run's files."""
    if os.geteuid() != 0:
        pytest.skip("mounting a tmpfs needs root")
    assert soak.main(["--cycles", "3", "--seed", "3", "--only", "full disk"]) == 0
    out = capsys.readouterr().out
    assert "hangs, stuck folders, differences, crashes: 0" in out
    assert int(re.search(r"full-disk runs: (\d+) exited 3", out)[1]) >= 1
    assert re.search(r"full disk\s+done\s+3", out)
