"""What runs return: :class:`RunResult` (every method's estimates, covariances, failures and
times, with pandas views), :class:`MethodResult` and :class:`MonteCarloTable`."""

from __future__ import annotations

import html
from dataclasses import dataclass, field
from typing import Any, Optional

import numpy as np

from . import _zakai
from .errors import ConfigError




@dataclass(slots=True)
class Smoothed:
    """One method's fixed-interval smoother over a run (:func:`zakai.smooth`): the best
    estimate of the state at every observation time from **all** the observations.

    Attributes
    ----------
    smoother : str or None
        ``"RTS"`` (Kalman–Bucy), ``"extended RTS"`` (EKF, IEKF, IOKF), ``"unscented RTS"``
        (UKF), ``"forward–backward"`` (the separation and implicit-FDM grid filters),
        ``"FFBSi"`` (particle filter); ``None`` when the method has none.
    estimates : ndarray, shape (N + 1, n)
        E[x(τ_k) | all observations]; NaN when there is no smoothed track.
    covariances : ndarray, shape (N + 1, n, n)
    failure : str or None
        Why there is no smoothed track (no smoother, the filter failed, the memory cap).
    notes : list of str
        What the smoother approximated or cost on this run.
    seconds : float
        Wall time of the backward pass.
    mse : float or None
        MSE of the smoothed means against the truth, when it is known.
    """

    smoother: Optional[str]
    estimates: np.ndarray
    covariances: np.ndarray
    failure: Optional[str]
    notes: list[str]
    seconds: float
    mse: Optional[float]

    @property
    def sds(self) -> np.ndarray:
        """Smoothed standard deviations (N + 1, n)."""
        return np.sqrt(np.clip(np.diagonal(self.covariances, axis1=1, axis2=2), 0.0, None))

    def __repr__(self) -> str:
        if self.failure is not None:
            return f"Smoothed(none: {_short(self.failure)})"
        mse = "" if self.mse is None else f", MSE {self.mse:.4g}"
        return f"Smoothed({self.smoother}, rows={len(self.estimates)}{mse})"


