"""Checks of a model on its data: the PIT and standardised innovations of each method's
one-step predictions against statsmodels on the Nile, uniform on data the model made, not
on a misspecified model; counts; the tests' p-values; bad requests."""

import numpy as np
import pytest

import zakai
from data import nile
from zakai.errors import ConfigError

PRIOR = (1120.0, 1e7)
Q, R = 1469.1, 15098.5



def level(r=R, methods=("kalman",)):
    model = zakai.Model.discrete("0", "x", noise_cov=r, diffusion=float(np.sqrt(Q)))
    return zakai.Scenario(model, zakai.Prior.gaussian(*PRIOR), list(methods), dt_obs=1.0,
                          domain=[(-2000, 4000)])


def test_the_kalman_checks_are_statsmodels_standardized_forecast_errors(sm):
    from math import erfc, sqrt

    years, flow = nile(sm)
    kf = zakai.filter(level(), flow, times=years, checks=True).methods["KF"]
    mod = sm.tsa.UnobservedComponents(flow, "llevel")
    mod.ssm.initialize_known(np.array([PRIOR[0]]), np.array([[PRIOR[1]]]))
    theirs = mod.filter([R, Q]).standardized_forecasts_error[0]
    ours = kf.standardized_innovations[:, 0]
    missing = np.isnan(flow)
    np.testing.assert_array_equal(np.isnan(ours), missing)
    np.testing.assert_allclose(ours[~missing], theirs[~missing], rtol=1e-8, atol=1e-10)
    phi = np.array([0.5 * erfc(-e / sqrt(2)) for e in theirs[~missing]])
    np.testing.assert_allclose(kf.pit[~missing, 0], phi, rtol=1e-8, atol=1e-12)
    # The innovation z − h(x̂⁻) is the forecast error itself for a linear model (the first
    # is 0: the Nile's 1871 flow is the prior's mean, 1120).
    scale = np.sqrt(mod.filter([R, Q]).forecasts_error_cov[0, 0, ~missing])
    np.testing.assert_allclose(kf.innovations[~missing, 0], ours[~missing] * scale,
                               rtol=1e-8, atol=1e-8)
    d = kf.diagnostics(lags=10)
    lb = sm.stats.acorr_ljungbox(theirs[~missing], lags=[10])
    assert d.rows[0]["ljung_box"] == pytest.approx(float(lb["lb_stat"].iloc[0]), rel=1e-9)
    assert d.rows[0]["ljung_box_p"] == pytest.approx(float(lb["lb_pvalue"].iloc[0]), rel=1e-6)
    assert d.rows[0]["count"] == int((~missing).sum())
    assert "Ljung–Box" in repr(d) and "<table>" in d._repr_html_()


def test_the_pit_is_uniform_on_the_model_s_own_data_and_not_on_a_misspecified_one():
    model = zakai.Model.discrete("-0.3*x", "x", noise_cov=0.5, diffusion=0.8)
    sc = zakai.Scenario(model, zakai.Prior.gaussian(0.0, 1.0), ["kalman", {"method": "pf", "particles": 2000}],
                        dt_obs=1.0, t_final=400.0, domain=[(-8, 8)], seed=11)
    times, states, z = zakai.simulate(sc)
    r = zakai.filter(sc, z, times=times, checks=True)
    for name in ("KF", "PF(2000)"):
        d = r.methods[name].diagnostics().rows[0]
        assert d["count"] == 401
        assert d["pit_ks_p"] > 0.05 and d["ljung_box_p"] > 0.05, (name, d)
    # The same data through a model whose measurements it believes ten times as precise:
    # predictive laws far too narrow, the PIT piled at 0 and 1.
    wrong = zakai.Model.discrete("-0.3*x", "x", noise_cov=0.05, diffusion=0.8)
    sc_wrong = zakai.Scenario(wrong, zakai.Prior.gaussian(0.0, 1.0), ["kalman"], dt_obs=1.0,
                              domain=[(-8, 8)])
    d = zakai.filter(sc_wrong, z, times=times, checks=True).methods["KF"].diagnostics().rows[0]
    assert d["pit_ks_p"] < 1e-4, d
    # A signal believed nearly still (G = 0.05 for 0.8): the filter lags behind it and its
    # one-step errors inherit the signal's persistence.
    still = zakai.Model.discrete("-0.3*x", "x", noise_cov=0.5, diffusion=0.05)
    sc_still = zakai.Scenario(still, zakai.Prior.gaussian(0.0, 1.0), ["kalman"], dt_obs=1.0,
                              domain=[(-8, 8)])
    d = zakai.filter(sc_still, z, times=times, checks=True).methods["KF"].diagnostics().rows[0]
    assert d["ljung_box_p"] < 1e-4, d


def test_counts_get_a_randomised_pit_that_is_uniform_on_their_own_data():
    model = zakai.Model.poisson("-0.2*x", "exp(x)", diffusion=0.4)
    sc = zakai.Scenario(model, zakai.Prior.gaussian(0.5, 0.2), ["separation"], dt_obs=1.0,
                        t_final=300.0, domain=[(-4, 4)], seed=5)
    times, _, z = zakai.simulate(sc)
    pit = zakai.filter(sc, z, times=times, checks=True).methods["separation"].pit[:, 0]
    assert np.all((pit > 0) & (pit < 1))
    # Counts take few values: without randomisation the PIT would pile on them.
    assert len(np.unique(np.round(pit, 6))) > 250
    d = zakai.filter(sc, z, times=times, checks=True).methods["separation"].diagnostics().rows[0]
    assert d["pit_ks_p"] > 0.05, d


def test_diagnostics_need_a_checked_run():
    sc = level()
    z = np.array([1100.0, 1050.0, 990.0])
    plain = zakai.filter(sc, z).methods["KF"]
    assert plain.pit is None and plain.standardized_innovations is None
    with pytest.raises(ConfigError, match="checks=True"):
        plain.diagnostics()
    with pytest.raises(ConfigError, match="checks"):
        zakai._zakai.filter_recorded(sc._text(), z.reshape(-1, 1), None, None, 1, True, None, True)
