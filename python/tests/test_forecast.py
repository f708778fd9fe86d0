"""Forecasts with intervals: the Kalman filter's against statsmodels' on the Nile, a grid
filter's and a particle filter's beside it, counts, pandas indexes, bad input."""

import numpy as np
import pandas as pd
import pytest

import zakai
from data import nile
from zakai.errors import ConfigError, FilterError

PRIOR = (1120.0, 1e7)
# The local level's variances near their maximum-likelihood values (test_fit.py).
Q, R = 1469.1, 15098.5



def local_level(methods=("kalman",), **params):
    model = zakai.Model.discrete("0", "x", noise_cov=R, diffusion=float(np.sqrt(Q)))
    return zakai.Scenario(
        model,
        zakai.Prior.gaussian(*PRIOR),
        list(methods),
        dt_obs=1.0,
        domain=[(-2000, 4000)],
        **params,
    )


def test_the_kalman_forecast_is_statsmodels_get_forecast(sm):
    years, flow = nile(sm)
    ours = zakai.forecast(local_level(), flow, 10, times=years)
    mod = sm.tsa.UnobservedComponents(flow, "llevel")
    mod.ssm.initialize_known(np.array([PRIOR[0]]), np.array([[PRIOR[1]]]))
    theirs = mod.filter([R, Q]).get_forecast(10)
    ci = np.asarray(theirs.conf_int(alpha=0.05))
    assert ours.observation_interval.shape == (10, 2)
    np.testing.assert_allclose(ours.observation_interval, ci, rtol=1e-7)
    np.testing.assert_allclose(ours.observation_mean, theirs.predicted_mean, rtol=1e-9)
    np.testing.assert_allclose(ours.observation_sd, np.sqrt(theirs.var_pred_mean), rtol=1e-9)
    np.testing.assert_array_equal(ours.times, 1970.0 + np.arange(1, 11))
    # The level's own interval is narrower by the measurement noise: sd² = P, not P + r.
    np.testing.assert_allclose(ours.state_sd**2 + R, ours.observation_sd**2, rtol=1e-9)
    frame = ours.to_pandas()
    assert list(frame.columns[:4]) == ["x1 mean", "x1 sd", "x1 lower", "x1 upper"]
    np.testing.assert_allclose(frame["z1 upper"].to_numpy(), ci[:, 1], rtol=1e-7)


def test_a_grid_and_a_particle_forecast_agree_with_the_kalman_one(sm):
    years, flow = nile(sm)
    sc = local_level(("kalman", "separation", {"method": "pf", "particles": 20000}), seed=4)
    kalman = zakai.forecast(sc, flow, 5, times=years, method="kalman")
    grid = zakai.forecast(sc, flow, 5, times=years, method="separation")
    cloud = zakai.forecast(sc, flow, 5, times=years, method="pf")
    assert grid.method != kalman.method != cloud.method
    width = kalman.observation_interval[:, 1] - kalman.observation_interval[:, 0]
    # The grid filter solves the same model on 945 cells of 6.3 (its chosen defaults): its
    # intervals (quantiles of the node masses spread over their cells) within a tenth of a
    # cell (0.04 and 0.13 here); the particle filter's within its Monte Carlo error with
    # 20 000 particles (1.2 here, 0.2 % of the interval's width).
    cell = 6000.0 / 945
    assert np.max(np.abs(grid.observation_interval - kalman.observation_interval)) < 0.1 * cell
    assert np.max(np.abs(grid.state_interval - kalman.state_interval)) < 0.1 * cell
    assert np.max(np.abs(cloud.observation_interval - kalman.observation_interval)) < 0.005 * width[0]


def test_a_forecast_continues_the_data_s_pandas_index(sm):
    years, flow = nile(sm)
    series = pd.Series(flow, index=pd.period_range("1871", periods=len(flow), freq="Y"))
    f = zakai.forecast(local_level(), series, 3)
    frame = f.to_pandas()
    assert [str(p) for p in frame.index] == ["1971", "1972", "1973"]
    dated = pd.Series(flow, index=pd.date_range("1871-01-01", periods=len(flow), freq="YS"))
    frame = zakai.forecast(local_level(), dated, 2).to_pandas()
    assert list(frame.index) == [pd.Timestamp("1971-01-01"), pd.Timestamp("1972-01-01")]
    # Irregular dates read in years: the forecast's dates a year apart after the last.
    gappy = pd.Series([1120.0, 1160.0, 1010.0],
                      index=pd.to_datetime(["1871-07-01", "1873-07-01", "1874-07-01"]))
    frame = zakai.forecast(local_level(), gappy, 2, time_unit="Y").to_pandas()
    assert list(frame.index) == [pd.Timestamp("1875-07-01"), pd.Timestamp("1876-07-01")]
    html = f._repr_html_()
    assert "<table>" in html and "1971" in html
    assert len(repr(f)) < 200


