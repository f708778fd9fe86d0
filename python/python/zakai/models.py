"""The model and the prior: :class:`Model` (drift f, observation h, diffusion G and the
observation noise, as text expressions) and :class:`Prior` (the density of x₀), as the Rust
core's ``Model`` and ``Prior``."""

from __future__ import annotations

import json as _json
from dataclasses import dataclass
from typing import Any, Iterable, Optional, Sequence, Union

import numpy as np

from . import _zakai
from ._convert import ArrayLike, _matrix, _vector, _strings, _positive_definite
from .errors import ConfigError, ExpressionError, ZakaiError

#: Half-width of the domain chosen around the prior when none is given, in prior sds.
DOMAIN_SDS: float = 8.0


@dataclass(frozen=True)
class Model:
    """A model ``dx = f(x) dt + G dv`` observed continuously (``dy = h(x) dt + dw``) or at
    discrete times (``z_k = h(x_k) + v_k``, or ``z_k ~ p(z | x_k)``).

    Build it with :meth:`continuous` or :meth:`discrete` (additive Gaussian noise), or with
    :meth:`discrete_time` for a map ``x_k = F(x_(k−1)) + w_k`` (any model becomes one with
    :meth:`in_discrete_time`), or with one of the measurement families beyond it: :meth:`poisson` (counts), :meth:`student_t`
    (outliers), :meth:`heteroscedastic` (a variance s(x): stochastic volatility) and
    :meth:`log_density` (any ``log p(z | x)``). Expressions are text in ``x``
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
            G (n × n rows; a scalar when n = 1); the identity when absent. Entries may be
            expressions in the parameters (``"sqrt(q)"``) or in the state, making G a function
            G(x) (``"0.3*sqrt(abs(x))"``: the grid, spectral and particle filters use it, the
            Kalman family takes it at the mean, QIEM and the exact filters refuse it).
        noise_cov : array_like, optional
            S; the identity when absent.
        """
        cov = None if noise_cov is None else _matrix(noise_cov, "noise_cov")
        return cls._of(drift, observation, diffusion, {"kind": "continuous", "cov": cov})

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
        gaussian = {"weight": 1.0, "mean": [0.0] * m, "cov": _matrix(noise_cov, "noise_cov")}
        return cls._of(drift, observation, diffusion, {"kind": "discrete", "mixture": [gaussian]})

    @classmethod
    def poisson(
        cls,
        drift: Union[str, Sequence[str]],
        rate: Union[str, Sequence[str]],
        diffusion: Optional[ArrayLike] = None,
    ) -> "Model":
        """Counts ``z_{k,j} ~ Poisson(λ_j(x_k))``, independent given the state.

        Parameters
        ----------
        rate : str or list of str
            λ = h(x), one expression per count series; it must be nonnegative wherever a
            filter evaluates it (``exp(x)`` is, ``x`` is not). The grid and particle
            filters use the Poisson likelihood exactly; the Kalman-type filters replace
            it by ``N(λ(x), diag λ(x̂⁻))`` and say so in the run's warnings.
        """
        return cls._of(drift, rate, diffusion, {"kind": "poisson"})

    @classmethod
    def student_t(
        cls,
        drift: Union[str, Sequence[str]],
        observation: Union[str, Sequence[str]],
        dof: Union[float, str],
        scale: Union[float, str],
        diffusion: Optional[ArrayLike] = None,
    ) -> "Model":
        """``z_{k,j} = h_j(x_k) + scale · t_j``, ``t_j`` Student's t with ``dof`` degrees of
        freedom: measurement noise with heavy tails (outliers).

        Parameters
        ----------
        dof, scale : float or str
            ν > 0 and σ > 0 (numbers, or expressions in the scenario's parameters). The
            Kalman-type filters need ν > 2 (a variance) and then use ``N(h, σ²ν/(ν−2))``.
        """
        return cls._of(
            drift, observation, diffusion, {"kind": "student_t", "dof": dof, "scale": scale}
        )

    @classmethod
    def heteroscedastic(
        cls,
        drift: Union[str, Sequence[str]],
        observation: Union[str, Sequence[str]],
        variance: Union[str, Sequence[str]],
        diffusion: Optional[ArrayLike] = None,
    ) -> "Model":
        """``z_{k,j} ~ N(h_j(x_k), s_j(x_k))``: Gaussian measurement noise whose variance is
        an expression in the state — stochastic volatility with ``observation="0"`` and
        ``variance="exp(x)"``.

        Parameters
        ----------
        variance : str or list of str
            s(x), one expression per observation component, positive wherever a filter
            evaluates it.
        """
        return cls._of(
            drift,
            observation,
            diffusion,
            {"kind": "heteroscedastic", "variance": _strings(variance, "variance")},
        )

    @classmethod
    def log_density(
        cls,
        drift: Union[str, Sequence[str]],
        observation: Union[str, Sequence[str]],
        log_density: str,
        diffusion: Optional[ArrayLike] = None,
    ) -> "Model":
        """Measurements with ``log p(z | x)`` given as one expression in the state (``x``
        or ``x1 … xn``) and the measurement (``z`` or ``z1 … zm``), e.g. Laplace noise
        ``"-abs(z - x)/b - log(2*b)"``.

        Only the grid and particle filters take it (the others raise
        :class:`~zakai.errors.FilterError` saying why), it cannot be simulated (give
        observations), and a measurement must be whole or wholly missing. The observation
        h (one expression per measurement component) fixes m and is what the run's
        innovations compare against.
        """
        return cls._of(
            drift, observation, diffusion, {"kind": "log_density", "expression": log_density}
        )

    @classmethod
    def discrete_time(
        cls,
        transition: Union[str, Sequence[str]],
        observation: Union[str, Sequence[str]],
        transition_cov: ArrayLike,
        noise_cov: ArrayLike,
    ) -> "Model":
        """A map from one observation time to the next, as FilterPy, statsmodels and
        ``particles`` write models: ``x_k = F(x_(k−1), t_k, u_k) + w_k``, ``w_k ~ N(0, Q)``,
        one transition per ``dt_obs``, measured as ``z_k = h(x_k) + v_k``,
        ``v_k ~ N(0, R)``. For another measurement density, build it with
        :meth:`poisson`, :meth:`heteroscedastic`, … and call :meth:`in_discrete_time`.

        The Kalman and Gaussian-sum filters are exact for a linear F, the particle filter
        draws from the transition, the EKF/UKF/IEKF/IOKF predict through F, ``"point_mass"``
        carries the exact density on a grid; the Yau–Yau, spectral, direct and Fokker–Planck
        methods refuse the model (they solve continuous-time equations).

        Parameters
        ----------
        transition : str or list of str
            F, one expression per state component (it may read ``t``, the time the
            transition reaches, and known inputs).
        observation : str or list of str
            h, one expression per measurement component.
        transition_cov : array_like
            Q (n × n, symmetric positive semidefinite; a scalar when n = 1).
        noise_cov : array_like
            R (m × m; a scalar when m = 1).

        >>> import zakai
        >>> ar1 = zakai.Model.discrete_time("0.9*x", "x", transition_cov=0.5, noise_cov=1.0)
        >>> ar1.config["dynamics"]
        'discrete'
        """
        return cls.discrete(transition, observation, noise_cov).in_discrete_time(transition_cov)

    def in_discrete_time(
        self,
        transition_cov: Optional[ArrayLike] = None,
        transition_mixture: Optional[Iterable[tuple[float, ArrayLike, ArrayLike]]] = None,
    ) -> "Model":
        """The same model read in discrete time: its drift as the map F of
        ``x_k = F(x_(k−1), t_k, u_k) + w_k`` and its diffusion G as the factor of
        ``w_k ~ N(0, G Gᵀ)``, one transition per ``dt_obs`` (the scenario's
        ``"dynamics": "discrete"``). ``transition_cov`` gives Q instead of G (numbers; G
        becomes its symmetric square root).

        ``transition_mixture`` gives ``w_k ~ Σ_j π_j N(μ_j, Q_j)`` instead, as
        ``(weight, mean, cov)`` triples (jumps, outliers in the signal): the particle,
        point-mass and Gaussian-sum filters carry the mixture itself; the Kalman, EKF, UKF,
        IEKF and IOKF filters its mean and covariance, and say so in their warnings.

        >>> import zakai
        >>> jumps = zakai.Model.discrete("0.8*x", "x", noise_cov=0.5).in_discrete_time(
        ...     transition_mixture=[(0.8, [0.0], [[0.1]]), (0.2, [1.5], [[2.0]])])
        >>> len(jumps.config["transition_noise"])
        2
        """
        config = {**self.config, "dynamics": "discrete"}
        if transition_mixture is not None:
            if transition_cov is not None:
                raise ConfigError("give transition_cov or transition_mixture, not both")
            config.pop("diffusion", None)
            config["transition_noise"] = _mixture_components(transition_mixture, "transition_mixture")
        if transition_cov is not None:
            config.pop("transition_noise", None)
            try:
                q = np.array(_matrix(transition_cov, "transition_cov"), dtype=float)
            except (TypeError, ValueError):
                raise ConfigError(
                    "transition_cov: Q must be numbers (for expressions, give G as diffusion= "
                    "and call in_discrete_time())"
                ) from None
            if not np.all(np.isfinite(q)) or not np.allclose(q, q.T):
                raise ConfigError("transition_cov: Q must be finite and symmetric")
            values, vectors = np.linalg.eigh(q)
            if values.min() < -1e-12 * max(1.0, float(np.abs(q).max())):
                raise ConfigError(
                    f"transition_cov: Q must be positive semidefinite (eigenvalue {values.min():.3g})"
                )
            g = vectors @ np.diag(np.sqrt(np.clip(values, 0.0, None))) @ vectors.T
            config["diffusion"] = g.tolist()
        return Model(config)

    def with_inputs(self, *inputs: str) -> "Model":
        """The same model driven by known inputs ``u1 … uk``: its expressions may then read
        them and the time ``t`` (``"-x + 2*u1"``). Each argument is the input as an
        expression in ``t``, the series a simulated run records (and :func:`zakai.simulate`
        returns with ``with_inputs=True``); recorded data bring their own (``inputs=`` of
        :func:`zakai.filter`), so ``"0"`` will do when you only filter. The EKF, UKF,
        particle and grid filters hold each row's inputs over its interval; methods whose
        operator is made once (Kalman–Bucy, spectral, superposition, direct, Gaussian sum,
        IEKF/IOKF) refuse a driven model and say why.

        >>> import zakai
        >>> m = zakai.Model.discrete("-x + 2*u1", "x", noise_cov=0.1).with_inputs("sin(t)")
        >>> m.config["inputs"]
        ['sin(t)']
        """
        return Model({**self.config, "inputs": _strings(list(inputs), "inputs")})

    @classmethod
    def _of(cls, drift: Any, observation: Any, diffusion: Any, noise: dict) -> "Model":
        """The model of these texts, diffusion and noise block (of the scenario JSON), its
        expressions' syntax checked at once (the names, which may be parameters of a
        scenario yet to be built, are checked by :class:`Scenario`)."""
        model = cls(
            {
                "drift": _strings(drift, "drift"),
                "observation": _strings(observation, "observation"),
                "diffusion": None if diffusion is None else _matrix(diffusion, "diffusion"),
                "noise": noise,
            }
        )
        model._check_syntax()
        return model

    def _check_syntax(self) -> None:
        """An :class:`ExpressionError` for every expression that does not parse (an unclosed
        bracket, ``**`` for ``^``), with its field and position."""
        n = len(self.config["drift"])
        _check_syntax(
            self.config,
            {
                "kind": "gaussian",
                "mean": [0.0] * n,
                "cov": [[1.0 if i == j else 0.0 for j in range(n)] for i in range(n)],
            },
            n,
        )


