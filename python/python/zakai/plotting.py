"""Figures of results (matplotlib, an optional dependency imported only here): what the
``.plot()`` methods of :class:`RunResult`, :class:`MethodResult`, :class:`Forecast`,
:class:`Profile` and :class:`Diagnostics` draw. Each returns the matplotlib Figure."""

from __future__ import annotations

from statistics import NormalDist
from typing import Any, Optional, Sequence

import numpy as np


def _pyplot() -> Any:
    try:
        import matplotlib.pyplot as plt
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError("plots need matplotlib (pip install matplotlib)") from e
    return plt


def run(result: Any, dim: int = 0, methods: Optional[Sequence[str]] = None) -> Any:
    """The estimates of component ``dim`` with ±2σ bands, the truth when known, and the
    observations below (a continuous model's path y(t) = Σ Δy)."""
    plt = _pyplot()
    fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(9, 6),
                                      gridspec_kw={"height_ratios": [3, 1]})
    t = result.times
    if result.truth is not None:
        top.plot(t, result.truth[:, dim], color="black", lw=1.5, label="truth")
    for key, m in result.methods.items():
        if methods is not None and key not in methods and m.key not in methods:
            continue
        _estimate(top, t, m, dim, key)
    top.set_ylabel(f"x{dim + 1}")
    top.legend(loc="best", fontsize="small")
    obs = result.observations
    if result.continuous:
        path = np.nancumsum(np.nan_to_num(obs, nan=0.0), axis=0)
        path[np.isnan(obs)] = np.nan
        bottom.plot(t, path, lw=1)
        bottom.set_ylabel("y")
    else:
        bottom.plot(t, obs, ".", ms=3)
        bottom.set_ylabel("z")
    bottom.set_xlabel("t")
    fig.tight_layout()
    return fig


def _estimate(ax: Any, t: np.ndarray, m: Any, dim: int, label: str) -> None:
    line, = ax.plot(t, m.estimates[:, dim], lw=1.2, label=label)
    sds = m.sds
    if sds is not None:
        lo = m.estimates[:, dim] - 2 * sds[:, dim]
        hi = m.estimates[:, dim] + 2 * sds[:, dim]
        ax.fill_between(t, lo, hi, color=line.get_color(), alpha=0.15, lw=0)


def method(m: Any, times: np.ndarray, dim: int = 0) -> Any:
    """One method's estimates of component ``dim`` with ±2σ bands, and beneath, when the run
    kept them, its marginal densities over time as a heat strip (each column the density
    after that row, scaled to its own maximum, as the playground's)."""
    plt = _pyplot()
    strip = m.densities is not None and m.density_grid is not None
    if strip:
        fig, (ax, heat) = plt.subplots(2, 1, sharex=True, figsize=(9, 6),
                                       gridspec_kw={"height_ratios": [1, 1]})
    else:
        fig, ax = plt.subplots(figsize=(9, 4))
    _estimate(ax, times, m, dim, m.name)
    ax.set_ylabel(f"x{dim + 1}")
    ax.legend(loc="best", fontsize="small")
    if strip:
        d = np.nan_to_num(m.densities, nan=0.0)
        top = d.max(axis=1, keepdims=True)
        scaled = np.divide(d, top, out=np.zeros_like(d), where=top > 0)
        grid = m.density_grid
        heat.pcolormesh(times, grid, scaled.T, shading="nearest", cmap="viridis")
        heat.set_ylabel(f"x{m.density_dim + 1}")
        heat.set_title("p / max p over time", fontsize="small")
        heat.set_xlabel("t")
    else:
        ax.set_xlabel("t")
    fig.tight_layout()
    return fig


