"""The project's own error types: every bad input or failed run ends in one of them,
and the exit code a command ends with for each."""
import signal

# a command's exit codes: 0 success, 2 bad input (InputError), 3 a solver failed
# (SolverError), 4 the run went unstable (its files up to the last good step written)
EXIT_INPUT, EXIT_SOLVER, EXIT_UNSTABLE = 2, 3, 4


class InputError(ValueError):
    """Bad input: the message names the bad value and what is allowed."""


class SolverError(RuntimeError):
    """A contact solver failed on a step (the message names the step and time)."""


class Interrupted(KeyboardInterrupt):
    """SIGINT or SIGTERM; ``signum`` says which (exit code 128 + signum)."""

    def __init__(self, signum: int = signal.SIGINT):
        super().__init__(signal.Signals(signum).name)
        self.signum = int(signum)

    @property
    def code(self) -> int:
        return 128 + self.signum


class Deferred:
    """While the numerical kernels compile or load, a signal is kept, not raised: raised
    inside one of numba's ctypes callbacks it would be printed and lost ("Exception
    ignored"), and the run would go on.  The command line's handler asks ``holding``;
    leaving the block raises the signal kept, if any."""
    holding = False
    pending: list = []

    def __enter__(self):
        Deferred.holding = True
        return self

    def __exit__(self, *exc):
        Deferred.holding = False
        if Deferred.pending and exc[0] is None:
            raise Interrupted(Deferred.pending.pop())
        return False
