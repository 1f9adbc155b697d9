"""Scene files: a beam or a bar, its time grid, contact law and output, in one TOML file.

    python -m skfem_beam run SCENE.toml [--out DIR] [--set time.dt=1e-5 ...] [--T 4]
        [--format F] [--frames N] [--save-every N] [--flush-every N]
        [--checkpoint-every S] [--resume DIR] [--overwrite]
    python -m skfem_beam modes SCENE.toml [--n 6] [--out DIR] [--set ...]

:func:`load` reads a file into the objects of the Python API, one to one (:class:`Scene`:
``problem`` a BeamProblem or a Bar, ``stepping`` a scheme.Stepping, the contact law, the
output options).  Every value is checked by the object it builds; the package checks only
the file's shape: an unknown section or key is refused in one line naming it and the
allowed ones, and a value the schema marks as a number (N), or an array of numbers
(ListOf), that is not one (``"0.5m"``) in one line naming its key path (with the index
inside an array: ``output.probes[0]``).  Relative paths (tables) are relative to the
scene file.  The keys are :data:`BEAM_KEYS`, :data:`BAR_KEYS` and :data:`PLATE_KEYS`
(docs/scene_files.md, docs/plate.md, generated from them).

Choices a TOML file forces:

- obstacles are numbers, polynomials ``{ poly = [c0, c1, c2, ...], about = x0 }``
  (Σ c_k (x − x0)^k, the second paper's convex obstacles) or tables ``{ x = [...],
  g = [...] }`` (linear between the points; its corners need not be mesh nodes), over a
  point (``x``), a span (``x_from``, ``x_to``) or, with neither, the whole beam;
- a beam's u0/v0 tables ``{ x = [...], u = [...] }`` are interpolated by a not-a-knot
  cubic spline (C², its slope gives the Hermite slopes); a bar's linearly (P1);
- ``[initial]`` of a beam is read in the fixed frame (ũ, ũ_t) unless ``fixed_frame =
  false``: a scene with no ``[initial]`` starts at rest, as the papers' pipe does.

The modules, each one job, in the order a file goes through them:

- ``schema``: the key tables and the check of a parsed file against them;
- ``read``: the file read once (TOML, kind, ``--set``, shape checked) into a plain
  :class:`~skfem_beam.scenefile.read.Parsed`; the tables it names; the shipped files;
- ``parts``, ``forcing``, ``obstacles``, ``beam``, ``bar``: the parsed keys → the
  problem (what a beam and a bar share; motion and loads; obstacles and holes; a
  BeamProblem; a Bar);
- ``build``: :func:`load` (read, then build): the problem and what the file leaves to
  inference (contact law, β, output options, [wear]) as one :class:`Scene`;
- ``commands``: the ``run`` and ``modes`` subcommands.
"""
from .schema import (BAR_KEYS, BEAM_KEYS, KINDS, PLATE_KEYS, N, ListOf, NumberOr,  # noqa: F401
                     NumberOrWord)
from .read import apply_set, example
from .build import Scene, load
from .commands import modes_main, run_main

__all__ = ["Scene", "load", "apply_set", "run_main", "modes_main", "example", "BEAM_KEYS",
           "BAR_KEYS", "PLATE_KEYS"]
