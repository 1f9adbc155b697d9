"""What every front end builds once and hands to a scene's runner (``cases._beam``,
``cases.impacting_bar``): the time grid, the method, the output options and the
summary's config.  The command line builds it from its flags (``cli.spec``), a scene
file from its keys (``scenefile.commands.run_main``); nothing below them reads their words."""
from __future__ import annotations

from dataclasses import dataclass, field

from .methods import Method, recorded_beta
from .output.options import OutputOptions
from .scheme.stepping import Stepping


@dataclass(frozen=True)
class RunSpec:
    """``stepping``: Δt, T and what is kept; ``method``: :mod:`skfem_beam.methods` (the
    β-scheme's carry β);
    ``options``: the output folder and streaming; ``config``: summary.json's record of
    what the user asked for, in the front end's own words (a resume compares it);
    ``mass``: the beam's mass matrix (consistent | redistributed); ``probes``: abscissae
    (m) whose displacement, velocity, moment and shear are written; ``wear``: Archard's
    law at the supports (:class:`~skfem_beam.output.supports.Wear`, two planes) or None."""
    stepping: Stepping
    method: Method
    options: OutputOptions
    config: dict = field(default_factory=dict)
    mass: str = "consistent"
    probes: tuple = ()
    wear: object = None

    @property
    def beta(self) -> float:
        """The β-scheme method's β; Moreau–Jean has none: the β its front end was given
        (config "beta"), which summary.json records, as it always has."""
        return recorded_beta(self.method, self.config.get("beta"))
