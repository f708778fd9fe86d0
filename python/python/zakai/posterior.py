"""Posterior distributions of a scenario's parameters given your observations:
:func:`sample` draws from p(θ | data) ∝ L(θ) p(θ) by Markov chain Monte Carlo and returns a
:class:`Posterior`.

The priors are the scenario's (``"prior"`` in a parameter: ``("lognormal", 7.0, 1.0)``,
``{"kind": "gamma", "shape": 2, "rate": 1}``, …), uniform on the bounds where none is given
(both bounds must then be finite). The likelihood is the method's, as for :func:`zakai.fit`:
adaptive random-walk Metropolis (Haario, Saksman & Tamminen 2001) on a deterministic one —
exact for the Kalman filters on a linear-Gaussian model, converging to the exact one for
the grid and spectral filters on a nonlinear model — and particle marginal
Metropolis–Hastings (Andrieu, Doucet & Holenstein 2010) on the particle filter's unbiased
estimate. The chains start around the maximum-likelihood estimate and report rank-normalised
split-R̂ and bulk/tail effective sample sizes (Vehtari et al. 2021).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any, Optional, Sequence, Union

import numpy as np

from . import _zakai
from ._convert import ArrayLike
from .fitting import _evaluator, _method_index, _observations
from .runs import _inputs, _scenario, _seed
from .scenario import Scenario


@dataclass(slots=True)
class Posterior:
    """Draws from the posterior of some parameters and what to make of them.

    Attributes
    ----------
    method : str
        The method whose likelihood was used.
    sampler : str
        ``"adaptive random-walk Metropolis"`` or ``"particle marginal Metropolis–Hastings"``.
    names : list of str
        The parameters, in order.
    draws : pandas.DataFrame
        One row per kept draw: ``chain``, ``draw``, one column per parameter, ``lp``
        (ln L + ln p(θ)) and ``loglik`` (ln L, the estimate a PMMH chain carries).
    priors : dict
        Each parameter's prior as the scenario states it (``{"kind": "uniform"}`` where none
        was declared), with ``bounds``.
    acceptance : numpy.ndarray
        Each chain's acceptance rate after the warm-up.
    warmup : int
        Warm-up iterations per chain.
    evaluations : int
        Log-likelihood evaluations (filter runs), the starting fit's included.
    nobs : int
        Observations the likelihood is of.
    notes : list of str
        Where the chains started, and warnings: R̂ > 1.01, an effective sample size below
        400, a chain that hardly moved, common random numbers.
    """

    method: str
    sampler: str
    names: list[str]
    draws: Any
    priors: dict[str, dict[str, Any]]
    acceptance: np.ndarray
    warmup: int
    evaluations: int
    nobs: int
    notes: list[str] = field(default_factory=list)
    chosen_defaults: list[str] = field(default_factory=list)
    _summary: list[dict[str, Any]] = field(default_factory=list, repr=False)

    @property
    def chains(self) -> int:
        """The number of chains."""
        return len(self.acceptance)

    def values(self, name: str) -> np.ndarray:
        """Parameter ``name``'s draws, shape ``(chains, draws)``."""
        if name not in self.names:
            raise KeyError(f"no parameter {name!r}; the posterior is of {self.names}")
        return self.draws[name].to_numpy().reshape(self.chains, -1)

    def prior_density(self, name: str, x: ArrayLike) -> np.ndarray:
        """Parameter ``name``'s prior density at ``x``, restricted to its bounds and normalised
        on them (what :meth:`plot` draws over the histogram)."""
        prior = dict(self.priors[name])
        lo, hi = prior.pop("bounds")
        xs = np.asarray(x, dtype=float)
        values = _zakai.prior_density(json.dumps(prior), float(lo), float(hi), xs.ravel().tolist())
        return np.array(values).reshape(xs.shape)

    def summary(self) -> Any:
        """Each parameter's posterior mean, sd, 5 %, 50 % and 95 % quantiles, the Monte Carlo
        standard error of the mean (sd/√ESS_bulk), R̂ and the bulk and tail effective sample
        sizes — a DataFrame indexed by parameter."""
        import pandas as pd

        rows = []
        for s in self._summary:
            d = s["diagnostics"] or {}
            rows.append({
                "mean": s["mean"], "sd": s["sd"], "q5": s["q05"], "median": s["median"],
                "q95": s["q95"], "mcse": _number(s["mcse"]), "r_hat": _number(d.get("rhat")),
                "ess_bulk": _number(d.get("ess_bulk")), "ess_tail": _number(d.get("ess_tail")),
            })
        return pd.DataFrame(rows, index=pd.Index([s["name"] for s in self._summary], name="parameter"))

    def to_arviz(self) -> Any:
        """The draws as an ArviZ ``InferenceData`` (``posterior`` with one variable per
        parameter, ``sample_stats`` with ``lp`` and ``loglik``, the total ln L of each draw), for ArviZ's plots and
        diagnostics. ArviZ is optional: ``pip install arviz``."""
        try:
            import arviz as az
        except ImportError as e:
            raise ImportError("Posterior.to_arviz needs ArviZ: pip install arviz") from e
        shape = (self.chains, -1)
        return az.from_dict(
            posterior={n: self.values(n) for n in self.names},
            sample_stats={
                "lp": self.draws["lp"].to_numpy().reshape(shape),
                "loglik": self.draws["loglik"].to_numpy().reshape(shape),
            },
        )

    def plot(self) -> Any:
        """Each parameter's traces (one line per chain) and marginal histogram with its prior
        density drawn over it (matplotlib); the Figure."""
        from . import plotting

        return plotting.posterior(self)

    def __repr__(self) -> str:
        s = self.summary()
        lines = [f"Posterior({self.method}, {self.sampler}, {self.chains} chains × "
                 f"{len(self.draws) // max(self.chains, 1)} draws, {self.nobs} observations)"]
        for n, row in s.iterrows():
            lines.append(f"  {n:<12} {row['mean']:>14.6g} ± {row['sd']:.4g}  "
                         f"[{row['q5']:.4g}, {row['q95']:.4g}]  R̂ {row['r_hat']:.3f}  "
                         f"ESS {row['ess_bulk']:.0f}")
        lines.extend(f"  note: {n}" for n in self.notes)
        return "\n".join(lines)

    def _repr_html_(self) -> str:
        import html

        s = self.summary()
        rows = "".join(
            f"<tr><td>{html.escape(str(n))}</td><td>{r['mean']:.6g}</td><td>{r['sd']:.4g}</td>"
            f"<td>[{r['q5']:.4g}, {r['q95']:.4g}]</td><td>{r['r_hat']:.3f}</td>"
            f"<td>{r['ess_bulk']:.0f}</td><td>{r['ess_tail']:.0f}</td></tr>"
            for n, r in s.iterrows()
        )
        notes = "".join(f"<li>{html.escape(n)}</li>" for n in self.notes)
        return (
            f"<b>Posterior</b> — {html.escape(self.method)}, {html.escape(self.sampler)}, "
            f"{self.chains} chains, {self.nobs} observations"
            "<table><tr><th>parameter</th><th>mean</th><th>sd</th><th>90 % interval</th>"
            f"<th>R̂</th><th>ESS bulk</th><th>ESS tail</th></tr>{rows}</table>"
            + (f"<ul>{notes}</ul>" if notes else "")
        )


