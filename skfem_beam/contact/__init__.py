"""Contact laws for one step of the scheme, all in the reduced variables y = C u.

Each step the integrator computes the unconstrained solution x_free = A⁻¹F and
y_free = C x_free.  With W = A⁻¹Cᵀ and the Delassus matrix D = C A⁻¹ Cᵀ, the step's
QP  min ½xᵀAx − Fᵀx, lo ≤ Cx ≤ hi  is equivalent to finding μ with

    y = y_free + D μ,  lo ≤ y ≤ hi,  μ_i ≥ 0 if y_i = lo_i,  μ_i ≤ 0 if y_i = hi_i,
    μ_i = 0 otherwise,

and then x = x_free + W μ; μ/Δt² are the nodal contact forces.  The step solvers
(registry.STEP_SOLVERS) and the two other laws (registry.LAWS: penalty, restitution):

- ``projection``: D diagonal (one constrained value, Lemma 4.1): y = clip(y_free).
- ``active-set``: exact, compiled, warm-started (any m).
- ``osqp``: the general QP engine, set up once per run.
- ``daqp``: exact dual active-set QP (daqp's Model).
- ``penalty``: normal compliance, one-sided springs (needs a stiffness).
- ``restitution``: exact contact with a Newton coefficient of restitution e (Paoli–Schatzman).
- ``round-hole``: exact contact in round holes (second-order cones), boxes beside them.
- ``round-hole-friction``: the same with Coulomb friction on the step's slip (round holes
  and flat faces).
- ``auto``: the cheapest exact one for the scene.

The protocol a law follows (and how to write one) is in :mod:`.base`; ``register(name,
law)`` makes a law of one's own a solver of every front end.
"""
from .base import LAW_SIGNATURE, ContactLaw, StepData, compiled_law
from .registry import LAWS, SOLVERS, STEP_SOLVERS, register, resolve

__all__ = ["LAW_SIGNATURE", "LAWS", "SOLVERS", "STEP_SOLVERS", "ContactLaw", "StepData",
           "compiled_law", "register", "resolve"]