@dataclass(slots=True)
class MethodResult:
    """One method's record in a run.

    Attributes
    ----------
    name : str
        Display name, e.g. ``"PF(200)"``.
    estimates : ndarray, shape (N + 1, n)
        x̂(τ_k); rows after a failure are NaN.
    covariances : ndarray, shape (N + 1, n, n), or None
        P(τ_k) where the method has one.
    failure : (k, t, message) or None
        Where and why the method failed.
    concerns : list of dict
        Self-checks that crossed their thresholds (``check``, ``worst``, ``threshold``,
        ``first_t``, ``steps``, ``advice``, ``text``): warnings, not failures.
    mse : float or None
        Mean square error against the truth (Shi, Chen & Yau 2021, (43)), when the truth is
        known and the method finished.
    log_likelihood : float or None
        The log-likelihood of the data under the method: the sum of ``log_likelihoods``;
        ``None`` when the method failed. Exact for the Kalman and Gaussian-sum filters, from
        the density's normaliser for the grid and spectral filters, the log of the weights'
        mean for the particle filter, from the Gaussian predictive density (an approximation)
        for the EKF, UKF, IEKF, IOKF and the direct method. For continuous observations it is
        the likelihood ratio against Wiener measure (the Kallianpur–Striebel normaliser).
    log_likelihoods : ndarray, shape (N + 1,)
        ln p(y_k | y_1:k−1) of each row's observation (0 where nothing was observed; NaN after
        a failure).
    seconds_per_step, build_seconds : float
        Wall time per step and to build the filter (its off-line part).
    smoothed : Smoothed or None
        The smoother's estimates in a run of :func:`zakai.smooth`; ``None`` in a filtering
        run.
    key : str or None
        The method's catalogue key (``"kalman"``, ``"pf"``); :attr:`RunResult.methods` finds
        the result by it as well as by the display name.
    pit : ndarray, shape (N + 1, m), or None
        With ``checks=True`` (:func:`zakai.filter`): the probability integral transform of
        each observation under the law the method predicted for it before seeing it,
        ``u = F(z)`` per component — uniform on (0, 1) and independent over the rows when the
        model and the method are right (Dawid 1984); for counts the randomised
        ``F(z − 1) + V (F(z) − F(z − 1))``. NaN where missing (and at row 0 of increments).
    standardized_innovations : ndarray, shape (N + 1, m), or None
        With ``checks=True``: ``(z − E z) / sd z`` under the same law — for a Gaussian law
        statsmodels' ``standardized_forecasts_error``.
    innovations : ndarray, shape (N + 1, m), or None
        With ``checks=True`` and discrete measurements: ``z − h(x̂⁻)``, the measurement less h
        at the mean the method predicted.
    densities : ndarray, shape (N + 1, points), or None
        With ``density_grid=``: the marginal density of component ``density_dim`` at the
        points ``density_grid`` after each row.
    """

    name: str
    estimates: np.ndarray
    covariances: Optional[np.ndarray]
    failure: Optional[tuple[int, float, str]]
    concerns: list[dict[str, Any]]
    mse: Optional[float]
    log_likelihood: Optional[float]
    log_likelihoods: np.ndarray
    seconds_per_step: float
    build_seconds: float
    smoothed: Optional[Smoothed] = None
    key: Optional[str] = None
    pit: Optional[np.ndarray] = None
    standardized_innovations: Optional[np.ndarray] = None
    innovations: Optional[np.ndarray] = None
    times: Optional[np.ndarray] = None
    densities: Optional[np.ndarray] = None
    density_grid: Optional[np.ndarray] = None
    density_dim: int = 0

    def plot(self, dim: int = 0) -> Any:
        """The estimates of component ``dim`` with ±2σ bands and, when the run kept them
        (``density_grid=``), the marginal densities over time as a heat strip beneath
        (matplotlib); the Figure."""
        from . import plotting

        times = self.times if self.times is not None else np.arange(len(self.estimates))
        return plotting.method(self, times, dim)

    def diagnostics(self, lags: int = 10) -> "Diagnostics":
        """The tests of the model on this method's one-step predictions (needs a run with
        ``checks=True``): per observed component the Ljung–Box test of the standardised
        innovations at ``lags`` lags (Ljung & Box 1978; statsmodels' ``acorr_ljungbox``) and
        the Kolmogorov–Smirnov test of the PIT's uniformity, with their p-values. Small
        p-values say the model (or the method's approximation of its posterior) does not
        describe the data: correlated errors, or predictive laws too narrow, too wide or
        off-centre.

        Examples
        --------
        >>> import numpy as np, zakai
        >>> model = zakai.Model.discrete("-0.3*x", "x", noise_cov=0.5, diffusion=0.8)
        >>> sc = zakai.Scenario(model, zakai.Prior.gaussian(0.0, 1.0), ["kalman"],
        ...                     dt_obs=1.0, t_final=200.0, seed=1)
        >>> times, _, z = zakai.simulate(sc)
        >>> d = zakai.filter(sc, z, times=times, checks=True).methods["KF"].diagnostics()
        >>> row = d.rows[0]
        >>> row["count"], row["pit_ks_p"] > 0.01, row["ljung_box_p"] > 0.01
        (201, True, True)
        """
        if self.pit is None or self.standardized_innovations is None:
            raise ConfigError(
                "diagnostics: this run did not record its predictive checks; run "
                "zakai.filter(..., checks=True)"
            )
        rows = []
        for j in range(self.pit.shape[1]):
            lb = _zakai.ljung_box(self.standardized_innovations[:, j].tolist(), int(lags))
            ks = _zakai.pit_uniformity(self.pit[:, j].tolist())
            rows.append({
                "component": j + 1,
                "ljung_box": None if lb is None else lb[0],
                "ljung_box_p": None if lb is None else lb[1],
                "lags": int(lags),
                "pit_ks": None if ks is None else ks[0],
                "pit_ks_p": None if ks is None else ks[1],
                "count": 0 if ks is None else ks[2],
            })
        return Diagnostics(self.name, rows, self.pit, self.standardized_innovations)

    @property
    def warned(self) -> bool:
        """Whether a self-check warned during the run."""
        return bool(self.concerns)

    def _summary(self) -> list[str]:
        """The method's numbers in a few words each."""
        out = []
        if self.mse is not None:
            out.append(f"MSE {self.mse:.4g}")
        if self.log_likelihood is not None:
            out.append(f"ln L {self.log_likelihood:.6g}")
        out.append(f"{self.seconds_per_step * 1e6:.3g} µs/step")
        if self.failure is not None:
            out.append(f"failed at t = {self.failure[1]:.4g}: {_short(self.failure[2])}")
        if self.concerns:
            out.append(f"{len(self.concerns)} self-check warning(s)")
        if self.pit is not None:
            out.append("checked")
        return out

    def __repr__(self) -> str:
        rows, n = self.estimates.shape
        return f"MethodResult({self.name}, rows={rows}, n={n}; " + "; ".join(self._summary()) + ")"

    def _repr_html_(self) -> str:
        return (f"<b>{html.escape(self.name)}</b> — {len(self.estimates)} rows: "
                + html.escape("; ".join(self._summary())))

    @property
    def sds(self) -> Optional[np.ndarray]:
        """Standard deviations (N + 1, n) from the covariances, or ``None``."""
        if self.covariances is None:
            return None
        return np.sqrt(np.clip(np.diagonal(self.covariances, axis1=1, axis2=2), 0.0, None))



