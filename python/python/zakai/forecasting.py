"""Forecasts with intervals: :func:`forecast` (a scenario's method through your data, then
ahead) and :meth:`Filter.forecast` (from a filter's present), both a :class:`Forecast`."""

from __future__ import annotations

import html
from typing import Any, Optional, Union

import numpy as np

from . import _zakai
from ._convert import ArrayLike, _recording_times, _table
from .errors import ConfigError
from .scenario import Scenario


class Forecast:
    """The predictive distribution of the state and of the observations ``steps`` steps
    ahead of a filter, with central intervals.

    The state's law is the method's own (the Gaussian of the Kalman family, the particle
    filter's cloud, a grid or spectral filter's density, the Gaussian-sum mixture), moved
    ahead by the method's prediction. The observation's is ``∫ p(z | x) p(x) dx`` for that law
    and the model's measurement density (for continuous observations the increment over the
    step): exact on the points of a cloud or a grid, the linearised ``N(h(m) + μ, H P Hᵀ + R)``
    for a Gaussian state with Gaussian noise — statsmodels' ``get_forecast(h).conf_int()`` for
    a linear model — and Gauss–Hermite points through any other measurement density. Intervals
    are the distribution functions' quantiles (integers for counts), not mean ± z·sd.

    Attributes
    ----------
    times : ndarray, shape (steps,)
        The forecast's times: the last observation's time plus ``dt``, ``2 dt``, … (for
        :meth:`Filter.forecast`, the time after the filter's present).
    state_mean, state_sd : ndarray, shape (steps, n), or (steps,) when n = 1
        The state's predictive mean and standard deviation.
    state_interval : ndarray, shape (steps, n, 2), or (steps, 2) when n = 1
        The central interval of probability ``level`` of each component.
    observation_mean, observation_sd : ndarray, shape (steps, m), or (steps,) when m = 1
        The observation's predictive mean and standard deviation (infinite for Student's t
        with ν ≤ 2).
    observation_interval : ndarray, shape (steps, m, 2), or (steps, 2) when m = 1
    level : float
    method : str
        The method's display name.
    observing : str
        ``"measurement"``, or ``"increment"`` for continuous observations (the increment of y
        over each step).
    count : bool
        Whether the observations are counts (integer interval bounds).
    index : pandas Index or None
        The times as a pandas index continuing the data's (see :meth:`to_pandas`).
    """

    __slots__ = (
        "times",
        "state_mean",
        "state_sd",
        "state_interval",
        "observation_mean",
        "observation_sd",
        "observation_interval",
        "level",
        "method",
        "observing",
        "count",
        "index",
        "_origin",
        "_dt",
    )

    def __init__(self, raw: dict, *, start: float, dt: float, level: float, origin: Any) -> None:
        ahead = np.asarray(raw["ahead"], dtype=float)

        def squeeze(a: np.ndarray) -> np.ndarray:
            return a[:, 0] if a.shape[1] == 1 else a

        def interval(lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
            both = np.stack([lower, upper], axis=-1)
            return both[:, 0, :] if both.shape[1] == 1 else both

        self.times = start + ahead
        self.state_mean = squeeze(raw["state_mean"])
        self.state_sd = squeeze(raw["state_sd"])
        self.state_interval = interval(raw["state_lower"], raw["state_upper"])
        self.observation_mean = squeeze(raw["observation_mean"])
        self.observation_sd = squeeze(raw["observation_sd"])
        self.observation_interval = interval(raw["observation_lower"], raw["observation_upper"])
        self.level = float(level)
        self.method = origin.name
        self.observing = "increment" if origin._inner.continuous else "measurement"
        self.count = bool(raw["count"])
        self.index = None
        self._origin = origin
        self._dt = float(dt)

    @property
    def steps(self) -> int:
        """Steps ahead."""
        return len(self.times)

    def density(self, grid: ArrayLike, step: int = -1, dim: int = 0) -> np.ndarray:
        """The state's predictive marginal density of component ``dim`` at the points
        ``grid``, ``step`` steps ahead (0 the first; negative counts from the last): the
        method's own density for grid and spectral methods, a kernel estimate from the
        particle filter's cloud, the Gaussian (or mixture) of the others."""
        steps = self.steps
        k = step + steps if step < 0 else step
        if not 0 <= k < steps:
            raise ConfigError(f"step: {step} is not one of the forecast's {steps} steps")
        ahead = self._origin.copy()
        for _ in range(k + 1):
            ahead.predict(self._dt)
        return ahead.density(grid, dim)

    def to_pandas(self) -> Any:
        """The forecast as a pandas DataFrame, one row per step, indexed by the times — a
        continuation of the data's index (dates or periods at its frequency) when the
        forecast follows a pandas series: per state component ``x<i> mean``, ``x<i> sd``,
        ``x<i> lower``, ``x<i> upper``, and per observation component ``z<j> …`` (``dy<j>``
        for increments)."""
        import pandas as pd

        columns: dict[str, Any] = {}

        def add(prefix: str, mean: np.ndarray, sd: np.ndarray, bounds: np.ndarray) -> None:
            mean = mean.reshape(self.steps, -1)
            sd = sd.reshape(self.steps, -1)
            bounds = bounds.reshape(self.steps, mean.shape[1], 2)
            for j in range(mean.shape[1]):
                name = f"{prefix}{j + 1}"
                columns[f"{name} mean"] = mean[:, j]
                columns[f"{name} sd"] = sd[:, j]
                columns[f"{name} lower"] = bounds[:, j, 0]
                columns[f"{name} upper"] = bounds[:, j, 1]

        add("x", self.state_mean, self.state_sd, self.state_interval)
        prefix = "dy" if self.observing == "increment" else "z"
        add(prefix, self.observation_mean, self.observation_sd, self.observation_interval)
        index = self.index if self.index is not None else pd.Index(self.times, name="t")
        return pd.DataFrame(columns, index=index)

    def plot(self) -> Any:
        """The fan: the state's and the observation's predictive means and intervals over the
        steps ahead (matplotlib); the Figure."""
        from . import plotting

        return plotting.forecast(self)

    def __repr__(self) -> str:
        return (
            f"Forecast({self.method}, steps={self.steps}, t={self.times[0]:g}…{self.times[-1]:g}, "
            f"level={self.level:g})"
        )

    def _repr_html_(self) -> str:
        mean = self.observation_mean.reshape(self.steps, -1)
        bounds = self.observation_interval.reshape(self.steps, mean.shape[1], 2)
        prefix = "Δy" if self.observing == "increment" else "z"
        shown = list(range(min(self.steps, 5))) + (
            [self.steps - 1] if self.steps > 5 else []
        )
        labels = (
            [str(v) for v in self.index] if self.index is not None else [f"{t:g}" for t in self.times]
        )
        head = "".join(
            f"<th>{prefix}{j + 1} mean</th><th>{self.level:.0%} interval</th>"
            for j in range(mean.shape[1])
        )
        rows = []
        for i in shown:
            if i == self.steps - 1 and self.steps > 5:
                rows.append(f"<tr><td colspan='{1 + 2 * mean.shape[1]}'>…</td></tr>")
            cells = "".join(
                f"<td>{mean[i, j]:.4g}</td><td>[{bounds[i, j, 0]:.4g}, {bounds[i, j, 1]:.4g}]</td>"
                for j in range(mean.shape[1])
            )
            rows.append(f"<tr><td>{html.escape(labels[i])}</td>{cells}</tr>")
        return (
            f"<b>Forecast</b> by {html.escape(self.method)}, {self.steps} steps"
            f"<table><tr><th>t</th>{head}</tr>{''.join(rows)}</table>"
        )


# The offset of one time unit of datetimes (as `time_unit` names them).
_UNITS = {"s": "seconds", "min": "minutes", "h": "hours", "D": "days", "W": "weeks",
          "M": "months", "Q": "months", "Y": "years"}


def _continued_index(index: Any, steps: int, dt: float, unit: Optional[str]) -> Any:
    """The labels of ``steps`` steps of ``dt`` after a pandas index's last: dates ``dt``
    time units apart when ``unit`` (the ``time_unit`` given) says what a unit is; else
    periods and dates ``dt`` of their frequency apart; None otherwise (the forecast is then
    indexed by its times)."""
    import pandas as pd

    whole = float(dt).is_integer()
    if isinstance(index, pd.PeriodIndex) and whole:
        return pd.period_range(index[-1] + int(dt), periods=steps, freq=index.freq * int(dt),
                               name=index.name)
    if not isinstance(index, pd.DatetimeIndex):
        return None
    freq = index.freq or (pd.infer_freq(index) if len(index) >= 3 else None)
    if freq is not None and whole and unit not in _UNITS:
        return pd.date_range(index[-1], periods=steps + 1, freq=freq * int(dt), name=index.name)[1:]
    if unit in _UNITS:
        size = dt * (3 if unit == "Q" else 1)
        if _UNITS[unit] in ("months", "years"):
            if not float(size).is_integer():
                return None
            offsets = [pd.DateOffset(**{_UNITS[unit]: int(size) * k}) for k in range(1, steps + 1)]
            return pd.DatetimeIndex([index[-1] + o for o in offsets], name=index.name)
        delta = pd.Timedelta(**{_UNITS[unit]: size})
        return pd.DatetimeIndex([index[-1] + delta * k for k in range(1, steps + 1)],
                                name=index.name)
    return None


def forecast(
    scenario: Union[Scenario, str],
    observations: ArrayLike,
    steps: int,
    *,
    method: Optional[str] = None,
    times: Optional[ArrayLike] = None,
    dt: Optional[float] = None,
    level: float = 0.95,
    seed: Optional[int] = None,
    inputs: Optional[ArrayLike] = None,
    time_unit: Optional[str] = None,
) -> Forecast:
    """One of the scenario's methods through your observations, then ``steps`` steps ahead.

    Parameters
    ----------
    scenario : Scenario or str
        Model (autonomous), prior, domain and methods (a preset name works).
    observations : array_like or pandas Series/DataFrame
        As :func:`filter` takes them (NaN is missing; a pandas index gives the times).
    steps : int
        How many steps ahead.
    method : str, optional
        A method key (``"kalman"``) or display name (``"KF"``) among the scenario's methods;
        the first when absent.
    times : array_like, optional
        The observations' times, as :func:`filter` takes them.
    dt : float, optional
        The forecast's step; the scenario's Δτ when absent.
    level : float
        The probability of the central intervals, strictly between 0 and 1.
    seed : int, optional
        Seeds the method's random numbers (particle filter); the scenario's seed when absent.
    inputs : array_like, optional
        A driven model's known inputs over the data, as :func:`filter` takes them (its
        forecast is refused: the inputs ahead are not known).
    time_unit : str, optional
        The unit of datetime times (see :func:`filter`).

    Returns
    -------
    Forecast
        Its :meth:`Forecast.to_pandas` continues the data's pandas index.

    Examples
    --------
    >>> import numpy as np, zakai
    >>> model = zakai.Model.discrete("0", "x", noise_cov=0.3, diffusion=0.5)
    >>> sc = zakai.Scenario(model, zakai.Prior.gaussian(0.0, 4.0), ["kalman"], dt_obs=1.0)
    >>> f = zakai.forecast(sc, np.array([1.2, 0.7, 1.9, 2.4]), steps=3)
    >>> f.observation_interval.shape
    (3, 2)
    >>> bool(np.all(np.diff(f.observation_sd) > 0))  # the further ahead, the wider
    True
    """
    from .runs import _inputs, _scenario, _seed
    from .stepping import Filter

    sc = _scenario(scenario)
    specs = sc.config["methods"]
    if not specs:
        raise ConfigError("methods: the scenario has no method to forecast with")
    chosen = 0
    if method is not None:
        keys, names = [s["method"] for s in specs], sc.method_names
        if method in keys:
            chosen = keys.index(method)
        elif method in names:
            chosen = names.index(method)
        else:
            raise ConfigError(
                f"method: {method!r} is none of the scenario's methods (keys {keys}, "
                f"names {names})"
            )
    if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) or steps < 1:
        raise ConfigError(f"steps: must be a whole number of at least 1 (got {steps!r})")
    t, _unit, index = _recording_times(observations, times, time_unit)
    obs = _table(observations, "observations")
    single = sc.copy()
    single.config["methods"] = [specs[chosen]]
    text, _box = single._text_for(obs, t)
    step = sc.dt_obs if dt is None else float(dt)
    last, _name, raw, inner = _zakai.forecast_recorded(
        text, obs, t, _seed(sc, seed), int(steps), step, float(level), _inputs(inputs)
    )
    origin = Filter._wrap(Scenario.from_json(text), inner)
    out = Forecast(raw, start=last, dt=step, level=level, origin=origin)
    if index is not None and len(index) > 0:
        # Dates step by their frequency unless a unit was given for them.
        out.index = _continued_index(index, int(steps), step, time_unit)
    return out
