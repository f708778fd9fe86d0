"""Exceptions raised by :mod:`zakai`.

Every error carries the message the ``zakai`` command line prints for the same input: the
field path of a scenario problem (``methods[2].particles``), the position of a syntax error
in an expression, the dimensions that disagree.
"""

from __future__ import annotations

__all__ = [
    "ZakaiError",
    "ConfigError",
    "ExpressionError",
    "DimensionError",
    "FilterError",
    "FilterWarning",
]


class ZakaiError(Exception):
    """Base class of every error raised by zakai.

    Attributes
    ----------
    problems : list of (str, str)
        For configuration errors, every ``(field, message)`` found (all at once); empty
        otherwise.
    """

    problems: list[tuple[str, str]]

    def __init__(self, message: str) -> None:
        super().__init__(message)
        self.problems = []


class ConfigError(ZakaiError, ValueError):
    """A scenario, model, prior or method parameter is invalid (all problems listed)."""


class ExpressionError(ConfigError):
    """A text expression of the model or prior is invalid (the message gives the position)."""


class DimensionError(ZakaiError, ValueError):
    """Array shapes do not fit the model (state dimension n, observation dimension m)."""


class FilterError(ZakaiError, RuntimeError):
    """A filter failed while stepping (non-finite numbers, lost mass, a wrong step length)."""


class FilterWarning(RuntimeWarning):
    """A method failed on the data where the call still returns a result: the log-likelihood
    of a method that failed part-way is ``-inf``, and the message names the method, the step
    and the reason."""