def _short(text: str, limit: int = 120) -> str:
    """``text`` cut to ``limit`` characters (with an ellipsis)."""
    return text if len(text) <= limit else text[: limit - 1] + "…"


class Diagnostics:
    """The tests of a model on one method's one-step predictions
    (:meth:`MethodResult.diagnostics`): per observed component the Ljung–Box statistic and
    p-value of the standardised innovations, and the Kolmogorov–Smirnov distance of the PIT
    from the uniform law and its p-value.

    Attributes
    ----------
    method : str
    rows : list of dict
        ``component``, ``ljung_box``, ``ljung_box_p``, ``lags``, ``pit_ks``, ``pit_ks_p``,
        ``count`` (the observations used).
    """

    __slots__ = ("method", "rows", "pit", "standardized")

    def __init__(self, method: str, rows: list[dict[str, Any]], pit: np.ndarray,
                 standardized: np.ndarray) -> None:
        self.method = method
        self.rows = rows
        self.pit = pit
        self.standardized = standardized

    def plot(self, component: int = 1) -> Any:
        """The 2 × 2 figure of the checks of observation component ``component`` (1-based):
        standardised innovations, PIT histogram, normal Q-Q plot, correlogram; the Figure."""
        from . import plotting

        return plotting.diagnostics(self, component)

    def to_pandas(self) -> Any:
        """The rows as a DataFrame indexed by component."""
        import pandas as pd

        return pd.DataFrame(self.rows).set_index("component")

    def __repr__(self) -> str:
        def p(v: Optional[float]) -> str:
            return "—" if v is None else f"{v:.3g}"

        parts = [f"z{r['component']}: Ljung–Box p = {p(r['ljung_box_p'])}, PIT uniform p = {p(r['pit_ks_p'])}"
                 for r in self.rows]
        return f"Diagnostics({self.method}; " + "; ".join(parts) + ")"

    def _repr_html_(self) -> str:
        def f(v: Optional[float]) -> str:
            return "—" if v is None else f"{v:.4g}"

        head = ("<tr><th>component</th><th>Ljung–Box Q</th><th>p</th><th>PIT KS D</th>"
                "<th>p</th><th>n</th></tr>")
        body = "".join(
            f"<tr><td>{r['component']}</td><td>{f(r['ljung_box'])}</td><td>{f(r['ljung_box_p'])}</td>"
            f"<td>{f(r['pit_ks'])}</td><td>{f(r['pit_ks_p'])}</td><td>{r['count']}</td></tr>"
            for r in self.rows
        )
        return f"<b>Diagnostics</b> of {html.escape(self.method)}<table>{head}{body}</table>"


class Methods(dict):  # type: ignore[type-arg]
    """The methods of a run by display name (``"KF"``, ``"PF(1000)"``, ``"SA(800)"``), in
    the scenario's order; a catalogue key (``"kalman"``, ``"pf"``, ``"separation"``) that is
    not a display name finds the one method with that key."""

    def __missing__(self, key: str) -> "MethodResult":
        found = [m for m in self.values() if m.key == key]
        if len(found) == 1:
            return found[0]
        if found:
            raise KeyError(
                f"{key!r}: {len(found)} methods have this key; use a display name: "
                + ", ".join(m.name for m in found)
            )
        raise KeyError(f"{key!r}: no method of this run has that name or key; the run has "
                       + ", ".join(f"{n} ({m.key})" for n, m in self.items()))


