"""Continuous-time nonlinear filtering on NumPy arrays, at Rust speed.

Zakai puts the Yau–Yau grid solvers (Yueh, Lin & Yau 2014), the spectral off-line/on-line
filter (Shi, Chen & Yau 2021), the direct method (Shi, Yang & Yau 2018), the Fokker–Planck
separation filter (Šimandl & Švácha 2005) and the MAP / IOKF framework (Kang, Salmon & Yau
2023) side by side with the Kalman–Bucy, EKF, UKF, particle and Gaussian-sum filters, on the
same truth and the same observations — simulated or yours.

Quick start::

    import zakai
    sc = zakai.Scenario.from_preset("cubic-sensor-1d")
    times, states, obs = zakai.simulate(sc, seed=3)
    result = zakai.filter(sc, obs, times=times, truth=states)
    print(result.table())

A scenario is the same JSON the ``zakai`` command line and the playground read
(:meth:`Scenario.to_json`). Models are text expressions in ``x`` (``x1 … xn`` when n > 1),
compiled once and evaluated in Rust. Errors are exceptions of :mod:`zakai.errors` with the
command line's messages.
"""

from __future__ import annotations

import json as _json
from dataclasses import dataclass, field
from typing import Any, Iterable, Mapping, Optional, Sequence, Union

import numpy as np

from . import _zakai
from .errors import ConfigError, DimensionError, ExpressionError, FilterError, ZakaiError

__version__: str = _zakai.__version__

__all__ = [
    "Scenario",
    "Model",
    "Prior",
    "Filter",
    "RunResult",
    "MethodResult",
    "MonteCarloTable",
    "presets",
    "methods",
    "simulate",
    "run",
    "filter",
    "monte_carlo",
    "set_memory_cap",
    "ZakaiError",
    "ConfigError",
    "ExpressionError",
    "DimensionError",
    "FilterError",
]

ArrayLike = Union[np.ndarray, Sequence[float], Sequence[Sequence[float]]]
MethodSpec = Union[str, Mapping[str, Any]]

#: Half-width of the domain chosen around the prior when none is given, in prior sds.
DOMAIN_SDS: float = 8.0


def presets() -> list[str]:
    """Names of the built-in scenarios (the papers' examples), in the command line's order."""
    return [name for name, _ in _zakai.presets()]


def set_memory_cap(cap: Union[int, str]) -> int:
    """Sets the largest memory a scenario's methods may need together — bytes, or text such
    as ``"8GiB"`` (default 1 GiB, the playground's cap). Scenarios are checked against it
    before anything is allocated (:class:`ConfigError`). Returns the previous cap in bytes."""
    return _zakai.set_memory_cap(cap)


def methods() -> list[dict[str, Any]]:
    """Every method: ``key``, names, paper, parameter schema and ``defaults``."""
    return _json.loads(_zakai.catalogue_json())


def _method_config(spec: MethodSpec) -> dict[str, Any]:
    """A full method config from a key (``"pf"``) or a dict ``{"method": "pf", ...}``."""
    if isinstance(spec, str):
        key, params = spec, {}
    elif isinstance(spec, Mapping):
        params = dict(spec)
        key = params.pop("method", None)
        if not isinstance(key, str):
            raise ConfigError("a method dict needs a 'method' key, e.g. {'method': 'pf'}")
    else:
        raise ConfigError(f"a method is a key or a dict, not {type(spec).__name__}")
    return _json.loads(_zakai.method_defaults_json(key, _json.dumps(params)))


def _numbers(value: Any, name: str) -> np.ndarray:
    """``value`` as a float array of finite numbers, or a :class:`ConfigError` naming it."""
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as e:
        raise ConfigError(f"{name}: must be numbers ({e})") from e
    if not np.isfinite(a).all():
        raise ConfigError(f"{name}: must be finite numbers, got {value!r}")
    return a


def _matrix(value: Any, name: str) -> list[list[float]]:
    """A square matrix as rows; a scalar is the 1 × 1 matrix."""
    a = np.atleast_2d(_numbers(value, name))
    if a.ndim != 2:
        raise DimensionError(f"{name} must be a matrix, got shape {a.shape}")
    return a.tolist()


