"""Write tests/reference/reference.npz (see scenes.py for what is pinned).

It was run at commit b43bbf0, before the redesign of issue 15, and builds the scenes as
the code did then; it is kept as the record of how the reference was made.  To make it
again from that code:  git worktree add /tmp/old b43bbf0 && cd /tmp/old &&
python /path/to/tests/reference/make.py  (with PYTHONPATH=/tmp/old)."""
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from scenes import runs  # noqa: E402


class _Old:
    """The scenes as the code before issue 15 built them."""
    from skfem_beam.cases.point_stops import PIPE_RHO_S, problem as point_stops  # noqa

    @staticmethod
    def _pipe(obstacles, element="hermite", **kw):
        from skfem_beam.problem import Beam, BeamProblem, Load
        kw.setdefault("load", Load.uniform(lambda t: np.sin(10 * t)))
        return BeamProblem(Beam(10.0, 282.84, _Old.PIPE_RHO_S), obstacles, J=40,
                           element=element, **kw)

    @staticmethod
    def flat_obstacles(element="hermite"):
        from skfem_beam.cases.flat_obstacles import obstacles
        return _Old._pipe(obstacles(10.0), element)

    @staticmethod
    def convex_obstacles(element="hermite"):
        from skfem_beam.cases.convex_obstacles import obstacles
        return _Old._pipe(obstacles(10.0), element)

    @staticmethod
    def energy_decay(element="hermite"):
        from skfem_beam.cases.convex_obstacles import obstacles
        from skfem_beam.problem import InitialState, Load
        return _Old._pipe(obstacles(10.0, 0.2, 0.3), element, load=Load(),
                          initial=InitialState(u0=lambda x: 0.005 * x**2,
                                               du0=lambda x: 0.01 * x, v0=lambda x: -x))


if __name__ == "__main__":
    data = {}
    for name, make in runs(_Old).items():
        for key, value in make().items():
            data[f"{name}/{key}"] = np.asarray(value)
        print(name)
    np.savez_compressed(Path(__file__).parent / "reference.npz", **data)