def _number(v: Optional[float]) -> float:
    """A JSON number, NaN for null."""
    return float("nan") if v is None else float(v)


def sample(
    scenario: Union[Scenario, str],
    observations: ArrayLike,
    method: Union[str, int, None] = None,
    params: Optional[Sequence[str]] = None,
    *,
    draws: int = 1000,
    warmup: int = 1000,
    chains: int = 4,
    sampler: str = "auto",
    common_random_numbers: bool = False,
    correlation: Optional[float] = None,
    start_from_fit: bool = True,
    surrogate: Union[str, int, None] = None,
    times: Optional[ArrayLike] = None,
    time_unit: Optional[str] = None,
    seed: Optional[int] = None,
    executor: Any = None,
    inputs: Optional[ArrayLike] = None,
) -> Posterior:
    """Draws from the posterior of the scenario's parameters given your observations.

    Parameters
    ----------
    scenario : Scenario
        With ``parameters``, each with a ``prior`` or finite bounds (a uniform prior on them).
    observations : array_like or pandas Series/DataFrame
        As for :func:`zakai.filter` (NaN a missing value, a pandas index as the times).
    method : str or int, optional
        The method whose likelihood is used, as for :func:`zakai.fit`.
    params : list of str, optional
        The parameters to sample; all the scenario declares when absent.
    draws, warmup, chains : int, optional
        Draws kept per chain, warm-up iterations per chain (the proposal adapts; discarded),
        and the number of chains (1000, 1000, 4).
    sampler : {"auto", "metropolis", "pmmh", "langevin"}, optional
        ``"auto"``: particle marginal Metropolis–Hastings for the particle filter, adaptive
        random-walk Metropolis otherwise; ``"langevin"``: Metropolis-adjusted Langevin steps
        on the method's score (the Kalman, point-mass, separation and implicit FDM filters),
        which mix faster per draw.
    common_random_numbers : bool, optional
        PMMH with the same random numbers at every proposal: a smooth but biased likelihood
        (the notes say so). Fresh numbers by default — the exact posterior.
    correlation : float, optional
        Correlated pseudo-marginal steps (Deligiannidis, Doucet & Pitt 2018) for the particle
        filter: its random numbers U move with each proposal by ``U' = ρU + √(1 − ρ²)ε`` with
        this ρ in [0, 1) (e.g. 0.99), so that successive estimates share most of their noise
        and far fewer particles keep the chain moving — still the exact posterior. In this
        process only (not with an ``executor``).
    start_from_fit : bool, optional
        Start the chains around the maximum-likelihood estimate (default), or around the
        scenario's values.
    surrogate : str or int, optional
        Delayed acceptance (Christen & Fox 2005): a cheaper method of the scenario (a key,
        added with its defaults if absent, or an index — e.g. a coarser grid added to the
        scenario's methods) whose likelihood screens each proposal before ``method`` runs on
        it; the draws stay exact for ``method``. Random-walk proposals on a method without
        random numbers; run in this process even with an ``executor``.
    times, time_unit, seed, executor, inputs
        As for :func:`zakai.fit`; with an ``executor`` each iteration's proposals (one per
        chain) go to its workers.

    Returns
    -------
    Posterior

    Raises
    ------
    ConfigError
        A parameter with neither a prior nor finite bounds, out-of-range options — before
        any run.

    Examples
    --------
    >>> import numpy as np, zakai
    >>> model = zakai.Model.discrete("0", "x", noise_cov="r", diffusion="sqrt(q)")
    >>> sc = zakai.Scenario(model, zakai.Prior.gaussian(0.0, 10.0), ["kalman"], dt_obs=1.0,
    ...     parameters={"q": (1.0, (0, 10)), "r": (1.0, (0, None), ("lognormal", 0.0, 1.0))})
    >>> rng = np.random.default_rng(1)
    >>> z = np.cumsum(rng.normal(size=60)) + rng.normal(size=60)
    >>> post = zakai.sample(sc, z, draws=400, warmup=400, seed=2)
    >>> list(post.summary().columns)
    ['mean', 'sd', 'q5', 'median', 'q95', 'mcse', 'r_hat', 'ess_bulk', 'ess_tail']
    """
    import pandas as pd

    for name, v in (("draws", draws), ("warmup", warmup), ("chains", chains)):
        if not isinstance(v, (int, np.integer)) or isinstance(v, bool) or v < 0:
            from .errors import ConfigError

            raise ConfigError(f"{name}: a nonnegative integer, not {v!r}")
    sc, index = _method_index(_scenario(scenario), method)
    screen = None
    if surrogate is not None:
        sc, screen = _method_index(sc, surrogate)
    obs, t, _unit = _observations(observations, times, time_unit)
    s = _seed(sc, seed)
    text, box = sc._text_for(obs, t)
    u = _inputs(inputs)
    out = json.loads(_zakai.sample(
        text, obs, t, index, list(params or []), s, int(draws), int(warmup), int(chains),
        sampler, bool(common_random_numbers), bool(start_from_fit),
        _evaluator(executor, text, obs, t, s, u), u, screen,
        None if correlation is None else float(correlation),
    ))
    p = out["posterior"]
    names = p["names"]
    frames = []
    for c, chain in enumerate(p["chains"]):
        theta = np.array(chain["theta"], dtype=float).reshape(-1, len(names))
        ll = np.array(chain["log_likelihood"], dtype=float)
        frame = pd.DataFrame(theta, columns=names)
        frame.insert(0, "draw", np.arange(len(ll)))
        frame.insert(0, "chain", c)
        frame["lp"] = ll + np.array(chain["log_prior"], dtype=float)
        frame["loglik"] = ll
        frames.append(frame)
    priors = {}
    for n, prior, bounds in zip(names, p["priors"], p["bounds"]):
        lo, hi = bounds
        priors[n] = dict(prior, bounds=(-np.inf if lo is None else lo, np.inf if hi is None else hi))
    return Posterior(
        method=p["method"],
        sampler=p["sampler"],
        names=names,
        draws=pd.concat(frames, ignore_index=True),
        priors=priors,
        acceptance=np.array([c["acceptance"] for c in p["chains"]]),
        warmup=p["warmup"],
        evaluations=p["evaluations"],
        nobs=p["observations"],
        notes=list(p["notes"]),
        chosen_defaults=([box] if box else []) + list(out["chosen_defaults"]),
        _summary=out["summary"],
    )