def diagnostics(d: Any, component: int = 1) -> Any:
    """The 2 × 2 figure of a method's checks (statsmodels' ``plot_diagnostics`` with the PIT
    histogram in place of the residuals'): the standardised innovations over the rows, the
    PIT's histogram against the uniform, the innovations' normal Q-Q plot, and their
    correlogram with ±1.96/√n."""
    plt = _pyplot()
    j = component - 1
    e = d.standardized[:, j]
    pit = d.pit[:, j]
    seen = np.isfinite(e)
    fig, ax = plt.subplots(2, 2, figsize=(10, 7))
    ax[0, 0].plot(np.flatnonzero(seen), e[seen], lw=0.8)
    ax[0, 0].axhline(0, color="gray", lw=0.5)
    ax[0, 0].set_title("standardised innovations")
    ax[0, 1].hist(pit[np.isfinite(pit)], bins=10, range=(0, 1), density=True, alpha=0.7)
    ax[0, 1].axhline(1, color="black", lw=1)
    row = d.rows[j]
    p = row["pit_ks_p"]
    ax[0, 1].set_title("PIT histogram" + ("" if p is None else f" (uniform: p = {p:.3g})"))
    x = np.sort(e[seen])
    n = len(x)
    if n:
        normal = NormalDist()
        q = np.array([normal.inv_cdf((i + 0.5) / n) for i in range(n)])
        ax[1, 0].plot(q, x, ".", ms=3)
        ax[1, 0].plot(q, q, color="black", lw=1)
    ax[1, 0].set_title("normal Q-Q")
    lags = int(row["lags"])
    if n > lags + 1:
        centred = e[seen] - e[seen].mean()
        c0 = float(centred @ centred)
        r = [float(centred[k:] @ centred[:-k]) / c0 for k in range(1, lags + 1)]
        ax[1, 1].bar(range(1, lags + 1), r, width=0.4)
        ax[1, 1].axhline(1.96 / np.sqrt(n), color="gray", ls="--", lw=0.8)
        ax[1, 1].axhline(-1.96 / np.sqrt(n), color="gray", ls="--", lw=0.8)
    lb = row["ljung_box_p"]
    ax[1, 1].set_title("correlogram" + ("" if lb is None else f" (Ljung–Box: p = {lb:.3g})"))
    fig.suptitle(f"{d.method}: checks of z{component}")
    fig.tight_layout()
    return fig


def forecast(f: Any) -> Any:
    """The forecast fan: the state's and the observation's predictive means and central
    intervals over the steps ahead."""
    plt = _pyplot()
    fig, axes = plt.subplots(2, 1, sharex=True, figsize=(9, 6))
    t = f.times
    for ax, mean, interval, label in (
        (axes[0], f.state_mean, f.state_interval, "x"),
        (axes[1], f.observation_mean, f.observation_interval,
         "Δy" if f.observing == "increment" else "z"),
    ):
        mean = mean.reshape(len(t), -1)
        interval = interval.reshape(len(t), mean.shape[1], 2)
        for j in range(mean.shape[1]):
            line, = ax.plot(t, mean[:, j], lw=1.2, label=f"{label}{j + 1} mean")
            ax.fill_between(t, interval[:, j, 0], interval[:, j, 1], color=line.get_color(),
                            alpha=0.2, lw=0, label=f"{f.level:.0%} interval")
        ax.set_ylabel(label)
        ax.legend(loc="best", fontsize="small")
    axes[1].set_xlabel("t")
    fig.suptitle(f"forecast by {f.method}")
    fig.tight_layout()
    return fig


def profile(p: Any, level: float = 0.95) -> Any:
    """ln L along the parameter per method, each maximum marked and the likelihood-ratio
    interval's level drawn: ln L(θ*) − ½ χ²₁(level) (a horizontal line per method)."""
    plt = _pyplot()
    half = 0.5 * NormalDist().inv_cdf(0.5 + level / 2) ** 2
    fig, ax = plt.subplots(figsize=(8, 5))
    for name, ll in p.loglik.items():
        line, = ax.plot(p.values, ll, lw=1.2, label=name)
        best = p.maxima.get(name)
        if best is not None:
            ax.plot([best[0]], [best[1]], "o", color=line.get_color())
            ax.axhline(best[1] - half, color=line.get_color(), ls=":", lw=0.8)
    ax.set_xlabel(p.parameter)
    ax.set_ylabel("ln L")
    ax.set_title(f"ln L along {p.parameter} (dotted: the {level:.0%} likelihood-ratio level)")
    ax.legend(loc="best", fontsize="small")
    fig.tight_layout()
    return fig


