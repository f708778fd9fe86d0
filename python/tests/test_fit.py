"""Fitting a model's parameters from Python: the Nile local level against statsmodels'
maximum-likelihood estimate (the same prior, the same gaps), profiles, executors (a process
pool and a Dask LocalCluster) giving the same numbers as every core, and bad input."""

from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pandas as pd
import pytest

import zakai
from data import nile
from zakai.errors import ConfigError


PRIOR = (1120.0, 1e7)



def local_level(methods=("kalman",)):
    """dx = √q dW, z = x + v with Var v = r: q and r the unknowns."""
    model = zakai.Model.discrete("0", "x", noise_cov="r", diffusion="sqrt(q)")
    return zakai.Scenario(
        model,
        zakai.Prior.gaussian(PRIOR[0], PRIOR[1]),
        list(methods),
        dt_obs=1.0,
        domain=[(-2000, 4000)],
        parameters={"q": (1000.0, (0, None)), "r": (10000.0, (0, None))},
    )


def test_the_kalman_fit_is_statsmodels_maximum_likelihood_estimate(sm):
    years, flow = nile(sm)
    # Zakai gets the year 1900 dropped (a step of two years); statsmodels has it missing.
    keep = years != 1900
    fitted = zakai.fit(local_level(), flow[keep], "kalman", times=years[keep])
    sm_flow = flow.copy()
    sm_flow[years == 1900] = np.nan
    mod = sm.tsa.UnobservedComponents(sm_flow, "llevel")
    mod.ssm.initialize_known(np.array([PRIOR[0]]), np.array([[PRIOR[1]]]))
    # The likelihood is flat near its top: statsmodels' default L-BFGS stops 8e-7 below it
    # (q = 1003.1), so its Nelder–Mead with tight tolerances is the reference.
    res = mod.fit(disp=False, method="nm", maxiter=5000, xtol=1e-10, ftol=1e-12)
    r_sm, q_sm = res.params  # sigma2.irregular, sigma2.level
    print(fitted)
    print("statsmodels", q_sm, r_sm, res.llf)
    assert fitted.params["q"] == pytest.approx(q_sm, rel=1e-3)
    assert fitted.params["r"] == pytest.approx(r_sm, rel=1e-3)
    # statsmodels leaves the first observation out of ln L (its burn-in of one state):
    # ln N(z_1871; 1120, 10⁷ + r) apart, the two likelihoods are the same function.
    s = PRIOR[1] + fitted.params["r"]
    first = -0.5 * (np.log(2 * np.pi * s) + (flow[0] - PRIOR[0]) ** 2 / s)
    same_point = mod.loglike([fitted.params["r"], fitted.params["q"]])
    assert fitted.loglik - first == pytest.approx(same_point, rel=1e-9)
    assert fitted.loglik - first >= res.llf - 1e-6
    # AIC and BIC: statsmodels' of its ln L (without the first observation) over its 99
    # effective observations; Zakai's ln L has that observation, and 99 rows (1900 dropped).
    assert fitted.aic + 2 * first == pytest.approx(res.aic, abs=1e-5)
    assert fitted.bic + 2 * first == pytest.approx(res.bic, abs=1e-5)
    assert fitted.nobs == 99 and res.nobs_effective == 99
    assert fitted.converged and not fitted.notes
    frame = fitted.to_pandas()
    assert list(frame.index) == ["q", "r"]
    assert (frame["ci_lower"] < frame["estimate"]).all()
    assert frame.loc["q", "lower"] == 0.0 and frame.loc["q", "upper"] is None
    # The Wald interval is computed on u = ln q and mapped back (issue 56, item 5): inside
    # q ≥ 0 (θ̂ − 1.96·se is negative here), and q̂·exp(±1.96·se/q̂) by the delta method.
    q, se = fitted.params["q"], fitted.stderr["q"]
    assert q - 1.96 * se < 0 < frame.loc["q", "ci_lower"]
    spread = np.exp(1.959963984540054 * se / q)
    assert frame.loc["q", "ci_lower"] == pytest.approx(q / spread, rel=1e-9)
    assert frame.loc["q", "ci_upper"] == pytest.approx(q * spread, rel=1e-9)


def test_fit_reads_a_pandas_series_and_a_grid_method(sm):
    years, flow = nile(sm)
    series = pd.Series(flow, index=years)
    fitted = zakai.fit(local_level(), series, "separation", params=["r"])
    exact = zakai.fit(local_level(), series, "kalman", params=["r"])
    assert fitted.method.startswith("SA") and list(fitted.params) == ["r"]
    # The grid filter's likelihood on its default grid: the estimate within a tenth of a
    # standard error of the exact one.
    assert abs(fitted.params["r"] - exact.params["r"]) < 0.1 * exact.stderr["r"]


