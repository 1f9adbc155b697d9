"""Modified mass (mass redistribution): no inertia at the dofs the constraints act on,
total mass and centre of mass kept; the β-scheme with it: β = 1/2 stable with zero
penetration, β < 1/4 refused with the reason."""
import numpy as np
import pytest

from skfem_beam import InputError, scenes
from skfem_beam.bar import bar_system, run_bar
from skfem_beam.spaces.bspline import BSplineSpace
from skfem_beam.spaces.hermite import HermiteSpace
from skfem_beam.spaces.redistribution import massless_dofs, redistribute, rigid_modes


def moments(M, R):
    return np.array([R[:, 0] @ M @ R[:, 0], R[:, 0] @ M @ R[:, 1]])


def check(M, Mr, R, massless):
    assert np.abs(Mr[massless].toarray()).max() == 0
    assert np.abs(Mr[:, massless].toarray()).max() == 0
    assert np.allclose(moments(Mr, R), moments(M, R), rtol=1e-13, atol=0)
    live = np.setdiff1d(np.arange(M.shape[0]), massless)
    assert np.linalg.eigvalsh(Mr[live][:, live].toarray()).min() > 0


@pytest.mark.parametrize("mass", ["average", "consistent", "lumped"])
def test_bar_contact_node_loses_its_mass(mass):
    s0 = bar_system(scenes.periodic_rod(20, mass=mass))
    R = rigid_modes(s0.space)
    Mr = redistribute(s0.M, s0.K, [0], R)
    check(s0.M, Mr, R, [0])


def test_system_of_a_redistributed_bar():
    s = bar_system(scenes.periodic_rod(20, mass="redistributed"))
    assert s.M[0].nnz == 0 and s.M.shape == (20, 20)


@pytest.mark.parametrize("Space", [HermiteSpace, BSplineSpace])
def test_beam_tip_stop(Space):
    space = Space(np.linspace(0, 1.5, 21))
    C = space.point_rows([1.5]) if Space is HermiteSpace else space.C[-1:]
    c = massless_dofs(C)
    if Space is HermiteSpace:     # the tip displacement only: its rotation keeps its inertia
        assert c.tolist() == [space.n - 2]
    else:                         # every coefficient the tip value reads
        assert c.size == np.count_nonzero(C.toarray())
    R = rigid_modes(space)
    check(space.M, redistribute(space.M, space.S, c, R), R, c)


def test_constraints_along_the_span_refused():
    space = HermiteSpace(np.linspace(0, 1, 11))
    with pytest.raises(InputError, match="isolated points"):
        redistribute(space.M, space.S, massless_dofs(space.C), rigid_modes(space))


@pytest.mark.parametrize("beta", [0.0, 0.2])
def test_beta_below_one_quarter_refused(beta):
    with pytest.raises(InputError, match=f"beta={beta:g} with a mass matrix that has no "
                                         "inertia"):
        run_bar(scenes.periodic_rod(20, mass="redistributed"), 0.01, 1.0, beta=beta)


def test_bar_half_beta_no_penetration_and_energy_kept():
    bar = scenes.impacting_bar(N=80, mass="redistributed")
    r = run_bar(bar, 0.04 / 80, 3.0, beta=0.5)
    assert r.penetration < 1e-15
    # the energy lost at the impact is O(Δt) (the contact node has no kinetic energy)
    assert abs(r.energy[-1] / 0.5 - 1) < 1e-4          # −0.00 % measured (−0.51 % average mass)


def test_loads_refused():
    with pytest.raises(InputError, match="with a load"):
        bar_system(scenes.impacting_bar(N=20, mass="redistributed", f=-1.0))
