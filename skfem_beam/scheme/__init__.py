"""The contact-implicit β-family of Dumont & Paoli (γ = 1/2, β ∈ [0, 1/2]).

Each step solves  u^{n+1} = argmin_{lo ≤ Cu ≤ hi} ½uᵀAu − Fⁿᵀu  with

    A  = M + Δt/2 B + Δt² β K
    Fⁿ = (2M − Δt²(1−2β)K) uⁿ − (M − Δt/2 B + Δt² β K) uⁿ⁻¹ + Δt² Gⁿ
    Gⁿ = β f^{n+1} + (1−2β) fⁿ + β f^{n−1},   fⁿ = (1/Δt)∫_{tₙ}^{tₙ+Δt} f dt

(B = 0 for the beam: the papers' scheme; B is Kelvin–Voigt damping for the bar).  The
free step is computed as the increment  Δ² = u − 2uⁿ + uⁿ⁻¹  of

    A Δ² = Fⁿ − A(2uⁿ − uⁿ⁻¹) = Δt²(Gⁿ − K uⁿ) − Δt B (uⁿ − uⁿ⁻¹):

one banded product instead of two, and the solve's round-off scales with Δ², not u.
The contact law (:mod:`skfem_beam.contact`) turns the free step into multipliers μ and
u^{n+1} = x_free + A⁻¹Cᵀμ.

Modules: ``stepping`` (the time grid, the result), ``operators`` (A, its factor, W, D,
the energy's matrix), ``kernels`` (the compiled loop on one state), ``run`` (start step
with the chosen law, chunks, checkpoints), ``moreau_jean`` (the velocity-level
integrator), ``methods`` (an integrator and its law as one object: what a run steps
with), ``solve`` (the entry point, on top of them all).
"""
from .run import Run
from .solve import drive, solve
from .stepping import Result, Stepping

__all__ = ["Result", "Run", "Stepping", "drive", "solve"]