def fit(f: Any, names: Optional[Sequence[str]] = None, points: int = 21, level: float = 0.95) -> Any:
    """Each fitted parameter's profile log-likelihood around θ̂ (the others refitted at each
    value, :func:`zakai.profile`), with θ̂, the Wald interval shaded and the likelihood-ratio
    level ``ln L(θ̂) − ½ χ²₁(level)`` dotted: where the two intervals differ, the likelihood is
    not the parabola the Wald interval assumes."""
    from .fitting import profile

    plt = _pyplot()
    if f._source is None:
        from .errors import ConfigError

        raise ConfigError("plot: this FitResult does not come from zakai.fit")
    names = list(names or f.params)
    sc, obs, times, time_unit, seed, inputs = f._source
    at_fit = sc.copy()
    at_fit.parameters = {
        n: ((f.params[n] if n in f.params else spec["value"]), tuple(spec.get("bounds", (None, None))))
        for n, spec in sc.parameters.items()
    }
    half = 0.5 * NormalDist().inv_cdf(0.5 + level / 2) ** 2
    fig, axes = plt.subplots(1, len(names), figsize=(4.5 * len(names), 4), squeeze=False)
    for ax, name in zip(axes[0], names):
        theta = f.params[name]
        lo, hi = f.intervals.get(name, (np.nan, np.nan))
        if not (np.isfinite(lo) and np.isfinite(hi)):
            lo, hi = theta - (abs(theta) or 1.0), theta + (abs(theta) or 1.0)
        a, b = f.bounds[name]
        left, right = theta - 1.5 * (theta - lo), theta + 1.5 * (hi - theta)
        if a is not None:
            left = max(left, a + 0.01 * (theta - a))
        if b is not None:
            right = min(right, b - 0.01 * (b - theta))
        values = np.linspace(left, right, points)
        others = [n for n in f.params if n != name]
        p = profile(at_fit, obs, name, values=values, refit=others or None, times=times,
                    time_unit=time_unit, seed=seed, inputs=inputs)
        ax.plot(values, next(iter(p.loglik.values())), lw=1.2)
        ax.axvline(theta, color="black", lw=0.8)
        ax.axvspan(*f.intervals.get(name, (theta, theta)), color="gray", alpha=0.15,
                   label=f"Wald {level:.0%}")
        ax.axhline(f.loglik - half, color="gray", ls=":", lw=1, label=f"LR {level:.0%} level")
        ax.set_xlabel(name)
        ax.set_ylabel("profile ln L")
        ax.legend(loc="lower center", fontsize="small")
    fig.suptitle(f"fit by {f.method}: ln L = {f.loglik:.6g}")
    fig.tight_layout()
    return fig


def posterior(p: Any) -> Any:
    """A :class:`~zakai.Posterior`: for each parameter its chains' traces (left) and the
    histogram of all draws as a density with the prior's density over it (right)."""
    plt = _pyplot()
    n = len(p.names)
    fig, axes = plt.subplots(n, 2, figsize=(10, 2.6 * n), squeeze=False)
    for i, name in enumerate(p.names):
        values = p.values(name)
        trace, marginal = axes[i]
        for c, chain in enumerate(values):
            trace.plot(chain, lw=0.6, alpha=0.8, label=f"chain {c}")
        trace.set_ylabel(name)
        trace.set_xlabel("draw")
        marginal.hist(values.ravel(), bins=40, density=True, alpha=0.5, label="posterior draws")
        x = np.linspace(values.min(), values.max(), 200)
        marginal.plot(x, p.prior_density(name, x), "k--", label="prior")
        marginal.set_xlabel(name)
        marginal.set_ylabel("density")
    axes[0][1].legend()
    fig.suptitle(f"Posterior under {p.method} ({p.sampler})")
    fig.tight_layout()
    return fig
