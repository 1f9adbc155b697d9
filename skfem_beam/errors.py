"""The project's own error types: every bad input or failed run ends in one of them."""


class InputError(ValueError):
    """Bad input: the message names the bad value and what is allowed."""


class SolverError(RuntimeError):
    """A contact solver failed on a step (the message names the step and time)."""
