"""What a command asks of its output, checked once where it is made: the folder, the
field format, what is kept, how often it is flushed and checkpointed, a resume."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..checks import check_count, check_nonnegative
from .fields import check_format


@dataclass(frozen=True)
class OutputOptions:
    """``out``: the folder; ``overwrite``: replace a folder holding another run;
    ``resume``: the folder of a stopped run to continue (then ``out`` is that folder);
    ``format``: field series xdmf | vtu | both | none; ``frames``: field snapshots kept
    (about); ``save_every``: keep every n-th step in timeseries.csv; ``flush_every``:
    steps between writes of the series; ``checkpoint_every``: seconds between
    checkpoints (None: none while running, one at the end)."""
    out: str | Path | None = None
    overwrite: bool = False
    resume: str | Path | None = None
    format: str = "both"
    frames: int = 200
    save_every: int = 1
    flush_every: int = 20000
    checkpoint_every: float | None = None

    def __post_init__(self):
        for name in ("frames", "save_every", "flush_every"):
            check_count(f"--{name.replace('_', '-')}", getattr(self, name))
        if self.checkpoint_every is not None:
            object.__setattr__(self, "checkpoint_every",
                               check_nonnegative("--checkpoint-every", self.checkpoint_every))
        check_format(self.format)
        if self.resume:
            object.__setattr__(self, "out", self.resume)