@dataclass(slots=True)
class RunResult:
    """Every method's estimates on one set of observations.

    Attributes
    ----------
    times : ndarray, shape (N + 1,)
    observations : ndarray, shape (N + 1, m)
        Row 0 of continuous observations is the start (zeros); row k the increment over
        (τ_{k−1}, τ_k]. Discrete: the measurement at τ_k.
    truth : ndarray, shape (N + 1, n), or None
    methods : Methods (a dict of str to MethodResult)
        In the scenario's order, keyed by display name (``"KF"``, ``"PF(1000)"``); a method's
        catalogue key (``"kalman"``, ``"pf"``) finds it too when one method has that key.
    warnings : list of (str, str)
        ``(method, message)`` about parameters (stability conditions and the like).
    chosen_defaults : list of str
        Sizes chosen from the problem.
    """

    seed: int
    continuous: bool
    times: np.ndarray
    observations: np.ndarray
    truth: Optional[np.ndarray]
    methods: Methods
    warnings: list[tuple[str, str]] = field(default_factory=list)
    chosen_defaults: list[str] = field(default_factory=list)
    #: The index of the pandas object the observations came in (labels :meth:`to_pandas`).
    index: Any = None
    #: The unit datetime times were read in (``"Y"``, ``"D"``, ``"s"`` …: Δτ and the
    #: model's rates are per it); ``None`` for times given as numbers.
    time_unit: Optional[str] = None

    def to_pandas(self) -> Any:
        """The run as a pandas DataFrame, one row per time, indexed like the observations
        given to :func:`filter` (else by ``t``): the time ``t``, the observations (NaN where
        missing), the truth when known, then per method its estimate ``<method> x<i>`` and,
        where it has a covariance, its standard deviation ``<method> sd x<i>``, and the
        log-likelihood of the row's observation ``<method> loglik`` (NaN after a failure); in
        a run of :func:`zakai.smooth` also ``<method> smoothed x<i>`` and
        ``<method> smoothed sd x<i>`` (NaN for a method without a smoother)."""
        import pandas as pd

        n = next(iter(self.methods.values())).estimates.shape[1] if self.methods else 0
        columns: dict[str, Any] = {"t": self.times}
        prefix = "dy" if self.continuous else "z"
        for j in range(self.observations.shape[1]):
            columns[f"{prefix}{j + 1}"] = self.observations[:, j]
        if self.truth is not None:
            for j in range(self.truth.shape[1]):
                columns[f"x{j + 1}"] = self.truth[:, j]
        for key, m in self.methods.items():
            sds = m.sds
            for j in range(n):
                columns[f"{key} x{j + 1}"] = m.estimates[:, j]
                if sds is not None:
                    columns[f"{key} sd x{j + 1}"] = sds[:, j]
            columns[f"{key} loglik"] = m.log_likelihoods
            if m.smoothed is not None:
                smoothed_sds = m.smoothed.sds
                for j in range(n):
                    columns[f"{key} smoothed x{j + 1}"] = m.smoothed.estimates[:, j]
                    columns[f"{key} smoothed sd x{j + 1}"] = smoothed_sds[:, j]
        index = self.index if self.index is not None else pd.Index(self.times, name="t")
        return pd.DataFrame(columns, index=index)

    @classmethod
    def _from_dict(cls, d: dict[str, Any]) -> "RunResult":
        methods = Methods()
        for m in d["methods"]:
            name = m["name"]
            key, i = name, 2
            while key in methods:  # two methods with one display name
                key, i = f"{name} #{i}", i + 1
            failure = m["failure"]
            sm = m.get("smoothed")
            methods[key] = MethodResult(
                name=name,
                estimates=m["estimates"],
                covariances=m["covariances"],
                failure=None if failure is None else (int(failure[0]), float(failure[1]), failure[2]),
                concerns=list(m["concerns"]),
                mse=m["mse"],
                log_likelihood=m["log_likelihood"],
                log_likelihoods=m["log_likelihoods"],
                seconds_per_step=m["seconds_per_step"],
                build_seconds=m["build_seconds"],
                smoothed=None if sm is None else Smoothed(**sm),
                key=m.get("key"),
                pit=m.get("pit"),
                standardized_innovations=m.get("standardized"),
                innovations=m.get("innovations"),
                times=d["times"],
                densities=m.get("densities"),
            )
        return cls(
            seed=d["seed"],
            continuous=d["continuous"],
            times=d["times"],
            observations=d["observations"],
            truth=d["truth"],
            methods=methods,
            warnings=[tuple(w) for w in d["warnings"]],
            chosen_defaults=list(d["chosen_defaults"]),
        )

    def table(self) -> str:
        """One line per method: last estimate, MSE, log-likelihood, failure, warnings, time
        per step."""
        lines = [
            f"{'method':<14} {'last estimate':>24} {'MSE':>10} {'log-lik':>12} {'µs/step':>9}  notes"
        ]
        for key, m in self.methods.items():
            last = m.estimates[-1]
            est = "—" if np.isnan(last).any() else np.array2string(last, precision=4)
            mse = "—" if m.mse is None else f"{m.mse:.4g}"
            ll = "—" if m.log_likelihood is None else f"{m.log_likelihood:.4f}"
            notes = []
            if m.failure is not None:
                notes.append(f"failed at t = {m.failure[1]:.4g}: {m.failure[2]}")
            notes += [c["text"] for c in m.concerns]
            lines.append(
                f"{key:<14} {est:>24} {mse:>10} {ll:>12} {m.seconds_per_step * 1e6:>9.2f}  "
                + "; ".join(notes)
            )
        return "\n".join(lines)

    def __repr__(self) -> str:
        return f"RunResult(seed={self.seed}, steps={len(self.times) - 1}, methods={list(self.methods)})"

    def plot(self, dim: int = 0, methods: Optional[list[str]] = None) -> Any:
        """Every method's estimates of component ``dim`` with ±2σ bands, the truth when known,
        and the observations below (matplotlib); ``methods`` (names or keys) to show some
        only. The Figure."""
        from . import plotting

        return plotting.run(self, dim, methods)

    def _repr_html_(self) -> str:
        head = ("<tr><th>method</th><th>last estimate</th><th>MSE</th><th>ln L</th>"
                "<th>µs/step</th><th>notes</th></tr>")
        rows = []
        for key, m in self.methods.items():
            last = m.estimates[-1]
            est = "—" if np.isnan(last).any() else ", ".join(f"{v:.4g}" for v in last)
            notes = []
            if m.failure is not None:
                notes.append(f"failed at t = {m.failure[1]:.4g}: {_short(m.failure[2])}")
            notes += [_short(c["text"]) for c in m.concerns]
            rows.append(
                f"<tr><td>{html.escape(key)}</td><td>{est}</td>"
                f"<td>{'—' if m.mse is None else f'{m.mse:.4g}'}</td>"
                f"<td>{'—' if m.log_likelihood is None else f'{m.log_likelihood:.6g}'}</td>"
                f"<td>{m.seconds_per_step * 1e6:.3g}</td><td>{html.escape('; '.join(notes))}</td></tr>"
            )
        return (f"<b>Run</b>: {len(self.times) - 1} steps, seed {self.seed}"
                f"<table>{head}{''.join(rows)}</table>")



