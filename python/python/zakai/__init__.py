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

The package mirrors the Rust side: :mod:`zakai.models` (``Model``, ``Prior``),
:mod:`zakai.scenario` (``Scenario``, presets, the method catalogue), :mod:`zakai.runs`
(``simulate``, ``run``, ``filter``, ``smooth``, ``monte_carlo``), :mod:`zakai.fitting` (``fit``,
``profile``, ``log_likelihood``: a scenario's parameters from your data), :mod:`zakai.forecasting`
(``forecast``, ``Forecast``: predictive intervals of states and observations), :mod:`zakai.results` (``RunResult``,
``MethodResult``, ``Smoothed``, ``MonteCarloTable``), :mod:`zakai.stepping` (the stepping ``Filter``) and
:mod:`zakai.errors`; everything is also here, at the top.
"""

from __future__ import annotations

from . import _zakai
from ._convert import ArrayLike, MethodSpec
from .fitting import FitResult, Profile, fit, log_likelihood, profile
from .posterior import Posterior, sample
from .forecasting import Forecast, forecast
from .errors import (
    ConfigError,
    DimensionError,
    ExpressionError,
    FilterError,
    FilterWarning,
    ZakaiError,
)
from .models import DOMAIN_SDS, Model, Prior
from .results import MethodResult, MonteCarloTable, RunResult, Smoothed
from .runs import filter, monte_carlo, run, simulate, smooth
from .scenario import Scenario, methods, noise_kinds, presets, set_memory_cap
from .stepping import Filter

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
    "noise_kinds",
    "simulate",
    "run",
    "filter",
    "smooth",
    "Smoothed",
    "monte_carlo",
    "fit",
    "profile",
    "log_likelihood",
    "forecast",
    "Forecast",
    "FitResult",
    "Profile",
    "set_memory_cap",
    "ZakaiError",
    "ConfigError",
    "ExpressionError",
    "DimensionError",
    "FilterError",
    "FilterWarning",
]