def _vector(value: Any, name: str = "vector") -> list[float]:
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


@dataclass(frozen=True)
class Model:
    """A model ``dx = f(x) dt + G dv`` observed continuously (``dy = h(x) dt + dw``) or at
    discrete times (``z_k = h(x_k) + v_k``).

    Build it with :meth:`continuous` or :meth:`discrete`. Expressions are text in ``x``
    (``x1 … xn`` when n > 1) with ``+ - * / ^``, ``sin cos tan exp log sqrt tanh abs`` and
    friends; they are compiled once, with exact derivatives, in Rust.
    """

    config: dict[str, Any]

    @classmethod
    def continuous(
        cls,
        drift: Union[str, Sequence[str]],
        observation: Union[str, Sequence[str]],
        diffusion: Optional[ArrayLike] = None,
        noise_cov: Optional[ArrayLike] = None,
    ) -> "Model":
        """``dx = f dt + G dv``, ``dy = h dt + dw`` with ``E[dw dwᵀ] = S dt``.

        Parameters
        ----------
        drift, observation : str or list of str
            f and h, one expression per component.
        diffusion : array_like, optional
            G (n × n rows; a scalar when n = 1); the identity when absent.
        noise_cov : array_like, optional
            S; the identity when absent.
        """
        return cls(
            {
                "drift": _strings(drift, "drift"),
                "observation": _strings(observation, "observation"),
                "diffusion": None if diffusion is None else _matrix(diffusion, "diffusion"),
                "noise": {
                    "kind": "continuous",
                    "cov": None if noise_cov is None else _matrix(noise_cov, "noise_cov"),
                },
            }
        )

    @classmethod
    def discrete(
        cls,
        drift: Union[str, Sequence[str]],
        observation: Union[str, Sequence[str]],
        noise_cov: ArrayLike,
        diffusion: Optional[ArrayLike] = None,
    ) -> "Model":
        """``dx = f dt + G dv`` measured as ``z_k = h(x_k) + v_k``, ``v_k ~ N(0, R)``.

        Parameters
        ----------
        noise_cov : array_like
            R (m × m; a scalar when m = 1).
        """
        m = len(_strings(observation, "observation"))
        return cls(
            {
                "drift": _strings(drift, "drift"),
                "observation": _strings(observation, "observation"),
                "diffusion": None if diffusion is None else _matrix(diffusion, "diffusion"),
                "noise": {
                    "kind": "discrete",
                    "mixture": [
                        {"weight": 1.0, "mean": [0.0] * m, "cov": _matrix(noise_cov, "noise_cov")}
                    ],
                },
            }
        )


def _positive_definite(rows: list[list[float]], name: str) -> list[list[float]]:
    """``rows`` when they are a symmetric positive definite matrix, else a ConfigError that
    says so (a variance must be positive)."""
    a = np.asarray(rows)
    if a.shape[0] != a.shape[1] or not np.allclose(a, a.T):
        raise ConfigError(f"{name}: must be a symmetric matrix, got {rows!r}")
    if np.linalg.eigvalsh(a).min() <= 0.0:
        what = "a variance" if a.shape == (1, 1) else "a covariance"
        raise ConfigError(f"{name}: {what} must be positive definite (> 0), got {rows!r}")
    return rows


