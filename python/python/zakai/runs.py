"""Whole runs: :func:`simulate` a scenario, :func:`run` it, :func:`filter` recorded
observations with every method, :func:`monte_carlo` the papers' tables."""

from __future__ import annotations

import json as _json
import warnings
from typing import Any, Callable, Optional, Union

import numpy as np

from . import _zakai
from .errors import ConfigError, FilterWarning
from ._convert import ArrayLike, _array, _recording_times, _table
from .scenario import Scenario
from .results import RunResult, MonteCarloTable



def _scenario(scenario: Union[Scenario, str]) -> Scenario:
    if isinstance(scenario, Scenario):
        return scenario
    if isinstance(scenario, str):
        return Scenario.from_preset(scenario)
    raise ConfigError(f"expected a Scenario or a preset name, not {type(scenario).__name__}")



def _seed(scenario: Scenario, seed: Optional[int]) -> int:
    value = scenario.seed if seed is None else seed
    if not isinstance(value, (int, np.integer)) or value < 0:
        raise ConfigError(f"seed: must be a nonnegative integer (got {value!r})")
    return int(value)



def simulate(
    scenario: Union[Scenario, str], seed: Optional[int] = None, *, with_inputs: bool = False
) -> tuple:
    """Simulates the scenario's truth and observations.

    Parameters
    ----------
    with_inputs : bool
        Also return the known inputs the run used (a driven model's, from the scenario's
        ``model.inputs`` expressions in t), to pass to :func:`filter` as ``inputs=``.

    Returns
    -------
    times : ndarray, shape (N + 1,)
        τ_k = k Δτ.
    states : ndarray, shape (N + 1, n)
    observations : ndarray, shape (N + 1, m)
        Continuous: row 0 zeros, row k the increment y(τ_k) − y(τ_{k−1}); discrete: z_k.
    inputs : ndarray, shape (N + 1, k), with ``with_inputs``
        Row k: the inputs over (τ_{k−1}, τ_k] (row 0 those a measurement at τ₀ reads).
    """
    sc = _scenario(scenario)
    times, states, observations, inputs = _zakai.simulate(sc._text(), _seed(sc, seed))
    if with_inputs:
        return times, states, observations, inputs
    return times, states, observations



def run(scenario: Union[Scenario, str], seed: Optional[int] = None) -> RunResult:
    """Simulates the run with ``seed`` and filters it with every method of the scenario."""
    sc = _scenario(scenario)
    return _warn_failures(RunResult._from_dict(_zakai.run(sc._text(), _seed(sc, seed))), 3)


def _warn_failures(result: RunResult, stacklevel: int) -> RunResult:
    """A :class:`zakai.FilterWarning` for every method that failed in ``result`` (the method,
    the row, its time and the reason; the other methods' results stand), and ``result``."""
    for m in result.methods.values():
        if m.failure is not None:
            k, t, message = m.failure
            warnings.warn(
                f"{m.name} failed at row {k} (t = {t:.6g}): {message}; its rows from there "
                "are NaN, the other methods' results stand",
                FilterWarning,
                stacklevel=stacklevel,
            )
    return result