def test_the_point_mass_fit_uses_its_score_and_lands_where_nelder_mead_does(sm):
    """The local level as a map x_k = x_(k−1) + w_k: the point-mass filter gives its score,
    so ``optimiser="auto"`` is L-BFGS; Nelder–Mead on the same likelihood lands within a
    hundredth of a standard error of it, and the Kalman filter's exact estimate (also by
    L-BFGS on its score) is within a tenth (the grid's resolution). L-BFGS on a method without
    a score (the UKF) is a ConfigError."""
    years, flow = nile(sm)
    series = pd.Series(flow, index=years)
    model = zakai.Model.discrete("x", "x", noise_cov="r", diffusion="sqrt(q)").in_discrete_time()
    scenario = zakai.Scenario(
        model,
        zakai.Prior.gaussian(PRIOR[0], PRIOR[1]),
        ["point_mass", "kalman"],
        dt_obs=1.0,
        domain=[(-2000, 4000)],
        parameters={"q": (1000.0, (0, None)), "r": (10000.0, (0, None))},
    )
    quasi_newton = zakai.fit(scenario, series, "point_mass")
    simplex = zakai.fit(scenario, series, "point_mass", optimiser="nelder-mead")
    exact = zakai.fit(scenario, series, "kalman")
    assert quasi_newton.optimiser == "L-BFGS" and quasi_newton.njev > 0
    assert simplex.optimiser == "Nelder–Mead" and simplex.njev == 0
    assert quasi_newton.converged and simplex.converged
    for name in ("q", "r"):
        se = quasi_newton.stderr[name]
        assert abs(quasi_newton.params[name] - simplex.params[name]) < 0.01 * se
        assert abs(quasi_newton.params[name] - exact.params[name]) < 0.1 * exact.stderr[name]
    assert "L-BFGS" in str(quasi_newton)
    assert exact.optimiser == "L-BFGS"
    with pytest.raises(ConfigError, match="gives no score"):
        zakai.fit(scenario, series, "ukf", optimiser="lbfgs")
    with pytest.raises(ValueError, match="optimiser must be"):
        zakai.fit(scenario, series, "kalman", optimiser="bfgs")


def test_a_profile_peaks_where_the_fit_does_for_one_parameter(sm):
    years, flow = nile(sm)
    sc = local_level(["kalman", "ukf"])
    sc.config["parameters"]["q"]["value"] = 1469.1
    p = zakai.profile(sc, flow, "r", np.linspace(8000, 25000, 35), times=years)
    one = zakai.fit(sc, flow, "kalman", params=["r"], times=years)
    assert set(p.loglik) == {"KF", "UKF"}
    x, _ = p.maxima["KF"]
    assert abs(x - one.params["r"]) < 0.05 * one.stderr["r"]
    frame = p.to_pandas()
    assert frame.index.name == "r" and frame.shape == (35, 2)
    # The same points by log_likelihood, one at a time.
    r0 = float(p.values[10])
    direct = zakai.log_likelihood(sc, flow, "kalman", times=years, r=r0)
    assert direct == pytest.approx(p.loglik["KF"][10], rel=1e-12)


def test_the_profile_likelihood_peaks_at_the_joint_fit(sm):
    years, flow = nile(sm)
    both = zakai.fit(local_level(), flow, "kalman", times=years)
    p = zakai.profile(local_level(), flow, "q", np.linspace(200, 5000, 25), refit=["r"], times=years)
    x, top = p.maxima["KF"]
    # The parabola through values 200 apart: q within a tenth of that, ln L within 0.005.
    assert abs(x - both.params["q"]) < 20 and abs(top - both.loglik) < 5e-3
    # Above the slice with r held at its start, everywhere.
    s = zakai.profile(local_level(), flow, "q", np.linspace(200, 5000, 25), times=years)
    assert (p.loglik["KF"] >= s.loglik["KF"] - 1e-9).all()


def test_an_executor_gives_the_same_fit_as_every_core(sm):
    years, flow = nile(sm)
    local = zakai.fit(local_level(), flow, "kalman", times=years)
    with ProcessPoolExecutor(max_workers=2) as pool:
        remote = zakai.fit(local_level(), flow, "kalman", times=years, executor=pool)
    assert remote.params == local.params and remote.nfev == local.nfev


def test_a_dask_cluster_spreads_a_profile(sm):
    distributed = pytest.importorskip("distributed")
    years, flow = nile(sm)
    sc = local_level(["kalman"])
    local = zakai.profile(sc, flow, "q", points=9, times=years)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            remote = zakai.profile(sc, flow, "q", points=9, times=years,
                                   executor=client.get_executor())
    np.testing.assert_array_equal(remote.values, local.values)
    np.testing.assert_array_equal(remote.loglik["KF"], local.loglik["KF"])


