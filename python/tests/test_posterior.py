"""Posteriors of a scenario's parameters (issue 64): the Nile's Kalman posterior against a
grid posterior of statsmodels' exact local-level likelihood; the draws as pandas and ArviZ;
an executor draws the same chains; bad requests are refused before any run."""

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import zakai
from data import nile
from zakai.errors import ConfigError

PRIOR = (1120.0, 1e7)
BOX = {"q": (0.0, 10_000.0), "r": (0.0, 40_000.0)}


def local_level(methods=("kalman",), box=BOX, priors=None):
    """dx = √q dW, z = x + v with Var v = r, q and r in ``box`` (uniform priors unless
    ``priors`` gives others)."""
    priors = priors or {}
    model = zakai.Model.discrete("0", "x", noise_cov="r", diffusion="sqrt(q)")
    return zakai.Scenario(
        model,
        zakai.Prior.gaussian(PRIOR[0], PRIOR[1]),
        list(methods),
        dt_obs=1.0,
        domain=[(-2000, 4000)],
        parameters={
            n: (v, box[n], priors[n]) if n in priors else (v, box[n])
            for n, v in (("q", 1000.0), ("r", 10000.0))
        },
    )


def test_the_nile_posterior_is_the_grid_posterior_of_statsmodels_likelihood(sm):
    """Random-walk Metropolis on the Kalman likelihood (4 chains × 2000 draws) against the
    posterior on a 120² grid of statsmodels' local-level log-likelihood (known initial state
    N(1120, 10⁷); its first observation's term, left out by statsmodels, added back), under
    uniform priors on [0, 10⁴] × [0, 4·10⁴]: each mean within 4 Monte Carlo standard errors,
    and the grid's CDF at each 5 %/95 % quantile of the draws within 4 √(p(1 − p)/ESS_tail)."""
    years, flow = nile(sm)
    post = zakai.sample(local_level(), flow, "kalman", times=years, draws=2000, warmup=1000, seed=3)
    mod = sm.tsa.UnobservedComponents(flow, "llevel")
    mod.ssm.initialize_known(np.array([PRIOR[0]]), np.array([[PRIOR[1]]]))
    cells = 120
    q = (np.arange(cells) + 0.5) * BOX["q"][1] / cells
    r = (np.arange(cells) + 0.5) * BOX["r"][1] / cells
    ll = np.empty((cells, cells))
    for i, qi in enumerate(q):
        for j, rj in enumerate(r):
            s = PRIOR[1] + rj
            first = -0.5 * (np.log(2 * np.pi * s) + (flow[0] - PRIOR[0]) ** 2 / s)
            ll[i, j] = mod.loglike([rj, qi]) + first
    w = np.exp(ll - ll.max())
    w /= w.sum()
    summary = post.summary()
    assert (summary["r_hat"] < 1.01).all() and (summary["ess_bulk"] > 400).all(), summary
    for name, x, marginal in (("q", q, w.sum(axis=1)), ("r", r, w.sum(axis=0))):
        row = summary.loc[name]
        mean = float(x @ marginal)
        assert abs(row["mean"] - mean) < 4 * row["mcse"], (name, row["mean"], mean)
        width = x[1] - x[0]
        cdf = np.concatenate([[0.0], np.cumsum(marginal)])
        edges = np.concatenate([x - width / 2, [x[-1] + width / 2]])
        for p, value in ((0.05, row["q5"]), (0.95, row["q95"])):
            at = np.interp(value, edges, cdf)
            assert abs(at - p) < 4 * np.sqrt(p * (1 - p) / row["ess_tail"]), (name, p, at)


def test_the_draws_are_a_frame_with_a_summary_an_arviz_view_and_a_plot(sm):
    years, flow = nile(sm)
    sc = local_level(box={"q": (0.0, None), "r": (0.0, 40_000.0)},
                     priors={"q": ("lognormal", 7.0, 2.0)})
    post = zakai.sample(sc, flow, times=years, draws=300, warmup=300, seed=1)
    assert post.sampler == "adaptive random-walk Metropolis"
    assert list(post.draws.columns) == ["chain", "draw", "q", "r", "lp", "loglik"]
    assert len(post.draws) == 4 * 300 and post.chains == 4
    assert post.values("q").shape == (4, 300)
    summary = post.summary()
    assert summary.loc["q", "mean"] == pytest.approx(post.draws["q"].mean(), rel=1e-12)
    assert summary.loc["r", "median"] == pytest.approx(post.draws["r"].median(), rel=1e-12)
    assert "maximum-likelihood estimate" in post.notes[0]
    assert post.priors["q"] == {"kind": "lognormal", "mu": 7.0, "sigma": 2.0, "bounds": (0.0, np.inf)}
    assert post.priors["r"]["kind"] == "uniform"
    # The prior's density restricted to the bounds: uniform 1/40 000 on r, and the
    # log-normal's own on q (its whole support).
    assert post.prior_density("r", [5.0, 50_000.0]) == pytest.approx([2.5e-5, 0.0])
    x = 1000.0
    ln = np.exp(-(np.log(x) - 7.0) ** 2 / 8.0) / (x * 2.0 * np.sqrt(2 * np.pi))
    assert post.prior_density("q", x) == pytest.approx(ln, rel=1e-12)
    assert np.all(post.draws["lp"] > post.draws["loglik"] - 30)
    idata = post.to_arviz()
    assert idata.posterior["q"].shape == (4, 300)
    assert float(idata.posterior["r"].mean()) == pytest.approx(summary.loc["r", "mean"], rel=1e-12)
    assert "Posterior" in repr(post) and "<table>" in post._repr_html_()
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    fig = post.plot()
    assert len(fig.axes) == 4


