"""Conversions of the caller's inputs — NumPy arrays, pandas objects, sequences, text — to
what the Rust core takes, each refused in Python's words when it does not fit."""

from __future__ import annotations

from typing import Any, Iterable, Mapping, Optional, Sequence, Union

import numpy as np

from .errors import ConfigError, DimensionError, ExpressionError



ArrayLike = Union[np.ndarray, Sequence[float], Sequence[Sequence[float]]]
MethodSpec = Union[str, Mapping[str, Any]]



def _numbers(value: Any, name: str) -> np.ndarray:
    """``value`` as a float array of finite numbers, or a :class:`ConfigError` naming it."""
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as e:
        raise ConfigError(f"{name}: must be numbers ({e})") from e
    if not np.isfinite(a).all():
        raise ConfigError(f"{name}: must be finite numbers, got {value!r}")
    return a



Coefficient = Union[float, str]


def _has_text(value: Any) -> bool:
    """Whether ``value`` (a number, text or nested sequence) holds a text entry."""
    if isinstance(value, str):
        return True
    if isinstance(value, (list, tuple)):
        return any(_has_text(v) for v in value)
    return False


def _coefficients(value: Any, name: str) -> np.ndarray:
    """Numbers and expressions in a scenario's parameters (``"sqrt(q)"``) as an object array:
    numbers finite floats, text kept as it is (the core reads and checks it)."""
    a = np.array(value, dtype=object)
    out = np.empty(a.shape, dtype=object)
    for i, v in np.ndenumerate(a):
        if isinstance(v, str):
            out[i] = v
        else:
            out[i] = float(_numbers(v, name))
    return out


def _matrix(value: Any, name: str) -> list[list[Coefficient]]:
    """A square matrix as rows; a scalar is the 1 × 1 matrix. Entries may be expressions in
    the scenario's parameters (``"r"``, ``"sqrt(q)"``)."""
    a = np.atleast_2d(_coefficients(value, name) if _has_text(value) else _numbers(value, name))
    if a.ndim != 2:
        raise DimensionError(f"{name} must be a matrix, got shape {a.shape}")
    return a.tolist()



def _vector(value: Any, name: str = "vector") -> list[Coefficient]:
    """A vector; entries may be expressions in the scenario's parameters."""
    if _has_text(value):
        return np.atleast_1d(_coefficients(value, name)).ravel().tolist()
    return np.atleast_1d(_numbers(value, name)).ravel().tolist()



def _strings(value: Union[str, Iterable[str]], name: str = "expression") -> list[str]:
    """Expressions as a list of text; a Python function is refused in words."""
    if isinstance(value, str):
        return [value]
    if callable(value):
        raise ExpressionError(
            f"{name}: expressions are text such as 'x - x^3', compiled in Rust; a Python "
            "function cannot be called there (Model.from_closures in the Rust crate takes closures)"
        )
    items = list(value)
    for v in items:
        if callable(v) or not isinstance(v, str):
            raise ExpressionError(
                f"{name}: each component is a text expression such as 'x - x^3', got {v!r}"
            )
    return items



def _domain(value: Any) -> list[list[float]]:
    """A (low, high) pair per dimension; one pair alone is the 1-D domain."""
    a = _numbers(value, "domain")
    if a.shape == (2,):
        a = a.reshape(1, 2)
    if a.ndim != 2 or a.shape[1] != 2:
        raise ConfigError(
            f"domain: needs a (low, high) pair per dimension, e.g. [(-4, 4)] in 1-D, got {value!r}"
        )
    return a.tolist()



def _positive_definite(rows: list[list[Any]], name: str) -> list[list[Any]]:
    """``rows`` when they are a symmetric positive definite matrix, else a ConfigError that
    says so (a variance must be positive). Rows with expressions in the scenario's parameters
    are checked by the core, at the parameters' values."""
    if _has_text(rows):
        return rows
    a = np.asarray(rows)
    if a.shape[0] != a.shape[1] or not np.allclose(a, a.T):
        raise ConfigError(f"{name}: must be a symmetric matrix, got {rows!r}")
    if np.linalg.eigvalsh(a).min() <= 0.0:
        what = "a variance" if a.shape == (1, 1) else "a covariance"
        raise ConfigError(f"{name}: {what} must be positive definite (> 0), got {rows!r}")
    return rows



def _array(value: Optional[ArrayLike], name: str) -> Optional[np.ndarray]:
    if value is None:
        return None
    try:
        # C-contiguous and aligned (a copy of an unaligned buffer, e.g. one unpickled by a
        # cluster's worker): the core reads the values in place.
        a = np.require(value, dtype=np.float64, requirements=["C", "A"])
    except (TypeError, ValueError) as e:
        raise DimensionError(f"{name} must be an array of numbers: {e}") from e
    if a.ndim == 0:
        a = a.reshape(1)
    return a


def _aligned(args: tuple) -> tuple:
    """``args`` with every array C-contiguous and aligned: arrays that crossed a process
    boundary (a cluster's worker unpickles them from protocol-5 buffers) may be neither."""
    return tuple(
        np.require(a, dtype=np.float64, requirements=["C", "A"]) if isinstance(a, np.ndarray) else a
        for a in args
    )



def _times(value: Any) -> Optional[np.ndarray]:
    """Times as seconds: numbers as they are; datetimes (NumPy ``datetime64``, pandas
    ``DatetimeIndex`` or ``Series``, ``datetime`` objects) as seconds since the first;
    ``timedelta64`` as seconds."""
    if value is None:
        return None
    a = np.asarray(value)
    if a.dtype.kind == "O" and a.size and all(hasattr(v, "timestamp") for v in a.ravel()):
        a = np.asarray(a, dtype="datetime64[ns]")
    if a.dtype.kind == "M":
        if np.isnat(a).any():
            raise ConfigError("times: a time is missing (NaT); every row needs its time")
        return np.ascontiguousarray((a - a.ravel()[0]) / np.timedelta64(1, "s"), dtype=np.float64)
    if a.dtype.kind == "m":
        return np.ascontiguousarray(a / np.timedelta64(1, "s"), dtype=np.float64)
    if a.dtype.kind not in "biuf":
        raise ConfigError(
            f"times: must be numbers or datetimes, got an array of {a.dtype} "
            "(convert text with pandas.to_datetime first)"
        )
    return _array(a, "times")



def _index_times(observations: Any) -> tuple[Optional[np.ndarray], Any]:
    """A pandas object's index as times (datetimes or numbers; a default ``RangeIndex``
    gives none), and the index itself to label the result."""
    index = getattr(observations, "index", None)
    if index is None or not hasattr(observations, "to_numpy"):
        return None, None
    if type(index).__name__ == "RangeIndex":
        return None, index
    return _times(index), index