def test_a_monte_carlo_on_an_executor_is_the_same_table():
    sc = zakai.Scenario.from_preset("sa-example-1")
    local = zakai.monte_carlo(sc, runs=4, seed=2).to_pandas()
    with ProcessPoolExecutor(max_workers=2) as pool:
        remote = zakai.monte_carlo(sc, runs=4, seed=2, executor=pool).to_pandas()
    # The runs come back bit for bit: every number but the timings is the same.
    timing = [c for c in local.columns if "second" in c or c.startswith("ms")]
    pd.testing.assert_frame_equal(local.drop(columns=timing), remote.drop(columns=timing))
    assert "mse" in local.columns and local["mse"].notna().all()


def test_bad_input_is_refused_with_its_reason(sm):
    years, flow = nile(sm)
    with pytest.raises(ConfigError, match="no parameter `sigma`"):
        zakai.fit(local_level(), flow, "kalman", params=["sigma"], times=years)
    with pytest.raises(ConfigError, match="method"):
        zakai.fit(local_level(), flow, 5, times=years)
    with pytest.raises(ConfigError, match="executor"):
        zakai.fit(local_level(), flow, times=years, executor=object())
    with pytest.raises(ConfigError, match="executor"):
        zakai.monte_carlo(local_level(), runs=2, executor=object())
    with pytest.raises(ConfigError, match="points"):
        zakai.profile(local_level(), flow, "q", points=1, times=years)
    bad = local_level()
    bad.config["model"]["diffusion"] = [["sqrt(qq)"]]
    with pytest.raises(ConfigError, match=r"model.diffusion\[0\]\[0\]: unknown variable `qq` at position 5") as e:
        zakai.fit(bad, flow, times=years)
    assert "finite" not in str(e.value)


def test_a_profile_says_what_the_method_doubts_at_its_maximum(sm):
    """Issue 56: a profile carries the method's self-checks at its maximum. The separation
    approach on 200 cells of the prior's ±8 sd (253 units a cell against a posterior sd of
    about 50) says its grid is too coarse there; the Kalman filter says nothing."""
    years, flow = nile(sm)
    sc = local_level(["kalman", {"method": "separation", "cells": [200]}])
    sd = PRIOR[1] ** 0.5
    sc.config["domain"] = [[PRIOR[0] - 8 * sd, PRIOR[0] + 8 * sd]]
    p = zakai.profile(sc, flow, "q", np.linspace(500, 2500, 5), times=years)
    assert p.notes["KF"] == []
    assert any(n.startswith("at the maximum q = ") and "posterior width in grid cells" in n
               for n in next(v for k, v in p.notes.items() if k.startswith("SA"))), p.notes


def test_a_diffuse_prior_without_a_domain_gets_its_box_from_the_data(sm):
    """Issue 56, item 2: the Nile with a diffuse prior N(1120, 10⁷) and no domain. The box
    around the prior, ±8 sd = [−24 178, 26 418], left about 253 per cell of the SA's 200 for a
    posterior sd of about 50, and the fit ran off to q ≈ 10⁴ with no note; the measurements
    (456 to 1370, noise sd √r = 100) put the box at about [−150, 2000] and the fit within 5 %
    of the Kalman filter's q and r."""
    years, flow = nile(sm)
    model = zakai.Model.discrete("0", "x", noise_cov="r", diffusion="sqrt(q)")
    params = {"q": (1000.0, (0, None)), "r": (10000.0, (0, None))}
    sc = zakai.Scenario(model, zakai.Prior.gaussian(*PRIOR), ["kalman", "separation"],
                        dt_obs=1.0, parameters=params)
    assert sc.domain[0][1] - sc.domain[0][0] > 5e4, sc.domain
    kalman = zakai.fit(sc, flow, "kalman", times=years)
    grid = zakai.fit(sc, flow, "separation", times=years)
    assert grid.chosen_defaults[0].startswith("domain ["), grid.chosen_defaults
    lo, hi = (float(v) for v in grid.chosen_defaults[0][len("domain ["):].split("]")[0].split(","))
    assert -1000 < lo < 400 and 1400 < hi < 3000, (lo, hi)
    for name in ("q", "r"):
        assert abs(grid.params[name] / kalman.params[name] - 1) < 0.05, (grid.params, kalman.params)
    # The domain the user gives is kept as given.
    sc.domain = [(-24178.0, 26418.0)]
    run = zakai.filter(sc, flow, times=years)
    assert not any(c.startswith("domain [") for c in run.chosen_defaults)