def _check_syntax(model: dict[str, Any], prior: dict[str, Any], n: int) -> None:
    """The syntax errors of a model and prior, checked inside a scenario of their own (on
    [−1, 1]ⁿ, with the UKF), as one :class:`ExpressionError` with every field and position;
    other problems — names, which may be a scenario's parameters, dimensions — are the
    :class:`Scenario`'s to report."""
    probe = {
        "name": "probe",
        "model": model,
        "prior": prior,
        "domain": [[-1.0, 1.0]] * n,
        "time": {"t_final": 1.0, "dt_obs": 1.0, "inner_steps": 1},
        "methods": [{"method": "ukf"}],
    }
    try:
        _zakai.check_scenario(_json.dumps(probe))
    except ZakaiError as e:
        syntax = [(f, m) for f, m in e.problems if "syntax error" in m]
        if syntax:
            error = ExpressionError("; ".join(f"{f}: {m}" for f, m in syntax))
            error.problems = syntax
            raise error from None


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
        """Σ wᵢ N(meanᵢ, covᵢ) from ``(weight, mean, cov)`` triples (weights normalised:
        nonnegative and finite, not all zero)."""
        return cls({"kind": "mixture", "components": _mixture_components(components, "prior")})

    @classmethod
    def density(cls, expression: str) -> "Prior":
        """An unnormalised density as text, restricted to the domain (give one). Its syntax
        is checked at once (:class:`ExpressionError` with the position); its names, against
        the model's state and the scenario's parameters, by :class:`Scenario`."""
        if not isinstance(expression, str):
            raise ConfigError(f"prior density: an expression as text, not {type(expression).__name__}")
        prior = {"kind": "density", "expression": expression}
        # Syntax alone: a 1-D probe model (the state's names are the scenario's to check).
        _check_syntax(
            {"drift": ["0"], "observation": ["0"], "diffusion": None,
             "noise": {"kind": "continuous", "cov": [[1.0]]}},
            prior,
            1,
        )
        return cls(prior)

    def covering_domain(self, sds: float = DOMAIN_SDS) -> Optional[list[list[float]]]:
        """``mean ± sds·sd`` per component (every mixture component covered), or ``None``
        for a density prior."""
        return _zakai.covering_domain(_json.dumps(self.config), float(sds))


