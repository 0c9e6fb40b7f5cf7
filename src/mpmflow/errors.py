"""Errors that reach the user as one clear paragraph (no traceback) and an exit code."""


class MpmflowError(Exception):
    """Base class: ``str(err)`` is the whole message for the user."""

    exit_code = 1


class CaseError(MpmflowError):
    """The case file or a command-line setting is invalid; nothing was run."""

    exit_code = 2


class SimulationError(MpmflowError):
    """The run stopped because the computation failed (solver, NaN, blow-up)."""

    exit_code = 3


class SolverError(SimulationError):
    """The pressure solve did not converge."""