def test_a_diffuse_prior_the_data_cannot_narrow_is_refused_with_give_a_domain():
    """Issue 56, item 2: where the measurements cannot narrow the prior's box (here continuous
    observations dy = x dt + dw of x' = −x + v) and the grid cannot resolve the posterior on it
    (N(0, 10⁸)'s ±8 sd is 1.6·10⁵ wide; the posterior sd to expect is about 1, and QIEM's 4001
    points put 0.03 in it), a run, a fit and a stepping filter refuse with "give a domain"; a
    given domain runs."""
    model = zakai.Model.continuous("-x", "x", noise_cov=1.0)
    prior = zakai.Prior.gaussian([0.0], [[1e8]])
    sc = zakai.Scenario(model, prior, ["qiem"], dt_obs=0.01, t_final=0.5)
    times, _, observations = zakai.simulate(sc, seed=3)
    with pytest.raises(zakai.ConfigError, match="give a domain"):
        zakai.filter(sc, observations, times=times)
    with pytest.raises(zakai.ConfigError, match="give a domain"):
        zakai.Filter("qiem", model, prior, dt_obs=0.01)
    zakai.Filter("ekf", model, prior, dt_obs=0.01)  # no grid: nothing to refuse
    sc.domain = [(-10.0, 10.0)]
    run = zakai.filter(sc, observations, times=times)
    assert run.methods["qiem"].estimates.shape[0] == observations.shape[0]


def test_the_likelihood_ratio_interval_is_where_statsmodels_profile_drops_by_the_level(sm):
    years, flow = nile(sm)
    fitted = zakai.fit(local_level(), flow, "kalman", times=years)
    lo, hi = fitted.profile_interval("r", level=0.95)
    assert lo < fitted.params["r"] < hi
    # statsmodels' profile of r: ln L maximised over q at r fixed (Nelder–Mead, tight).
    mod = sm.tsa.UnobservedComponents(flow, "llevel")
    mod.ssm.initialize_known(np.array([PRIOR[0]]), np.array([[PRIOR[1]]]))
    best = mod.fit(disp=False, method="nm", maxiter=5000, xtol=1e-10, ftol=1e-12).llf

    def drop(r):
        res = mod.fit_constrained({"sigma2.irregular": r}, disp=False, method="nm",
                                  maxiter=5000, xtol=1e-10, ftol=1e-12)
        return best - res.llf

    # ½ χ²₁(0.95) = 1.92: at both ends (statsmodels' ln L leaves out the first observation,
    # whose term moves by 10⁻⁴ over this range of r).
    for end in (lo, hi):
        assert drop(end) == pytest.approx(1.920729, abs=0.02), end
    # Skewed: further above θ̂ than below, which the symmetric-on-a-log-scale Wald interval
    # does not follow exactly.
    assert hi - fitted.params["r"] != pytest.approx(fitted.params["r"] - lo, rel=0.05)
    # q's likelihood is far from a parabola: the guide's numbers on the whole series, Wald
    # [266, 8107] against the likelihood-ratio [261, 5984].
    data = sm.datasets.nile.load_pandas().data
    whole = zakai.fit(local_level(), data["volume"].to_numpy(float), "kalman",
                      times=data["year"].to_numpy(float))
    assert whole.intervals["q"] == pytest.approx((266.2, 8107.3), rel=2e-3)
    assert whole.profile_interval("q") == pytest.approx((260.6, 5983.9), rel=5e-3)
    with pytest.raises(ConfigError, match="not fitted"):
        fitted.profile_interval("s")


def test_parameters_carry_priors_validated_with_their_field():
    model = zakai.Model.discrete("0", "x", noise_cov="r", diffusion="sqrt(q)")
    prior = zakai.Prior.gaussian(1120.0, 1e7)
    sc = zakai.Scenario(model, prior, ["kalman"], dt_obs=1.0,
                        parameters={"q": (1000.0, (0, None), ("lognormal", 7.0, 1.0)),
                                    "r": {"value": 1e4, "bounds": (1.0, 1e6), "prior": "uniform"}})
    assert sc.parameters["q"]["prior"] == {"kind": "lognormal", "mu": 7.0, "sigma": 1.0}
    assert sc.parameters["r"]["prior"] == {"kind": "uniform"}
    again = zakai.Scenario.from_json(sc.to_json())
    assert again.parameters == sc.parameters
    bad = [
        ({"q": (1000.0, (0, None), ("gamma", -1.0, 1.0)), "r": 1e4}, "parameters.q.prior.shape"),
        ({"q": (1000.0, (0, None), "uniform"), "r": 1e4}, "both be finite"),
        ({"q": (-5.0, None, ("lognormal", 0.0, 1.0)), "r": 1e4}, "parameters.q.value"),
        ({"q": (1000.0, (0, None), ("beta", 1.0)), "r": 1e4}, "beta takes 2"),
        ({"q": (1000.0, (0, None), ("cauchy", 0.0, 1.0)), "r": 1e4}, "kind one of"),
    ]
    for params, message in bad:
        with pytest.raises(ConfigError, match=message):
            zakai.Scenario(model, prior, ["kalman"], dt_obs=1.0, parameters=params)