@dataclass(frozen=True)
class Prior:
    """The density of x₀: :meth:`gaussian`, :meth:`mixture` or :meth:`density` (text)."""

    config: dict[str, Any]

    @classmethod
    def gaussian(cls, mean: ArrayLike, cov: ArrayLike) -> "Prior":
        """N(mean, cov); a scalar cov is a variance when n = 1."""
        c = _matrix(cov, "prior cov")
        _positive_definite(c, "prior cov")
        return cls({"kind": "gaussian", "mean": _vector(mean, "prior mean"), "cov": c})

    @classmethod
    def mixture(cls, components: Iterable[tuple[float, ArrayLike, ArrayLike]]) -> "Prior":
        """Σ wᵢ N(meanᵢ, covᵢ) from ``(weight, mean, cov)`` triples (weights normalised)."""
        return cls(
            {
                "kind": "mixture",
                "components": [
                    {
                        "weight": float(w),
                        "mean": _vector(m, f"prior component {i} mean"),
                        "cov": _positive_definite(
                            _matrix(c, f"prior component {i} cov"), f"prior component {i} cov"
                        ),
                    }
                    for i, (w, m, c) in enumerate(components)
                ],
            }
        )

    @classmethod
    def density(cls, expression: str) -> "Prior":
        """An unnormalised density as text, restricted to the domain (give one)."""
        return cls({"kind": "density", "expression": expression})

    def covering_domain(self, sds: float = DOMAIN_SDS) -> Optional[list[list[float]]]:
        """``mean ± sds·sd`` per component (every mixture component covered), or ``None``
        for a density prior."""
        return _zakai.covering_domain(_json.dumps(self.config), float(sds))


class Scenario:
    """A model, prior, domain, time grid and methods: what one run needs.

    The same JSON as the command line's scenario files and the playground's "copy link".
    Fields a user changes most are attributes (``dt_obs``, ``t_final``, ``seed``, ``domain``,
    ``methods``, ``initial_state``); everything else through :attr:`config` (a dict). Every
    assignment is checked when the scenario is used (or by :meth:`validate`), all problems at
    once, with their field paths.

    Parameters
    ----------
    model : Model
    prior : Prior
    methods : list of str or dict
        Method keys (``"ukf"``, ``"pf"``, ``"qiem"``, …, see :func:`methods`) or dicts
        ``{"method": "pf", "particles": 1000}``; parameters left out take their defaults,
        sizes left unset are chosen from the problem.
    dt_obs, t_final : float
        Observation interval Δτ and horizon T (simulations; a recording brings its own times).
    domain : list of (low, high), optional
        The box the grid and spectral methods live on; ``prior mean ± 8 sd`` when absent.
    initial_state : array_like, optional
        x₀ of simulations; drawn from the prior when absent.
    """

    def __init__(
        self,
        model: Model,
        prior: Prior,
        methods: Sequence[MethodSpec] = ("ukf",),
        *,
        dt_obs: float = 0.01,
        t_final: float = 1.0,
        domain: Optional[Sequence[Sequence[float]]] = None,
        initial_state: Optional[ArrayLike] = None,
        seed: int = 0,
        name: str = "custom",
    ) -> None:
        if domain is None:
            domain = prior.covering_domain()
            if domain is None:
                raise ConfigError(
                    "domain: a density prior needs the domain it lives on"
                    if prior.config.get("kind") == "density"
                    else "domain: none given, and none can be set around this prior"
                )
        self.config: dict[str, Any] = {
            "name": name,
            "model": dict(model.config),
            "prior": dict(prior.config),
            "initial_state": None if initial_state is None else _vector(initial_state, "initial_state"),
            "domain": _domain(domain),
            "time": {"t_final": float(t_final), "dt_obs": float(dt_obs), "inner_steps": 1},
            "seed": int(seed),
            "failure": {"divergence_bound": None, "track_loss": None},
            "methods": [_method_config(m) for m in methods],
        }

    @classmethod
    def from_json(cls, text: str) -> "Scenario":
        """A scenario from its JSON text (a scenario file, ``zakai show``); checked at once."""
        scenario = cls.__new__(cls)
        normalised, _, _ = _zakai.check_scenario(text)
        scenario.config = _json.loads(normalised)
        return scenario

    @classmethod
    def from_preset(cls, name: str) -> "Scenario":
        """A built-in scenario (see :func:`presets`), e.g. ``"cubic-sensor-1d"``."""
        return cls.from_json(_zakai.preset_json(name))

    def to_json(self, indent: Optional[int] = 2) -> str:
        """The scenario as JSON, readable by ``zakai run <file>`` and the playground."""
        return _json.dumps(self.config, indent=indent, ensure_ascii=False)

    def copy(self) -> "Scenario":
        """An independent copy."""
        return Scenario.from_json(self.to_json())

    def validate(self) -> "Scenario":
        """Raises :class:`ConfigError` listing every problem; returns the scenario."""
        _zakai.check_scenario(self._text())
        return self

    def _text(self) -> str:
        return _json.dumps(self.config)

    @property
    def name(self) -> str:
        """The scenario's name."""
        return self.config["name"]

    @property
    def dt_obs(self) -> float:
        """Δτ, the observation interval."""
        return self.config["time"]["dt_obs"]

    @dt_obs.setter
    def dt_obs(self, value: float) -> None:
        self.config["time"]["dt_obs"] = float(value)

    @property
    def t_final(self) -> float:
        """T, the horizon of simulations."""
        return self.config["time"]["t_final"]

    @t_final.setter
    def t_final(self, value: float) -> None:
        self.config["time"]["t_final"] = float(value)

    @property
    def seed(self) -> int:
        """The default seed of :func:`simulate`, :func:`run` and :func:`monte_carlo`."""
        return self.config["seed"]

    @seed.setter
    def seed(self, value: int) -> None:
        self.config["seed"] = int(value)

    @property
    def domain(self) -> list[list[float]]:
        """The box ``[[low, high], …]`` of the grid and spectral methods."""
        return self.config["domain"]

    @domain.setter
    def domain(self, value: Sequence[Sequence[float]]) -> None:
        self.config["domain"] = _domain(value)

    @property
    def initial_state(self) -> Optional[list[float]]:
        """x₀ of simulations, or ``None`` (drawn from the prior)."""
        return self.config["initial_state"]

    @initial_state.setter
    def initial_state(self, value: Optional[ArrayLike]) -> None:
        self.config["initial_state"] = None if value is None else _vector(value, "initial_state")

    @property
    def methods(self) -> list[dict[str, Any]]:
        """The methods' configs (dicts; edit them in place or assign a new list of keys or
        dicts)."""
        return self.config["methods"]

    @methods.setter
    def methods(self, value: Sequence[MethodSpec]) -> None:
        self.config["methods"] = [_method_config(m) for m in value]

    @property
    def method_names(self) -> list[str]:
        """Display names with the sizes that matter (``"PF(200)"``), after validation."""
        return _zakai.check_scenario(self._text())[1]

    @property
    def chosen_defaults(self) -> list[str]:
        """Notes of the sizes chosen from the problem (e.g. the spectral basis)."""
        return _zakai.check_scenario(self._text())[2]

    @property
    def n(self) -> int:
        """State dimension."""
        return len(self.config["model"]["drift"])

    @property
    def m(self) -> int:
        """Observation dimension."""
        return len(self.config["model"]["observation"])

    def __repr__(self) -> str:
        keys = ", ".join(m["method"] for m in self.methods)
        return f"Scenario({self.name!r}, n={self.n}, m={self.m}, methods=[{keys}])"