class MonteCarloTable:
    """The papers' table over many runs: per method the MSE (mean ± standard error over the
    runs it finished, with the failed runs beside it), the paper's number where the scenario
    is a paper's table row, warned runs and time per step.

    Attributes
    ----------
    scenario : str
    runs : int
    seed : int
        Seed of the first run (runs use ``seed, seed + 1, …``).
    rows : list of dict
        One dict per method (``name``, ``mse``, ``mse_stderr``, ``mse_text``,
        ``mse_quartiles``, ``failed``, ``warned``, ``paper``, ``coincides_with``,
        ``seconds_per_step``, ``build_seconds``, ``e_mean`` …).
    how_means_are_taken : str
        The rule behind every mean, said above the table.
    """

    def __init__(self, summary: dict[str, Any]) -> None:
        self.scenario: str = summary["scenario"]
        self.runs: int = summary["runs"]
        self.seed: int = summary["seed"]
        self.rows: list[dict[str, Any]] = summary["methods"]
        self.warnings: list[tuple[str, str]] = [tuple(w) for w in summary["warnings"]]
        self.how_means_are_taken: str = summary["how_means_are_taken"]

    _COLUMNS = ("name", "mse", "mse_stderr", "failed", "runs", "mse_text", "paper_text",
                "warned", "seconds_per_step", "build_seconds")

    def to_pandas(self) -> Any:
        """The table as a pandas DataFrame indexed by method (needs pandas)."""
        try:
            import pandas as pd
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("MonteCarloTable.to_pandas needs pandas (pip install pandas)") from e
        frame = pd.DataFrame(
            [{c: r[c] for c in self._COLUMNS} for r in self.rows]
        )
        return frame.set_index("name")

    def notes(self) -> list[str]:
        """Rows that are the same numbers as an earlier row, with the reason when known."""
        out = []
        for r in self.rows:
            c = r.get("coincides_with")
            if c is not None:
                why = f": {c['why']}" if c.get("why") else ""
                out.append(f"{r['name']} = {c['method']} in every run (largest relative "
                           f"difference {c['largest_relative_difference']:.1e}){why}")
        return out

    def __str__(self) -> str:
        lines = [
            f"{self.scenario}: {self.runs} runs from seed {self.seed}",
            f"{self.how_means_are_taken}.",
            f"{'method':<14} {'MSE (runs finished)':>30} {'warned':>7} {'µs/step':>9}  paper",
        ]
        for r in self.rows:
            lines.append(
                f"{r['name']:<14} {r['mse_text']:>30} {r['warned']:>7} "
                f"{r['seconds_per_step'] * 1e6:>9.2f}  {r['paper_text']}"
            )
        return "\n".join(lines + self.notes())

    def __repr__(self) -> str:
        return f"MonteCarloTable({self.scenario!r}, runs={self.runs})"