def filter(
    scenario: Union[Scenario, str],
    observations: ArrayLike,
    times: Optional[ArrayLike] = None,
    truth: Optional[ArrayLike] = None,
    seed: Optional[int] = None,
    *,
    inputs: Optional[ArrayLike] = None,
    time_unit: Optional[str] = None,
    checks: bool = False,
    density_grid: Optional[ArrayLike] = None,
    density_dim: int = 0,
) -> RunResult:
    """Every method of the scenario on your observations.

    Parameters
    ----------
    scenario : Scenario or str
        Model, prior, domain and methods (a preset name works).
    observations : array_like or pandas Series/DataFrame, shape (rows, m) or (rows,) when m = 1
        Continuous models: the increments Δy over each interval (N rows for N + 1 times), or
        the layout :func:`simulate` returns (N + 1 rows, row 0 zeros). Discrete models: the
        measurements z_k at every time, the first at the prior's time. **NaN is a missing
        value**: only the observed components of a row are used, and a row of NaN is a
        prediction only. A pandas object's index gives the times (unless ``times`` does),
        and :meth:`RunResult.to_pandas` keeps it.
    times : array_like, optional
        τ₀ … τ_N (τ₀ the prior's time), increasing, possibly irregular: every method predicts
        over each step whatever its length (grid and spectral methods as whole Δτ and a
        remainder). Every Δτ from 0 when absent. Datetimes are read **in a unit**, which Δτ
        and the model's rates are per (and :attr:`RunResult.time_unit` names): a pandas
        ``PeriodIndex``, or a ``DatetimeIndex`` with a frequency (set, or inferred from
        regular dates), in steps of that frequency (a yearly index steps by 1, a daily one
        by 1 per day); other datetimes need ``time_unit``. A step of more than 10⁴ Δτ is
        refused as a mis-set Δτ or unit.
    truth : array_like, shape (N + 1, n), optional
        The true states, for errors (MSE) against them.
    seed : int, optional
        Seeds the methods' random numbers (particle filter); the scenario's seed when absent.
    inputs : array_like or pandas DataFrame, shape (rows, k), optional
        The known inputs u1…uk of a driven model (one whose expressions read them or the
        time t): one row per time, row k held over (τ_{k−1}, τ_k] (for increments one row
        per interval also works). Required when the model reads inputs; methods that need a
        time-invariant model say so in their failure.
    time_unit : str, optional
        The unit of datetime times: ``"s"``, ``"min"``, ``"h"``, ``"D"``, ``"W"`` (time since
        the first divided by it) or ``"M"``, ``"Q"``, ``"Y"`` (whole calendar periods since
        the first: a month is one step whatever its length). Needed for datetimes without a
        frequency; overrides an index's frequency.
    checks : bool
        Record each observation's one-step predictive checks — its PIT and standardised
        error under the law each method predicted for it, and for discrete measurements the
        innovation (:attr:`MethodResult.pit`, :attr:`MethodResult.standardized_innovations`,
        :attr:`MethodResult.innovations`) — for :meth:`MethodResult.diagnostics`. Each step
        then costs a second prediction (on a copy of the filter).
    density_grid : array_like, optional
        Points at which to keep each method's marginal density of state component
        ``density_dim`` after every observation (:attr:`MethodResult.densities`, drawn as a
        heat strip by :meth:`MethodResult.plot`): a grid or spectral filter's own density,
        the particle filter's kernel estimate, the Gaussian of the others.
    density_dim : int
        The component of ``density_grid`` (0-based).

    Examples
    --------
    >>> import numpy as np, zakai
    >>> model = zakai.Model.discrete("0", "x", noise_cov=0.3, diffusion=0.5)
    >>> sc = zakai.Scenario(model, zakai.Prior.gaussian(0.0, 4.0), ["kalman"], dt_obs=1.0)
    >>> r = zakai.filter(sc, np.array([1.2, 0.7, 1.9, np.nan, 2.4]), checks=True)
    >>> r.methods["KF"].pit.shape, bool(np.isnan(r.methods["KF"].pit[3, 0]))
    ((5, 1), True)
    """
    grid = None
    if density_grid is not None:
        points = np.asarray(density_grid, dtype=float).ravel()
        grid = (int(density_dim), points.tolist())
    result = _recorded(
        scenario, observations, times, truth, seed, smooth=False, inputs=inputs,
        time_unit=time_unit, checks=checks, marginals=grid,
    )
    if grid is not None:
        for m in result.methods.values():
            m.density_grid, m.density_dim = np.asarray(grid[1]), grid[0]
    return result



def _inputs(inputs: Optional[ArrayLike]) -> Optional[np.ndarray]:
    """Known inputs as a (rows, k) array (a 1-D array or Series is one input)."""
    if inputs is None:
        return None
    a = _table(inputs, "inputs")
    return a.reshape(-1, 1) if a.ndim == 1 else a



def _recorded(
    scenario: Union[Scenario, str],
    observations: ArrayLike,
    times: Optional[ArrayLike],
    truth: Optional[ArrayLike],
    seed: Optional[int],
    smooth: bool,
    inputs: Optional[ArrayLike] = None,
    time_unit: Optional[str] = None,
    checks: bool = False,
    marginals: Optional[tuple[int, list[float]]] = None,
) -> RunResult:
    """:func:`filter`, or with ``smooth`` :func:`smooth`."""
    sc = _scenario(scenario)
    t, unit, index = _recording_times(observations, times, time_unit)
    obs = _table(observations, "observations")
    text, box = sc._text_for(obs, t)
    result = RunResult._from_dict(
        _zakai.filter_recorded(
            text,
            obs,
            t,
            _array(truth, "truth"),
            _seed(sc, seed),
            smooth,
            _inputs(inputs),
            bool(checks),
            marginals,
        )
    )
    result.time_unit = unit
    if box is not None:
        result.chosen_defaults.insert(0, box)
    if index is not None and len(index) == len(result.times):
        result.index = index
    return _warn_failures(result, 4)


