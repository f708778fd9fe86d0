"""The stepping filter: :class:`Filter`, one method you step, predict, update and fork."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Optional, Sequence

import numpy as np

from . import _zakai
from .errors import ConfigError, FilterError
from ._convert import ArrayLike, _array
from .models import Model, Prior
from .scenario import Scenario

if TYPE_CHECKING:
    from .forecasting import Forecast



def _drive(t: Optional[float], u: Optional[ArrayLike]) -> tuple:
    """A driven model's step time and inputs as the core takes them."""
    if t is None:
        if u is not None:
            raise ConfigError("u: a driven model's inputs come with the step's time t (t=..., u=...)")
        return (None, None)
    return (float(t), [] if u is None else [float(v) for v in _array(u, "u").ravel()])


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
        The box of grid and spectral methods; ``prior mean ± 8 sd`` when absent, refused
        (:class:`ConfigError`) when a grid method's grid cannot resolve the posterior to expect
        on it (a diffuse prior with sharp measurements).
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


    # A misspelt or FilterPy-style attribute (``f.x = …``) raises AttributeError instead of
    # being accepted and ignored.
    __slots__ = ("scenario", "_inner", "_at_prior", "_seed", "_log")

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
        # A box set around the prior that the grid cannot resolve the posterior on is refused
        # here: a stepping filter sees no data to narrow it with.
        if domain is None:
            _zakai.refuse_coarse_prior_box(scenario._text())
        self.scenario = scenario
        self._inner = _zakai.Stepper(scenario._text(), int(seed))
        # Whether the filter is still at the prior's time (no step taken yet).
        self._at_prior = True
        # The seed and every call that moved the filter, for pickling (see __reduce__).
        self._seed = int(seed)
        self._log: Optional[list[tuple[Any, ...]]] = []

    @classmethod
    def _wrap(cls, scenario: Scenario, inner: Any) -> "Filter":
        """A Filter around a stepper already past the prior (a forecast's origin)."""
        f = cls.__new__(cls)
        f.scenario = scenario
        f._inner = inner
        f._at_prior = False
        # Its past is a run's, not calls of its own: it has nothing to replay.
        f._seed = None
        f._log = None
        return f

    def _record(self, call: tuple[Any, ...]) -> None:
        """Notes a call that moved the filter (after it succeeded)."""
        if self._log is not None:
            self._log.append(call)

    @classmethod
    def _restore(cls, text: str, seed: int, log: list[tuple[Any, ...]], at_prior: bool) -> "Filter":
        """A pickled filter: built again from its scenario and seed, its calls replayed (every
        method is deterministic given its seed, so its state is the one pickled, to the bit)."""
        f = cls.__new__(cls)
        f.scenario = Scenario.from_json(text)
        f._inner = _zakai.Stepper(text, seed)
        f._seed = seed
        f._log = []
        for name, *args in log:
            if name == "run!":
                try:
                    f._inner.run(*args)
                except FilterError:
                    pass
            else:
                getattr(f._inner, name)(*args)
            f._log.append((name, *args))
        f._at_prior = at_prior
        return f

    def forecast(
        self, steps: int, dt: Optional[float] = None, level: float = 0.95
    ) -> "Forecast":
        """The predictive distributions of the state and of the observations ``dt``,
        ``2 dt``, … ``steps · dt`` ahead (Δτ when ``dt`` is absent), with central intervals of
        probability ``level``, from a copy: the filter itself does not move. See
        :class:`Forecast` for what each method's laws are.

        Examples
        --------
        >>> import zakai
        >>> model = zakai.Model.discrete("0", "x", noise_cov=0.3, diffusion=0.5)
        >>> f = zakai.Filter("kalman", model, zakai.Prior.gaussian(0.0, 1.0), dt_obs=1.0)
        >>> f.update([0.4])
        >>> ahead = f.forecast(2)
        >>> round(float(ahead.observation_sd[0] ** 2), 6)  # 0.3/1.3 + 0.25 + 0.3: P + q + r
        0.780769
        """
        from .forecasting import Forecast

        if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)):
            raise ConfigError(f"steps: must be a whole number (got {steps!r})")
        step = self._dt(dt)
        raw = self._inner.forecast(int(steps), step, float(level))
        return Forecast(raw, start=0.0, dt=step, level=level, origin=self.copy())

    def _dt(self, dt: Optional[float]) -> float:
        if dt is None:
            return self.scenario.dt_obs
        if not isinstance(dt, (int, float, np.integer, np.floating)):
            raise ConfigError(f"dt: must be a number of time units (got {type(dt).__name__})")
        return float(dt)

    def step(
        self,
        observation: ArrayLike,
        dt: Optional[float] = None,
        *,
        t: Optional[float] = None,
        u: Optional[ArrayLike] = None,
    ) -> None:
        """Predicts over ``dt`` (Δτ when absent) and assimilates one observation: the
        increment dy for continuous models, the measurement z for discrete ones (``dt = 0``
        assimilates at the current time). NaN components are missing: only the observed
        ones are used, and an all-NaN observation is a prediction only. A driven model
        (:meth:`Model.with_inputs`) needs the observation's time ``t`` and the known inputs
        ``u`` over the interval that ends at it. A step that fails raises
        :class:`FilterError` and leaves the filter as it was."""
        args = (_array(observation, "observation"), self._dt(dt), *_drive(t, u))
        self._inner.step(*args)
        self._record(("step", *args))
        self._at_prior = False

    def predict(
        self,
        dt: Optional[float] = None,
        *,
        t: Optional[float] = None,
        u: Optional[ArrayLike] = None,
    ) -> None:
        """Predicts over ``dt`` (Δτ when absent) without an observation: a gap in the data,
        or a forecast (on a :meth:`copy`, to keep the filter itself at the present). A driven
        model needs the time ``t`` it predicts to and the inputs ``u`` held until then."""
        args = (self._dt(dt), *_drive(t, u))
        self._inner.predict(*args)
        self._record(("predict", *args))
        self._at_prior = False

    def update(self, z: ArrayLike) -> None:
        """Assimilates the measurement ``z`` at the current time, without predicting
        (discrete models; NaN components are missing)."""
        z = _array(z, "z")
        self._inner.update(z)
        self._record(("update", z))
        self._at_prior = False

    @property
    def log_likelihood(self) -> Optional[float]:
        """ln p(y_k | y_1:k−1) of the last step's observation given the ones before it: 0
        when it observed nothing (a gap, every component missing); summed over the steps,
        the log-likelihood of the data (see :attr:`MethodResult.log_likelihood` for what is
        exact and what approximate). For continuous observations, against Wiener measure."""
        return self._inner.log_likelihood

    def copy(self) -> "Filter":
        """An independent copy of the filter in its current state: stepping one does not
        move the other (e.g. to forecast from here)."""
        twin = Filter.__new__(Filter)
        twin.scenario = self.scenario.copy()
        twin._inner = self._inner.fork()
        twin._at_prior = self._at_prior
        twin._seed = self._seed
        twin._log = None if self._log is None else list(self._log)
        return twin

    def __copy__(self) -> "Filter":
        return self.copy()

    def __deepcopy__(self, memo: dict[int, Any]) -> "Filter":
        return self.copy()

    def __reduce__(self) -> Any:
        """Pickles the filter as its scenario, its seed and the calls that moved it: unpickled,
        it is built again and the calls replayed, so it holds the state pickled (every method
        is deterministic given its seed) and steps on identically. Unpickling costs the
        replay's time; the pickle grows with the observations the filter has seen."""
        if self._log is None:
            raise TypeError(
                "this zakai.Filter is a forecast's origin, the state a whole run left: it "
                "cannot be pickled; pickle the scenario and the observations instead"
            )
        return (Filter._restore, (self.scenario._text(), self._seed, list(self._log), self._at_prior))

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
        try:
            result = self._inner.run(obs, steps)
        except FilterError:
            # The rows before the one that failed were taken: a replay fails at the same row.
            self._record(("run!", obs, steps))
            raise
        self._record(("run", obs, steps))
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

    @property
    def footprint(self) -> Optional[dict[str, Any]]:
        """How a compressed density is held (the tensor-train filter): ``numbers`` stored,
        ``grid_points`` of the full grid they stand for, ``ranks`` (r₀ … r_d) now and
        ``peak_ranks``, the largest each has been; ``None`` for the other methods."""
        return self._inner.footprint

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
