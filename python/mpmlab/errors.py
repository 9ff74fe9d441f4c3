"""The errors mpmlab raises, one class per exit code of `mpm run` (README, "Exit codes").

Every class derives from :class:`Error`, whose ``exit_code`` is the code `mpm run` exits with
for the same cause; the message is the one `mpm` prints. Input errors are also ``ValueError``s,
output errors ``OSError``s.
"""


class Error(Exception):
    """An mpmlab error; ``exit_code`` is `mpm`'s exit code for it."""

    exit_code = 1


class InternalError(Error, RuntimeError):
    """A failure of the code itself (exit code 1)."""

    exit_code = 1


class InputError(Error, ValueError):
    """Invalid input: a configuration key, value, file or call (exit code 2)."""

    exit_code = 2


class RunFailed(Error):
    """A run stopped by a numerical failure; its outputs up to the failing state are written."""


class NonFiniteError(RunFailed):
    """A non-finite value, a singular consistent mass matrix, error norms not finite (3)."""

    exit_code = 3


class LeftGridError(RunFailed):
    """A particle left the grid (4)."""

    exit_code = 4


class InvertedDeformationError(RunFailed):
    """det F <= 0, or a particle domain the basis cannot represent (5)."""

    exit_code = 5


class ReconstructionError(RunFailed):
    """A reconstruction mapping cannot fit an element (6)."""

    exit_code = 6


class Interrupted(Error):
    """The run was interrupted by a signal (7)."""

    exit_code = 7


class OutputError(Error, OSError):
    """An output could not be written (8)."""

    exit_code = 8


class ConservationError(RunFailed):
    """The particle-to-grid mapping lost or created mass or momentum of order one (9)."""

    exit_code = 9


class BasisError(RunFailed):
    """A basis could not be evaluated (max-ent Newton iteration, 10)."""

    exit_code = 10


class SolverError(RunFailed):
    """An iterative mass solver did not converge (11)."""

    exit_code = 11


class ReturnMappingError(RunFailed):
    """A plastic law's return mapping found no admissible stress (12)."""

    exit_code = 12


_BY_CODE = {
    c.exit_code: c
    for c in (InternalError, InputError, NonFiniteError, LeftGridError, InvertedDeformationError,
              ReconstructionError, Interrupted, OutputError, ConservationError, BasisError,
              SolverError, ReturnMappingError)
}


def error_for_exit_code(code):
    """The class raised for `mpm`'s exit code ``code`` (InternalError for an unknown one)."""
    return _BY_CODE.get(code, InternalError)


__all__ = [c.__name__ for c in _BY_CODE.values()] + ["Error", "RunFailed", "error_for_exit_code"]