def test_pmmh_on_an_executor_draws_the_same_chains():
    """Particle marginal Metropolis–Hastings draws a fresh seed per proposal: the executor's
    workers, given those seeds, return the same likelihood estimates, so the chains are the
    same draw for draw."""
    model = zakai.Model.discrete("-a*x", "x", noise_cov=0.3)
    sc = zakai.Scenario(model, zakai.Prior.gaussian(0.0, 0.5), [{"method": "pf", "particles": 200}],
                        dt_obs=0.5, domain=[(-4, 4)], parameters={"a": (1.0, (0.1, 4.0))})
    z = np.sin(np.arange(30) / 4.0)
    here = zakai.sample(sc, z, draws=60, warmup=40, chains=2, seed=5, start_from_fit=False)
    assert here.sampler == "particle marginal Metropolis–Hastings"
    with ThreadPoolExecutor(2) as pool:
        there = zakai.sample(sc, z, draws=60, warmup=40, chains=2, seed=5, start_from_fit=False,
                             executor=pool)
    np.testing.assert_array_equal(here.draws["a"].to_numpy(), there.draws["a"].to_numpy())
    # Common random numbers: said to be biased.
    common = zakai.sample(sc, z, draws=60, warmup=40, chains=2, seed=5, start_from_fit=False,
                          common_random_numbers=True)
    assert any("not the exact posterior" in n for n in common.notes)
    # Correlated pseudo-marginal steps: in this process only, and not with common numbers.
    correlated = zakai.sample(sc, z, draws=60, warmup=40, chains=2, seed=5,
                              start_from_fit=False, correlation=0.99)
    assert correlated.sampler == "correlated pseudo-marginal Metropolis–Hastings"
    assert not any("not the exact posterior" in n for n in correlated.notes)
    with ThreadPoolExecutor(2) as pool, pytest.raises(ConfigError, match="cannot supply"):
        zakai.sample(sc, z, draws=60, warmup=40, seed=5, start_from_fit=False,
                     correlation=0.99, executor=pool)
    with pytest.raises(ConfigError, match="correlation"):
        zakai.sample(sc, z, correlation=0.99, common_random_numbers=True)
    with pytest.raises(ConfigError, match="correlation"):
        zakai.sample(sc, z, correlation=1.0)


def test_delayed_acceptance_screens_with_a_cheaper_method(sm):
    """A surrogate (here the UKF, the Kalman filter's equal on this linear model) screens the
    proposals: said in the notes, and the draws summarised as usual."""
    years, flow = nile(sm)
    post = zakai.sample(local_level(), flow, "kalman", times=years, draws=300, warmup=300,
                        seed=2, surrogate="ukf")
    assert any(n.startswith("delayed acceptance") for n in post.notes), post.notes
    assert post.summary().loc["q", "mean"] > 0
    with pytest.raises(ConfigError, match="surrogate"):
        zakai.sample(local_level(), flow, "kalman", times=years, surrogate="ukf",
                     sampler="langevin")


def test_bad_requests_are_refused_before_any_run(sm):
    years, flow = nile(sm)
    open_box = local_level(box={"q": (0.0, None), "r": (0.0, None)})
    with pytest.raises(ConfigError, match="parameters.q.prior"):
        zakai.sample(open_box, flow, times=years)
    with pytest.raises(ConfigError, match="chains"):
        zakai.sample(local_level(), flow, times=years, chains=0)
    with pytest.raises(ConfigError, match="draws"):
        zakai.sample(local_level(), flow, times=years, draws=-1)
    with pytest.raises(ValueError, match="sampler"):
        zakai.sample(local_level(), flow, times=years, sampler="nuts")
