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



#: Calendar units of ``time_unit`` (counted in whole periods: a month is one step whatever
#: its length) and the fixed ones (NumPy's timedelta units).
CALENDAR_UNITS = ("M", "Q", "Y")
FIXED_UNITS = ("W", "D", "h", "min", "s", "ms", "us", "ns")


def _unit_error(what: str) -> ConfigError:
    return ConfigError(
        f"times: {what}: give time_unit= — one of {', '.join(FIXED_UNITS)} (fixed lengths) or "
        f"{', '.join(CALENDAR_UNITS)} (calendar months, quarters, years) — the unit the "
        "model's rates and dt_obs are in"
    )


def _period_steps(periods: Any) -> np.ndarray:
    """Steps of a pandas PeriodIndex from its first period, in its frequency's unit."""
    ordinals = np.asarray(periods.asi8, dtype=np.int64)
    return (ordinals - ordinals[0]).astype(np.float64)


def _times(value: Any, time_unit: Optional[str] = None) -> tuple[Optional[np.ndarray], Optional[str]]:
    """Times as numbers, and their unit (``None`` for numbers given as numbers).

    * Numbers: as they are.
    * A pandas ``PeriodIndex``, or a ``DatetimeIndex`` with a frequency (set, or inferred
      from regular dates): steps of that frequency from the first (a yearly index steps by
      1), unless ``time_unit`` says otherwise.
    * Other datetimes (NumPy ``datetime64``, ``datetime`` objects, an irregular index): need
      ``time_unit``: fixed units (``"D"``, ``"h"``, ``"s"`` …) divide the time since the
      first; calendar units (``"M"``, ``"Q"``, ``"Y"``) count whole periods.
    * ``timedelta64``: in ``time_unit`` (fixed units), seconds when absent.
    """
    if value is None:
        return None, None
    if time_unit is not None and time_unit not in CALENDAR_UNITS + FIXED_UNITS:
        raise ConfigError(
            f"time_unit: {time_unit!r} is not one of {', '.join(FIXED_UNITS + CALENDAR_UNITS)}"
        )
    kind = type(value).__name__
    if kind == "PeriodIndex" and time_unit is None:
        if len(value) and value.isna().any():
            raise ConfigError("times: a period is missing (NaT); every row needs its time")
        return np.ascontiguousarray(_period_steps(value)), value.freqstr
    if kind == "PeriodIndex":
        value = value.to_timestamp()
    a = np.asarray(value)
    if a.dtype.kind == "O" and a.size and all(hasattr(v, "timestamp") for v in a.ravel()):
        a = np.asarray(a, dtype="datetime64[ns]")
    if a.dtype.kind == "M":
        if np.isnat(a).any():
            raise ConfigError("times: a time is missing (NaT); every row needs its time")
        if time_unit is None:
            freq = getattr(value, "freq", None)
            if freq is None and a.size >= 3:
                import pandas as pd

                inferred = pd.infer_freq(pd.DatetimeIndex(a.ravel()))
                freq = None if inferred is None else pd.tseries.frequencies.to_offset(inferred)
            if freq is None:
                raise _unit_error(
                    "datetimes without a frequency (irregular, or too few to infer one)"
                )
            # Regular in its frequency: row k is k steps from the first.
            return np.arange(a.size, dtype=np.float64) * freq.n, freq.base.freqstr
        if time_unit in CALENDAR_UNITS:
            import pandas as pd

            periods = pd.DatetimeIndex(a.ravel()).to_period(time_unit)
            return np.ascontiguousarray(_period_steps(periods)), time_unit
        step = np.timedelta64(1, time_unit if time_unit != "min" else "m")
        return np.ascontiguousarray((a - a.ravel()[0]) / step, dtype=np.float64), time_unit
    if a.dtype.kind == "m":
        if time_unit in CALENDAR_UNITS:
            raise ConfigError(f"time_unit: durations have no calendar; use one of {', '.join(FIXED_UNITS)}")
        unit = time_unit or "s"
        step = np.timedelta64(1, unit if unit != "min" else "m")
        return np.ascontiguousarray(a / step, dtype=np.float64), unit
    if a.dtype.kind not in "biuf":
        raise ConfigError(
            f"times: must be numbers or datetimes, got an array of {a.dtype} "
            "(convert text with pandas.to_datetime first)"
        )
    if time_unit is not None:
        raise ConfigError("time_unit: the times are numbers already, in the model's unit")
    return _array(a, "times"), None



def _table(value: Any, name: str) -> np.ndarray:
    """A pandas Series/DataFrame (or anything else) as a float array: a column that is not
    numeric is refused by name, with the first value that is not a number."""
    if not hasattr(value, "to_numpy"):
        return _array(value, name)
    columns = value.items() if hasattr(value, "columns") else [(getattr(value, "name", None), value)]
    for label, column in columns:
        try:
            np.asarray(column.to_numpy(), dtype=float)
        except (TypeError, ValueError):
            bad = next(v for v in column.to_numpy() if not _is_number(v))
            which = f"column {label!r}" if label is not None else "the series"
            raise ConfigError(
                f"{name}: {which} is not numeric ({column.dtype}): {bad!r} is not a number "
                "(NaN marks a missing value)"
            ) from None
    return _array(value.to_numpy(dtype=float), name)


def _is_number(v: Any) -> bool:
    try:
        float(v)
        return True
    except (TypeError, ValueError):
        return False


def _index_times(
    observations: Any, time_unit: Optional[str] = None
) -> tuple[Optional[np.ndarray], Optional[str], Any]:
    """A pandas object's index as times and their unit (:func:`_times`; a default
    ``RangeIndex`` gives none), and the index itself to label the result."""
    index = getattr(observations, "index", None)
    if index is None or not hasattr(observations, "to_numpy"):
        return None, None, None
    if type(index).__name__ == "RangeIndex":
        return None, None, index
    times, unit = _times(index, time_unit)
    return times, unit, index


def _recording_times(
    observations: Any, times: Any, time_unit: Optional[str]
) -> tuple[Optional[np.ndarray], Optional[str], Any]:
    """The times of a recording — given, else its pandas index's — with their unit, and the
    index that labels the result."""
    given, unit = _times(times, time_unit)
    if given is not None:
        index = getattr(observations, "index", None) if hasattr(observations, "to_numpy") else None
        return given, unit, index
    return _index_times(observations, time_unit)