def _mixture_components(components: Iterable[tuple[float, ArrayLike, ArrayLike]], what: str) -> list:
    """``(weight, mean, cov)`` triples as a scenario's mixture components, checked: weights
    nonnegative and finite with a positive sum, covariances positive definite."""
    components = list(components)
    if not components:
        raise ConfigError(f"{what} components: needs at least one (weight, mean, cov)")
    weights = []
    for i, (w, _, _) in enumerate(components):
        try:
            weights.append(float(w))
        except (TypeError, ValueError):
            raise ConfigError(f"{what} component {i} weight: a number, not {w!r}") from None
    bad = [i for i, w in enumerate(weights) if not (np.isfinite(w) and w >= 0)]
    if bad:
        raise ConfigError(
            f"{what} component {bad[0]} weight: must be nonnegative and finite, got {weights[bad[0]]}"
        )
    total = sum(weights)
    if not total > 0 or not np.isfinite(total):
        raise ConfigError(f"{what} components: the weights must have a positive finite sum, got {total}")
    return [
        {
            "weight": float(w),
            "mean": _vector(m, f"{what} component {i} mean"),
            "cov": _positive_definite(_matrix(c, f"{what} component {i} cov"), f"{what} component {i} cov"),
        }
        for i, (w, m, c) in enumerate(components)
    ]