def test_filter_forecast_leaves_the_filter_and_gives_densities():
    model = zakai.Model.continuous("-x", "x", diffusion=0.6, noise_cov=0.5)
    f = zakai.Filter("qiem", model, zakai.Prior.gaussian(1.0, 0.2), dt_obs=0.05, points=[401])
    f.step([0.04])
    before, var = f.mean.copy(), float(f.cov[0, 0])
    ahead = f.forecast(20, level=0.9)
    np.testing.assert_array_equal(f.mean, before)
    assert ahead.observing == "increment"
    # dx = −x dt + 0.6 dv (Ornstein–Uhlenbeck): the mean decays as e^{−t}, the variance
    # as v e^{−2t} + 0.18 (1 − e^{−2t}) — within the implicit scheme's O(Δt) error.
    t = ahead.times
    np.testing.assert_allclose(ahead.state_mean, before[0] * np.exp(-t), rtol=2e-3)
    decay = np.exp(-2 * t)
    np.testing.assert_allclose(ahead.state_sd**2, var * decay + 0.18 * (1 - decay), rtol=5e-3)
    # The increment of y over a step: mean h(x) Δτ, spread mostly the noise's √(0.5 Δτ).
    np.testing.assert_allclose(ahead.observation_mean, ahead.state_mean * 0.05, rtol=1e-3)
    grid = np.linspace(-3, 3, 61)
    density = ahead.density(grid, step=-1)
    assert abs(np.trapezoid(density, grid) - 1.0) < 1e-3
    mean = np.trapezoid(grid * density, grid)
    assert mean == pytest.approx(ahead.state_mean[-1], abs=2e-3)


def test_counts_get_integer_intervals():
    model = zakai.Model.poisson("-0.5*x", "exp(x)", diffusion=0.3)
    sc = zakai.Scenario(
        model, zakai.Prior.gaussian(1.0, 0.1), [{"method": "pf", "particles": 5000}], dt_obs=1.0
    )
    f = zakai.forecast(sc, np.array([3.0, 2.0, 4.0, 1.0]), 4, level=0.8)
    assert f.count
    bounds = f.observation_interval
    np.testing.assert_array_equal(bounds, np.round(bounds))
    assert np.all(bounds[:, 0] <= f.observation_mean) and np.all(f.observation_mean <= bounds[:, 1])


def test_bad_forecasts_are_refused():
    sc = local_level()
    z = np.array([1100.0, 1050.0])
    with pytest.raises(ConfigError, match="level"):
        zakai.forecast(sc, z, 3, level=1.5)
    with pytest.raises(ConfigError, match="steps"):
        zakai.forecast(sc, z, 0)
    with pytest.raises(ConfigError, match="method"):
        zakai.forecast(sc, z, 3, method="ukf")
    with pytest.raises(ConfigError, match="dt"):
        zakai.forecast(sc, z, 3, dt=-1.0)
    logd = zakai.Model.log_density("0", "x", "-abs(z - x) - log(2)", diffusion=1.0)
    f = zakai.Filter("pf", logd, zakai.Prior.gaussian(0.0, 1.0), dt_obs=1.0)
    with pytest.raises(FilterError, match="log-density"):
        f.forecast(2)


def test_a_forecast_after_simulated_increments_continues_their_times():
    sc = zakai.Scenario.from_preset("cubic-sensor-1d")
    sc.methods = [{"method": "qiem", "points": [401]}, "ekf"]
    times, states, obs = zakai.simulate(sc, seed=3)
    f = zakai.forecast(sc, obs, 4, times=times, method="qiem")
    np.testing.assert_allclose(f.times, times[-1] + sc.dt_obs * np.arange(1, 5))
    assert f.observing == "increment" and f.method == "QIEM"
    grid = np.linspace(-4, 4, 161)
    assert abs(np.trapezoid(f.density(grid, step=0), grid) - 1.0) < 1e-2
    # The EKF's forecast from the same data: a Gaussian law, its interval symmetric.
    g = zakai.forecast(sc, obs, 4, times=times, method="ekf")
    centre = g.observation_interval.mean(axis=1)
    np.testing.assert_allclose(centre, g.observation_mean, atol=1e-12)