@dataclass
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
    seconds_per_step, build_seconds : float
        Wall time per step and to build the filter (its off-line part).
    """

    name: str
    estimates: np.ndarray
    covariances: Optional[np.ndarray]
    failure: Optional[tuple[int, float, str]]
    concerns: list[dict[str, Any]]
    mse: Optional[float]
    seconds_per_step: float
    build_seconds: float

    @property
    def warned(self) -> bool:
        """Whether a self-check warned during the run."""
        return bool(self.concerns)

    @property
    def sds(self) -> Optional[np.ndarray]:
        """Standard deviations (N + 1, n) from the covariances, or ``None``."""
        if self.covariances is None:
            return None
        return np.sqrt(np.clip(np.diagonal(self.covariances, axis1=1, axis2=2), 0.0, None))


@dataclass
class RunResult:
    """Every method's estimates on one set of observations.

    Attributes
    ----------
    times : ndarray, shape (N + 1,)
    observations : ndarray, shape (N + 1, m)
        Row 0 of continuous observations is the start (zeros); row k the increment over
        (τ_{k−1}, τ_k]. Discrete: the measurement at τ_k.
    truth : ndarray, shape (N + 1, n), or None
    methods : dict of str to MethodResult
        In the scenario's order, keyed by display name.
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
    methods: dict[str, MethodResult]
    warnings: list[tuple[str, str]] = field(default_factory=list)
    chosen_defaults: list[str] = field(default_factory=list)
    #: The index of the pandas object the observations came in (labels :meth:`to_pandas`).
    index: Any = None

    def to_pandas(self) -> Any:
        """The run as a pandas DataFrame, one row per time, indexed like the observations
        given to :func:`filter` (else by ``t``): the time ``t``, the observations (NaN where
        missing), the truth when known, then per method its estimate ``<method> x<i>`` and,
        where it has a covariance, its standard deviation ``<method> sd x<i>`` (NaN after a
        failure)."""
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
        index = self.index if self.index is not None else pd.Index(self.times, name="t")
        return pd.DataFrame(columns, index=index)

    @classmethod
    def _from_dict(cls, d: dict[str, Any]) -> "RunResult":
        methods: dict[str, MethodResult] = {}
        for m in d["methods"]:
            name = m["name"]
            key, i = name, 2
            while key in methods:  # two methods with one display name
                key, i = f"{name} #{i}", i + 1
            failure = m["failure"]
            methods[key] = MethodResult(
                name=name,
                estimates=m["estimates"],
                covariances=m["covariances"],
                failure=None if failure is None else (int(failure[0]), float(failure[1]), failure[2]),
                concerns=list(m["concerns"]),
                mse=m["mse"],
                seconds_per_step=m["seconds_per_step"],
                build_seconds=m["build_seconds"],
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
        """One line per method: last estimate, MSE, failure, warnings, time per step."""
        lines = [f"{'method':<14} {'last estimate':>24} {'MSE':>10} {'µs/step':>9}  notes"]
        for key, m in self.methods.items():
            last = m.estimates[-1]
            est = "—" if np.isnan(last).any() else np.array2string(last, precision=4)
            mse = "—" if m.mse is None else f"{m.mse:.4g}"
            notes = []
            if m.failure is not None:
                notes.append(f"failed at t = {m.failure[1]:.4g}: {m.failure[2]}")
            notes += [c["text"] for c in m.concerns]
            lines.append(
                f"{key:<14} {est:>24} {mse:>10} {m.seconds_per_step * 1e6:>9.2f}  "
                + "; ".join(notes)
            )
        return "\n".join(lines)

    def __repr__(self) -> str:
        return f"RunResult(seed={self.seed}, steps={len(self.times) - 1}, methods={list(self.methods)})"


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
    scenario: Union[Scenario, str], seed: Optional[int] = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Simulates the scenario's truth and observations.

    Returns
    -------
    times : ndarray, shape (N + 1,)
        τ_k = k Δτ.
    states : ndarray, shape (N + 1, n)
    observations : ndarray, shape (N + 1, m)
        Continuous: row 0 zeros, row k the increment y(τ_k) − y(τ_{k−1}); discrete: z_k.
    """
    sc = _scenario(scenario)
    return _zakai.simulate(sc._text(), _seed(sc, seed))


def run(scenario: Union[Scenario, str], seed: Optional[int] = None) -> RunResult:
    """Simulates the run with ``seed`` and filters it with every method of the scenario."""
    sc = _scenario(scenario)
    return RunResult._from_dict(_zakai.run(sc._text(), _seed(sc, seed)))


def _array(value: Optional[ArrayLike], name: str) -> Optional[np.ndarray]:
    if value is None:
        return None
    try:
        a = np.ascontiguousarray(value, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise DimensionError(f"{name} must be an array of numbers: {e}") from e
    if a.ndim == 0:
        a = a.reshape(1)
    return a


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


def filter(
    scenario: Union[Scenario, str],
    observations: ArrayLike,
    times: Optional[ArrayLike] = None,
    truth: Optional[ArrayLike] = None,
    seed: Optional[int] = None,
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
        remainder). Datetimes (``datetime64``, pandas ``DatetimeIndex``, ``datetime`` objects) are
        converted to **seconds since the first**, so Δτ and the model's rates are per
        second (a step of more than 10⁴ Δτ is refused as a mis-set Δτ). Every Δτ from 0 when absent.
    truth : array_like, shape (N + 1, n), optional
        The true states, for errors (MSE) against them.
    seed : int, optional
        Seeds the methods' random numbers (particle filter); the scenario's seed when absent.
    """
    sc = _scenario(scenario)
    index_times, index = _index_times(observations)
    obs = _array(
        observations.to_numpy(dtype=float) if hasattr(observations, "to_numpy") else observations,
        "observations",
    )
    given = _times(times)
    result = RunResult._from_dict(
        _zakai.filter_recorded(
            sc._text(),
            obs,
            given if given is not None else index_times,
            _array(truth, "truth"),
            _seed(sc, seed),
        )
    )
    if index is not None and len(index) == len(result.times):
        result.index = index
    return result


def monte_carlo(
    scenario: Union[Scenario, str], runs: int, seed: Optional[int] = None
) -> MonteCarloTable:
    """``runs`` runs with seeds ``seed, seed + 1, …`` on every core (the GIL released).

    Returns the papers' table; ``.to_pandas()`` gives it as a DataFrame.
    """
    sc = _scenario(scenario)
    if not isinstance(runs, (int, np.integer)) or runs < 1:
        raise ConfigError(f"runs: must be a positive integer (got {runs!r})")
    return MonteCarloTable(_json.loads(_zakai.monte_carlo_json(sc._text(), int(runs), _seed(sc, seed))))


class Filter:
    """One filter stepped by hand: ``f.step(dy, dt)``, then ``f.mean``, ``f.cov``,
    ``f.density(grid)``.

    Parameters
    ----------
    method : str
        A method key (see :func:`methods`): ``"kalman"``, ``"ekf"``, ``"ukf"``, ``"pf"``,
        ``"iekf"``, ``"iokf"``, ``"qiem"``, ``"iem"``, ``"spt"``, ``"qiem4"``, ``"spectral"``,
        ``"direct"``, ``"separation"``, ``"implicit_fdm"``, ``"gaussian_sum"``.
    model : Model
    prior : Prior
    dt_obs : float
        The observation interval Δτ (the default step; grid and spectral methods are built
        for it and cross other steps as whole Δτ and a remainder). A method's own ``dt`` (the grid filters' time step) is one of
        ``params``.
    domain : list of (low, high), optional
        The box of grid and spectral methods; ``prior mean ± 8 sd`` when absent.
    seed : int
        Seeds the method's random numbers.
    **params
        The method's parameters (``particles=1000``, ``points=[401]`` …); the rest take their
        defaults or are chosen from the problem (:attr:`chosen_defaults`).

    Examples
    --------
    >>> model = Model.continuous("0", "x^3")
    >>> f = Filter("qiem", model, Prior.gaussian(1.0, 0.1), dt_obs=0.01, points=[401])
    >>> f.step([0.012], 0.01)
    >>> float(f.mean[0])  # doctest: +SKIP
    """

    def __init__(
        self,
        method: str,
        model: Model,
        prior: Prior,
        *,
        dt_obs: float,
        domain: Optional[Sequence[Sequence[float]]] = None,
        seed: int = 0,
        **params: Any,
    ) -> None:
        scenario = Scenario(
            model,
            prior,
            [{"method": method, **params}],
            dt_obs=dt_obs,
            t_final=dt_obs,
            domain=domain,
            seed=seed,
        )
        self.scenario: Scenario = scenario
        self._inner = _zakai.Stepper(scenario._text(), int(seed))
        # Whether the filter is still at the prior's time (no step taken yet).
        self._at_prior = True

    def _dt(self, dt: Optional[float]) -> float:
        if dt is None:
            return self.scenario.dt_obs
        if not isinstance(dt, (int, float, np.integer, np.floating)):
            raise ConfigError(f"dt: must be a number of time units (got {type(dt).__name__})")
        return float(dt)

    def step(self, observation: ArrayLike, dt: Optional[float] = None) -> None:
        """Predicts over ``dt`` (Δτ when absent) and assimilates one observation: the
        increment dy for continuous models, the measurement z for discrete ones (``dt = 0``
        assimilates at the current time). NaN components are missing: only the observed
        ones are used, and an all-NaN observation is a prediction only. A step that fails
        raises :class:`FilterError` and leaves the filter as it was."""
        self._inner.step(_array(observation, "observation"), self._dt(dt))
        self._at_prior = False

    def predict(self, dt: Optional[float] = None) -> None:
        """Predicts over ``dt`` (Δτ when absent) without an observation: a gap in the data,
        or a forecast (on a :meth:`copy`, to keep the filter itself at the present)."""
        self._inner.predict(self._dt(dt))
        self._at_prior = False

    def update(self, z: ArrayLike) -> None:
        """Assimilates the measurement ``z`` at the current time, without predicting
        (discrete models; NaN components are missing)."""
        self._inner.update(_array(z, "z"))
        self._at_prior = False

    def copy(self) -> "Filter":
        """An independent copy of the filter in its current state: stepping one does not
        move the other (e.g. to forecast from here)."""
        twin = Filter.__new__(Filter)
        twin.scenario = self.scenario.copy()
        twin._inner = self._inner.fork()
        twin._at_prior = self._at_prior
        return twin

    def __copy__(self) -> "Filter":
        return self.copy()

    def __deepcopy__(self, memo: dict[int, Any]) -> "Filter":
        return self.copy()

    def __reduce__(self) -> Any:
        raise TypeError(
            "a zakai.Filter holds its state in native memory and cannot be pickled; "
            "keep its scenario (f.scenario.to_json()) and the observations, and step a new "
            "Filter through them, or copy it in the same process with f.copy()"
        )

    def run(
        self, observations: ArrayLike, dts: Optional[ArrayLike] = None
    ) -> tuple[np.ndarray, Optional[np.ndarray]]:
        """Steps through every row of ``observations`` (step lengths ``dts``) in Rust and
        returns the means (rows, n) and covariances (rows, n, n) or ``None``, after each
        step. NaN components are missing.

        Without ``dts`` every row comes Δτ after the one before — and, as in
        :func:`filter`, a discrete model's first row is a measurement at the prior's time
        (step 0) when the filter has not stepped yet."""
        obs = _array(observations, "observations")
        assert obs is not None
        rows = obs.shape[0]
        if dts is None:
            steps = np.full(rows, self.scenario.dt_obs)
            if rows and self._at_prior and not self._inner.continuous:
                steps[0] = 0.0
        else:
            steps = _array(dts, "dts")
        result = self._inner.run(obs, steps)
        self._at_prior = self._at_prior and rows == 0
        return result

    @property
    def name(self) -> str:
        """Display name, e.g. ``"PF(1000)"``."""
        return self._inner.name

    @property
    def mean(self) -> np.ndarray:
        """The conditional mean (or the method's point estimate), shape (n,)."""
        return self._inner.mean

    @property
    def cov(self) -> Optional[np.ndarray]:
        """The conditional covariance, shape (n, n), or ``None``."""
        return self._inner.cov

    @property
    def map(self) -> Optional[np.ndarray]:
        """The maximum a posteriori point, for methods that compute one."""
        return self._inner.map

    @property
    def warnings(self) -> list[str]:
        """Warnings about the parameters (stability conditions), known before any step."""
        return self._inner.warnings

    @property
    def chosen_defaults(self) -> list[str]:
        """Notes of the sizes chosen from the problem."""
        return self._inner.chosen_defaults

    def self_check(self) -> list[dict[str, Any]]:
        """The self-checks crossing their thresholds now (``check``, ``value``,
        ``threshold``, ``above``, ``advice``); empty when all is well."""
        return self._inner.self_check()

    def density(self, grid: ArrayLike, dim: int = 0) -> np.ndarray:
        """The marginal density of component ``dim`` at the points ``grid`` (the Gaussian of
        the estimate for Kalman-type filters)."""
        return self._inner.density(_array(grid, "grid"), int(dim))

    def density2d(
        self, xs: ArrayLike, ys: ArrayLike, dims: tuple[int, int] = (0, 1)
    ) -> np.ndarray:
        """The joint marginal density of components ``dims`` on ``xs × ys``, shape
        (len(ys), len(xs))."""
        return self._inner.density2d(_array(xs, "xs"), _array(ys, "ys"), tuple(dims))

    def __repr__(self) -> str:
        return repr(self._inner)