def smooth(
    scenario: Union[Scenario, str],
    observations: ArrayLike,
    times: Optional[ArrayLike] = None,
    truth: Optional[ArrayLike] = None,
    seed: Optional[int] = None,
    *,
    inputs: Optional[ArrayLike] = None,
    time_unit: Optional[str] = None,
) -> RunResult:
    """Every method of the scenario as its fixed-interval smoother on your observations.

    A filter's estimate at τ_k uses the observations up to τ_k; a smoother's uses all of
    them, before and after — the best estimate of the past, and what bridges a gap from both
    sides. The run is :func:`filter`'s (same arguments, same filtered estimates), and each
    :class:`MethodResult` carries ``smoothed`` (:class:`Smoothed`): the smoothed means and
    covariances at every row, or why there are none.

    Smoothers: the Rauch–Tung–Striebel recursion for the Kalman–Bucy filter (exact on
    linear-Gaussian models) and its extended (EKF, IEKF, IOKF) and unscented (UKF) forms;
    the forward–backward recursion on the grid of the separation and implicit-FDM filters
    (the smoothed density of the discrete model the filter solves); forward filtering,
    backward simulation for the particle filter (``trajectories`` of its parameters, error
    ~ 1/√M). The other methods run their filter and say why they have no smoother
    (``zakai.methods()`` lists each method's ``smoother``).

    Parameters are those of :func:`filter`.

    Examples
    --------
    >>> import numpy as np, zakai
    >>> model = zakai.Model.discrete("0", "x", noise_cov=0.3, diffusion=0.5)
    >>> sc = zakai.Scenario(model, zakai.Prior.gaussian(0.0, 4.0), ["kalman"],
    ...                     dt_obs=1.0, domain=[(-10, 14)])
    >>> z = np.array([1.2, 0.7, 1.9, np.nan, np.nan, 2.4, 2.0])
    >>> r = zakai.smooth(sc, z)
    >>> s = r.methods["KF"].smoothed
    >>> bool(s.sds[3, 0] < r.methods["KF"].sds[3, 0])  # the gap is bridged from both sides
    True
    """
    return _recorded(
        scenario, observations, times, truth, seed, smooth=True, inputs=inputs, time_unit=time_unit
    )


def _check_executor(executor: Any) -> None:
    """A ConfigError unless ``executor`` can take tasks (``.submit``)."""
    if not hasattr(executor, "submit"):
        raise ConfigError(
            f"executor: a concurrent.futures.Executor (with .submit), not {type(executor).__name__}"
        )



def _run_task(args: tuple) -> str:
    """One realisation, as an executor's worker runs it (module level: pickled by reference)."""
    return _zakai.run_json(*args)



def monte_carlo(
    scenario: Union[Scenario, str],
    runs: int,
    seed: Optional[int] = None,
    *,
    executor: Any = None,
    progress: Optional[Callable[[int, int], Any]] = None,
) -> MonteCarloTable:
    """``runs`` runs with seeds ``seed, seed + 1, …`` on every core (the GIL released), or
    one task per run on ``executor`` — any ``concurrent.futures.Executor``, e.g. a Dask
    cluster's ``client.get_executor()`` (its workers need ``zakai`` installed); each run comes
    back bit for bit, so the table is the same as on this machine (times apart).

    ``progress(done, runs)``, when given, is called after each run (a notebook's progress
    bar, say): on every core, from the thread that ran it, beside other Python threads, and an
    exception it raises is raised once the runs are over; with an ``executor``, on the calling
    thread as each result comes back, and an exception stops the wait there.

    Returns the papers' table; ``.to_pandas()`` gives it as a DataFrame.
    """
    sc = _scenario(scenario)
    if not isinstance(runs, (int, np.integer)) or runs < 1:
        raise ConfigError(f"runs: must be a positive integer (got {runs!r})")
    first = _seed(sc, seed)
    if progress is not None and not callable(progress):
        raise ConfigError(f"progress: must be callable as progress(done, runs) (got {progress!r})")
    if executor is None:
        text = _zakai.monte_carlo_json(sc._text(), int(runs), first, progress)
        return MonteCarloTable(_json.loads(text))
    _check_executor(executor)
    text = sc._text()
    futures = [executor.submit(_run_task, (text, first + i)) for i in range(int(runs))]
    results = []
    for done, f in enumerate(futures, start=1):
        results.append(f.result())
        if progress is not None:
            progress(done, int(runs))
    return MonteCarloTable(_json.loads(_zakai.monte_carlo_from_runs(text, results, first)))
