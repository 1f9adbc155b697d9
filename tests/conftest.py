import numpy as np
import pytest

from skfem_beam.cases import point_stops


@pytest.fixture(scope="session")
def pipe():
    """The first paper's scene as a problem object (J=19 Hermite)."""
    return point_stops.problem()


def rate(errors, hs):
    """Least-squares slope of log(error) against log(h)."""
    return np.polyfit(np.log(hs), np.log(errors), 1)[0]
