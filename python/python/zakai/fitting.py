"""Fitting a scenario's parameters to your data: :func:`fit` (maximum likelihood with
standard errors), :func:`profile` (the log-likelihood along one parameter for every method)
and :func:`log_likelihood` (one evaluation).

The likelihood of the data is the method's own (see :attr:`MethodResult.log_likelihood`):
exact for the Kalman filters on linear-Gaussian models, converging with the grid for the grid
and spectral filters, an unbiased estimate (of L, not ln L) for the particle filter, and a
Gaussian approximation for the EKF, UKF, IEKF, IOKF and the direct method — whose maxima can
sit at the wrong parameter values, which :func:`profile` shows side by side.

Evaluations run on every core of this machine (the GIL released). Pass a
``concurrent.futures.Executor`` — a ``ProcessPoolExecutor``, or a Dask cluster's
``client.get_executor()`` — and the batches (a profile's values, the first simplex, the
information's finite-difference stencil) are spread over it instead, one task per
likelihood evaluation; the workers need ``zakai`` installed.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Any, Callable, Optional, Sequence, Union

import numpy as np

from . import _zakai
from ._convert import ArrayLike, _aligned, _array, _recording_times, _table
from .errors import ConfigError, FilterWarning
from .runs import _check_executor, _inputs, _scenario, _seed
from .scenario import Scenario



def _observations(
    observations: Any, times: Optional[ArrayLike], time_unit: Optional[str] = None
) -> tuple[np.ndarray, Optional[np.ndarray], Optional[str]]:
    """The observations as an array, their times (given, or a pandas index's) and the
    times' unit (see :func:`zakai.filter`)."""
    t, unit, _ = _recording_times(observations, times, time_unit)
    obs = _table(observations, "observations")
    return obs, t, unit



def _method_index(sc: Scenario, method: Union[str, int, None]) -> tuple[Scenario, int]:
    """The scenario and the index of ``method`` in it: a key (added with its defaults when the
    scenario lacks it), an index, or the first method when ``None``."""
    methods = sc.config["methods"]
    if method is None:
        return sc, 0
    if isinstance(method, (int, np.integer)) and not isinstance(method, bool):
        if not 0 <= method < len(methods):
            raise ConfigError(f"method: index {method} asked for, the scenario has {len(methods)} methods")
        return sc, int(method)
    if isinstance(method, str):
        for i, m in enumerate(methods):
            if m.get("method") == method:
                return sc, i
        extended = sc.copy()
        extended.methods = list(methods) + [method]
        return extended, len(methods)
    raise ConfigError(f"method: a method key such as 'ukf' or an index, not {method!r}")



def _task(args: tuple) -> float:
    """One likelihood evaluation, as an executor's worker runs it (module level, so that it
    pickles by reference)."""
    return _zakai.log_likelihood(*_aligned(args))



def _evaluator(
    executor: Any,
    text: str,
    obs: np.ndarray,
    times: Optional[np.ndarray],
    seed: int,
    inputs: Optional[np.ndarray] = None,
) -> Optional[Callable[[int, list[str], list[list[float]]], list[float]]]:
    """The batch evaluator the core calls, one executor task per point; ``None`` without an
    executor (the core then runs the batch on every core itself)."""
    if executor is None:
        return None
    _check_executor(executor)

    def evaluate(
        method: int,
        names: list[str],
        points: list[list[float]],
        seeds: Optional[list[int]] = None,
    ) -> list[float]:
        # A seed per point when the sampler asks for fresh random numbers (PMMH).
        each = seeds if seeds is not None else [seed] * len(points)
        futures = [
            executor.submit(_task, (text, obs, times, method, names, s, list(p), inputs))
            for p, s in zip(points, each)
        ]
        return [float(f.result()) for f in futures]

    return evaluate



@dataclass(slots=True)
class FitResult:
    """A maximum-likelihood fit.

    Attributes
    ----------
    method : str
        The method whose likelihood was maximised.
    params : dict
        The estimate θ̂, by parameter name.
    stderr : dict
        Standard errors from the observed information −∇² ln L(θ̂) (central differences);
        NaN where there are none (see ``notes``).
    loglik : float
        ln L(θ̂).
    nfev : int
        Likelihood evaluations (filter runs), the information's included.
    njev : int
        Scores — ln L with its gradient, one forward and one backward pass — taken by
        L-BFGS (0 with Nelder–Mead).
    nit : int
        Iterations of the optimiser.
    converged : bool
        Whether the optimiser met its tolerance.
    optimiser : str
        ``"L-BFGS"`` (argmin's, on the method's score: the Kalman, point-mass, separation and
        implicit FDM filters) or
        ``"Nelder–Mead"`` (argmin's simplex: every other method).
    cov : ndarray, shape (p, p), or None
        The estimate's asymptotic covariance (the information's inverse).
    start : dict
        The starting values (the scenario's).
    bounds : dict
        ``(lower, upper)`` per parameter, ``None`` an open side.
    nobs : int
        Observations the likelihood is of.
    notes : list of str
        What to know: no convergence, an estimate on a bound, why there are no standard
        errors.
    chosen_defaults : list of str
        Sizes chosen from the problem at the starting values and held at every point.
    intervals : dict
        95 % Wald intervals ``(lower, upper)`` per parameter, computed on the scale the fit
        moves on (``ln(θ − lo)`` for a lower bound, the logit for an interval) and mapped
        back, so they stay inside the bounds; θ̂ ± 1.96·se for an unbounded parameter; NaN
        without a standard error.
    time_unit : str or None
        The unit datetime times were read in (rates per that unit); ``None`` for numbers.
    """

    method: str
    params: dict[str, float]
    stderr: dict[str, float]
    loglik: float
    nfev: int
    nit: int
    converged: bool
    cov: Optional[np.ndarray]
    start: dict[str, float]
    bounds: dict[str, tuple[Optional[float], Optional[float]]]
    nobs: int
    notes: list[str] = field(default_factory=list)
    chosen_defaults: list[str] = field(default_factory=list)
    intervals: dict[str, tuple[float, float]] = field(default_factory=dict)
    time_unit: Optional[str] = None
    njev: int = 0
    optimiser: str = "Nelder–Mead"
    # What the fit was of — (one-method scenario, observations, times, time_unit, seed,
    # inputs) — for profile_interval; None for a FitResult made by hand.
    _source: Any = field(default=None, repr=False, compare=False)

    def plot(self, names: Optional[Sequence[str]] = None, points: int = 21, level: float = 0.95) -> Any:
        """Each fitted parameter's (or those of ``names``) profile log-likelihood around θ̂,
        with θ̂, the Wald interval shaded and the likelihood-ratio level dotted (matplotlib);
        the Figure. Each profile refits the other parameters at ``points`` values."""
        from . import plotting

        return plotting.fit(self, names, points, level)

    def profile_interval(self, name: str, level: float = 0.95, points: int = 15) -> tuple[float, float]:
        """The likelihood-ratio interval of parameter ``name``: the values θ where the profile
        log-likelihood (ln L maximised over the other fitted parameters) is within
        ``½ χ²₁(level)`` of its maximum ln L(θ̂) (Wilks 1938) — unlike the Wald interval
        (:attr:`intervals`) it follows the likelihood's shape. Found by :func:`profile` on
        ``points`` values each side of θ̂, widened until the level is crossed (to the bound,
        which is then the end, when it is not; ±inf when an unbounded side is not crossed
        within 2⁶ times its first reach), and linear interpolation between the two values
        around each crossing.

        Examples
        --------
        >>> import numpy as np, zakai
        >>> model = zakai.Model.discrete("0", "x", noise_cov="r", diffusion=0.5)
        >>> sc = zakai.Scenario(model, zakai.Prior.gaussian(0.0, 4.0), ["kalman"], dt_obs=1.0,
        ...                     parameters={"r": (0.3, (0, None))})
        >>> z = np.sin(np.arange(40) / 3.0) + 0.5 * np.cos(np.arange(40) * 1.7)
        >>> fit = zakai.fit(sc, z, "kalman")
        >>> lo, hi = fit.profile_interval("r")
        >>> bool(lo < fit.params["r"] < hi)
        True
        """
        from statistics import NormalDist

        if self._source is None:
            raise ConfigError("profile_interval: this FitResult does not come from zakai.fit")
        if name not in self.params:
            raise ConfigError(f"profile_interval: {name!r} was not fitted ({list(self.params)})")
        if not 0.0 < level < 1.0:
            raise ConfigError(f"level: must be strictly between 0 and 1 (got {level})")
        sc, obs, times, time_unit, seed, inputs = self._source
        at_fit = sc.copy()
        declared = at_fit.parameters
        at_fit.parameters = {
            n: ((self.params[n] if n in self.params else spec["value"]),
                tuple(spec.get("bounds", (None, None))))
            for n, spec in declared.items()
        }
        others = [n for n in self.params if n != name]
        theta = self.params[name]
        lower, upper = self.bounds[name]
        drop = 0.5 * NormalDist().inv_cdf(0.5 + level / 2) ** 2
        target = self.loglik - drop
        wald = self.intervals.get(name, (float("nan"), float("nan")))
        spread = abs(theta) * 0.5 or 1.0
        if np.isfinite(self.stderr.get(name, np.nan)) and self.stderr[name] > 0:
            spread = 2.0 * self.stderr[name]

        def end(sign: int) -> float:
            reach = spread if not np.isfinite(wald[(sign + 1) // 2]) else max(
                spread, 1.5 * abs(wald[(sign + 1) // 2] - theta))
            bound = upper if sign > 0 else lower
            for _ in range(6):
                far = theta + sign * reach
                if bound is not None and (far - bound) * sign >= 0:
                    # Up to the bound (short of it by a hundredth of the way there).
                    far = bound - sign * 0.01 * abs(bound - theta)
                values = np.linspace(theta, far, points + 1)[1:]
                ll = profile(at_fit, obs, name, values=values, refit=others or None,
                             times=times, time_unit=time_unit, seed=seed, inputs=inputs)
                curve = np.concatenate([[self.loglik], next(iter(ll.loglik.values()))])
                xs = np.concatenate([[theta], values])
                # A value where the method failed (−inf, NaN) counts as below the level.
                below = np.flatnonzero(~(curve >= target))
                if below.size:
                    k = int(below[0])
                    x0, x1, y0, y1 = xs[k - 1], xs[k], curve[k - 1], curve[k]
                    if not np.isfinite(y1):
                        return float(x1)
                    return float(x0 + (target - y0) * (x1 - x0) / (y1 - y0))
                if bound is not None and (far - bound) * sign >= -0.011 * abs(bound - theta):
                    return float(bound)
                reach *= 2.0
            return float("inf") * sign

        return (end(-1), end(+1))

    @property
    def aic(self) -> float:
        """Akaike's information criterion, ``2p − 2 ln L(θ̂)`` (p the parameters fitted).

        >>> import math
        >>> r = FitResult("KF", {"q": 1.0}, {"q": 0.1}, -10.0, 5, 2, True, None, {"q": 1.0},
        ...               {"q": (0.0, None)}, 100)
        >>> r.aic
        22.0
        """
        return 2.0 * len(self.params) - 2.0 * self.loglik

    @property
    def bic(self) -> float:
        """The Bayesian (Schwarz) information criterion, ``p ln n − 2 ln L(θ̂)``, n the
        number of observations (``nobs``)."""
        return len(self.params) * float(np.log(self.nobs)) - 2.0 * self.loglik

    def to_pandas(self) -> Any:
        """The estimates as a DataFrame indexed by parameter: ``estimate``, ``stderr``, the
        95 % Wald interval ``ci_lower``/``ci_upper`` (see :attr:`intervals`: inside the
        bounds), ``start``, ``lower``, ``upper``."""
        import pandas as pd

        names = list(self.params)
        est = np.array([self.params[n] for n in names])
        se = np.array([self.stderr[n] for n in names])
        return pd.DataFrame(
            {
                "estimate": est,
                "stderr": se,
                "ci_lower": [self.intervals[n][0] for n in names],
                "ci_upper": [self.intervals[n][1] for n in names],
                "start": [self.start[n] for n in names],
                "lower": [self.bounds[n][0] for n in names],
                "upper": [self.bounds[n][1] for n in names],
            },
            index=pd.Index(names, name="parameter"),
        )

    def __repr__(self) -> str:
        est = ", ".join(f"{n}={self.params[n]:.4g}±{self.stderr[n]:.2g}" for n in self.params)
        return f"FitResult({self.method}: {est}; ln L = {self.loglik:.6g}, n = {self.nobs})"

    def _repr_html_(self) -> str:
        import html

        rows = "".join(
            f"<tr><td>{html.escape(n)}</td><td>{self.params[n]:.6g}</td><td>{self.stderr[n]:.4g}</td>"
            f"<td>[{self.intervals.get(n, (float('nan'),) * 2)[0]:.4g}, "
            f"{self.intervals.get(n, (float('nan'),) * 2)[1]:.4g}]</td></tr>"
            for n in self.params
        )
        notes = "".join(f"<li>{html.escape(n)}</li>" for n in self.notes)
        return (
            f"<b>Maximum-likelihood fit</b> — {html.escape(self.method)}, {self.nobs} observations"
            "<table><tr><th>parameter</th><th>estimate</th><th>stderr</th><th>95 % interval</th></tr>"
            f"{rows}</table>ln L = {self.loglik:.6f}, AIC = {self.aic:.4f}, BIC = {self.bic:.4f}; "
            f"{html.escape(self.optimiser)}, {self.nit} iterations"
            + (", converged" if self.converged else ", <b>not converged</b>")
            + (f"<ul>{notes}</ul>" if notes else "")
        )

    def __str__(self) -> str:
        lines = [f"Maximum-likelihood fit — {self.method}, {self.nobs} observations"]
        for n in self.params:
            lines.append(f"  {n:<12} {self.params[n]:>14.6g} ± {self.stderr[n]:.4g}")
        scores = f"{self.njev} scores and " if self.njev else ""
        lines.append(f"  ln L = {self.loglik:.6f}; {self.optimiser}: {self.nit} iterations, "
                     f"{scores}{self.nfev} evaluations" + (", converged" if self.converged else ""))
        lines.append(f"  AIC = {self.aic:.4f}, BIC = {self.bic:.4f}")
        lines.extend(f"  note: {n}" for n in self.notes)
        return "\n".join(lines)



def fit(
    scenario: Union[Scenario, str],
    observations: ArrayLike,
    method: Union[str, int, None] = None,
    params: Optional[Sequence[str]] = None,
    *,
    times: Optional[ArrayLike] = None,
    time_unit: Optional[str] = None,
    seed: Optional[int] = None,
    executor: Any = None,
    inputs: Optional[ArrayLike] = None,
    optimiser: str = "auto",
) -> FitResult:
    """Maximum-likelihood estimate of the scenario's parameters from your observations.

    Parameters
    ----------
    scenario : Scenario
        With ``parameters`` (their values are the starting point, their bounds the search
        box) used in its expressions or coefficients.
    observations : array_like or pandas Series/DataFrame
        As for :func:`zakai.filter` (NaN a missing value, a pandas index as the times).
    method : str or int, optional
        The method whose likelihood is maximised: a key (``"kalman"``, ``"separation"``, …;
        added with its defaults if the scenario lacks it) or an index; the first method when
        absent.
    params : list of str, optional
        The parameters to fit; all the scenario declares when absent (the others keep their
        values).
    times : array_like, optional
        τ₀ … τ_N, as for :func:`zakai.filter`.
    time_unit : str, optional
        The unit of datetime times, as for :func:`zakai.filter`.
    seed : int, optional
        The method's random numbers (the same at every point); the scenario's when absent.
    executor : concurrent.futures.Executor, optional
        Spreads the batches of evaluations over its workers (e.g. a Dask cluster's
        ``client.get_executor()``); every core of this machine when absent.
    inputs : array_like, shape (rows, k), optional
        The known inputs of a driven model, as for :func:`zakai.filter`.
    optimiser : {"auto", "nelder-mead", "lbfgs"}, optional
        ``"auto"`` (default): L-BFGS on the method's score — its log-likelihood's gradient
        from one forward and one backward pass — where the method gives one (the Kalman,
        point-mass, separation and implicit FDM filters), else Nelder–Mead; ``"lbfgs"`` raises ``ValueError`` for a method without
        a score.

    Returns
    -------
    FitResult
    """
    sc, index = _method_index(_scenario(scenario), method)
    obs, t, unit = _observations(observations, times, time_unit)
    s = _seed(sc, seed)
    text, box = sc._text_for(obs, t)
    u = _inputs(inputs)
    d = _zakai.fit(
        text, obs, t, index, list(params or []), s, _evaluator(executor, text, obs, t, s, u), u,
        optimiser,
    )
    names = d["names"]
    cov = d["covariance"]
    return FitResult(
        method=d["method"],
        params=dict(zip(names, d["estimate"])),
        stderr=dict(zip(names, d["stderr"])),
        loglik=d["log_likelihood"],
        nfev=d["evaluations"],
        nit=d["iterations"],
        converged=d["converged"],
        cov=None if cov is None else np.array(cov).reshape(len(names), len(names)),
        start=dict(zip(names, d["start"])),
        bounds=dict(zip(names, [tuple(b) for b in d["bounds"]])),
        nobs=d["observations"],
        notes=list(d["notes"]),
        chosen_defaults=([box] if box else []) + list(d["chosen_defaults"]),
        intervals=dict(zip(names, [tuple(i) for i in d["intervals"]])),
        time_unit=unit,
        njev=d["scores"],
        optimiser=d["optimiser"],
        _source=(_single_method(sc, index), obs, t, None, s, u),
    )


def _single_method(sc: Scenario, index: int) -> Scenario:
    """The scenario with its method ``index`` only."""
    single = sc.copy()
    single.config["methods"] = [sc.config["methods"][index]]
    return single



@dataclass(slots=True)
class Profile:
    """The log-likelihood along one parameter for every method of a scenario: the profile
    log-likelihood max over ``refit`` of ln L at each value when :func:`profile` was given
    parameters to refit, else a slice with the others at their values (with one unknown, the
    log-likelihood itself).

    Attributes
    ----------
    parameter : str
    values : ndarray
        The parameter's values.
    loglik : dict of ndarray
        ln L at each value, by method name (``-inf`` where the method failed).
    maxima : dict
        ``(θ*, ln L(θ*))`` by method name — the best value refined by a parabola through its
        neighbours — or ``None`` where the method failed everywhere.
    notes : dict of list of str
        By method name, what the method says about its likelihood at its maximum: the
        guarantees of its chosen steps it reports as violated and its self-checks that warned,
        each with its advice (one more run at the maximum). Empty when it says nothing — a
        maximum with notes may not be trustworthy.
    """

    parameter: str
    values: np.ndarray
    loglik: dict[str, np.ndarray]
    maxima: dict[str, Optional[tuple[float, float]]]
    notes: dict[str, list[str]]

    def to_pandas(self) -> Any:
        """A DataFrame indexed by the parameter's values, a column of ln L per method."""
        import pandas as pd

        return pd.DataFrame(self.loglik, index=pd.Index(self.values, name=self.parameter))

    def plot(self, level: float = 0.95) -> Any:
        """ln L along the parameter for every method, its maximum marked and the
        likelihood-ratio level ``ln L(θ*) − ½ χ²₁(level)`` dotted (matplotlib); the Figure."""
        from . import plotting

        return plotting.profile(self, level)

    def __repr__(self) -> str:
        best = ", ".join(
            f"{m}: {self.parameter}* = {v[0]:.4g}" if v is not None else f"{m}: —"
            for m, v in self.maxima.items()
        )
        return (f"Profile({self.parameter}, {len(self.values)} values in "
                f"[{self.values[0]:.4g}, {self.values[-1]:.4g}]; {best})")

    def _repr_html_(self) -> str:
        import html

        rows = "".join(
            f"<tr><td>{html.escape(m)}</td><td>{'—' if v is None else f'{v[0]:.6g}'}</td>"
            f"<td>{'—' if v is None else f'{v[1]:.6g}'}</td>"
            f"<td>{html.escape('; '.join(self.notes.get(m, [])))}</td></tr>"
            for m, v in self.maxima.items()
        )
        return (f"<b>Profile</b> of ln L along {html.escape(self.parameter)}, {len(self.values)} values"
                f"<table><tr><th>method</th><th>{html.escape(self.parameter)}*</th><th>ln L</th>"
                f"<th>notes</th></tr>{rows}</table>")



def profile(
    scenario: Union[Scenario, str],
    observations: ArrayLike,
    param: str,
    values: Optional[ArrayLike] = None,
    *,
    points: int = 41,
    refit: Optional[Sequence[str]] = None,
    times: Optional[ArrayLike] = None,
    time_unit: Optional[str] = None,
    seed: Optional[int] = None,
    executor: Any = None,
    inputs: Optional[ArrayLike] = None,
) -> Profile:
    """The log-likelihood of your observations along ``param`` for every method of the
    scenario: with ``refit`` (names of other parameters) the profile log-likelihood, ln L
    maximised over them at each value (a Nelder–Mead fit per value, warm-started); without, a
    slice with the other parameters at their values.

    ``values`` default to ``points`` values spanning the parameter's bounds (less 1 % at each
    end), or a quarter to four times its distance from a one-sided bound, or its value ± 3 when
    unbounded. ``times``, ``time_unit``, ``seed``, ``executor`` and ``inputs`` are as for
    :func:`fit`.
    """
    sc = _scenario(scenario)
    obs, t, unit = _observations(observations, times, time_unit)
    s = _seed(sc, seed)
    v = None
    if values is not None:
        v = np.asarray(values, dtype=float).ravel()
        if v.size < 1 or not np.isfinite(v).all():
            raise ConfigError("values: must be finite numbers")
        v = v.tolist()
    if not isinstance(points, (int, np.integer)) or not 2 <= points <= 10_000:
        raise ConfigError(f"points: must be an integer in [2, 10000], got {points!r}")
    text, _ = sc._text_for(obs, t)
    u = _inputs(inputs)
    grid, rows = _zakai.profile(
        text, obs, t, str(param), v, int(points), s, [str(n) for n in (refit or [])],
        _evaluator(executor, text, obs, t, s, u),
        u,
    )
    return Profile(
        parameter=str(param),
        values=np.array(grid),
        loglik={r["method"]: np.array(r["log_likelihoods"]) for r in rows},
        maxima={r["method"]: r["maximum"] for r in rows},
        notes={r["method"]: list(r["notes"]) for r in rows},
    )



def log_likelihood(
    scenario: Union[Scenario, str],
    observations: ArrayLike,
    method: Union[str, int, None] = None,
    *,
    times: Optional[ArrayLike] = None,
    time_unit: Optional[str] = None,
    seed: Optional[int] = None,
    inputs: Optional[ArrayLike] = None,
    **values: float,
) -> float:
    """ln p(observations | θ) under one method, with parameters set by keyword
    (``log_likelihood(sc, z, "kalman", q=1400.0, r=15000.0)``; the others at their values).
    Without keywords, the likelihood of the scenario as it stands (it need not declare any
    parameter). ``-inf`` where the method fails on the data, with a
    :class:`zakai.FilterWarning` naming the method, the step and the reason. ``inputs``: a
    driven model's known inputs, and ``time_unit`` the unit of datetime times, as for
    :func:`zakai.filter`."""
    sc, index = _method_index(_scenario(scenario), method)
    obs, t, unit = _observations(observations, times, time_unit)
    names = list(values)
    text, _ = sc._text_for(obs, t)
    if not names:
        value, failure = _zakai.scenario_log_likelihood(
            text, obs, t, index, _seed(sc, seed), _inputs(inputs)
        )
        if failure is not None:
            warnings.warn(failure, FilterWarning, stacklevel=2)
        return float(value)
    return _zakai.log_likelihood(
        text,
        obs,
        t,
        index,
        names,
        _seed(sc, seed),
        [float(values[n]) for n in names],
        _inputs(inputs),
    )
