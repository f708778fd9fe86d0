"""Discrete-time models from Python, against FilterPy, which writes every model as a map:
Zakai's UKF on the growth model ``x_k = x/2 + 25x/(1 + x²) + 8 cos(1.2k) + w_k``,
``z_k = x_k²/20 + v_k`` (Kitagawa 1996) is FilterPy's ``UnscentedKalmanFilter`` with that
``fx`` (FilterPy's sigma points redrawn from the predicted moments before each update, as
Zakai draws them), and Zakai's Kalman and point-mass filters on a linear map with a gap are
FilterPy's ``KalmanFilter`` (the point-mass filter within its grid's error)."""

import numpy as np
import pytest

import zakai
from zakai.errors import ConfigError

ALPHA, BETA, KAPPA = 0.5, 2.0, 0.0


def growth(x, k):
    return x / 2 + 25 * x / (1 + x**2) + 8 * np.cos(1.2 * k)


def test_ukf_agrees_with_filterpy_on_the_growth_model():
    filterpy_kalman = pytest.importorskip("filterpy.kalman")
    model = zakai.Model.discrete_time(
        "x/2 + 25*x/(1 + x^2) + 8*cos(1.2*t)", "x^2/20", transition_cov=10.0, noise_cov=1.0
    )
    ours = zakai.Filter(
        "ukf", model, zakai.Prior.gaussian(0.0, 5.0), dt_obs=1.0, alpha=ALPHA, beta=BETA, kappa=KAPPA
    )
    points = filterpy_kalman.MerweScaledSigmaPoints(1, alpha=ALPHA, beta=BETA, kappa=KAPPA)
    clock = {"k": 0}
    theirs = filterpy_kalman.UnscentedKalmanFilter(
        dim_x=1, dim_z=1, dt=1.0, fx=lambda x, dt: growth(x, clock["k"]),
        hx=lambda x: x**2 / 20, points=points,
    )
    theirs.x, theirs.P = np.array([0.0]), np.array([[5.0]])
    theirs.Q, theirs.R = np.array([[10.0]]), np.array([[1.0]])
    rng = np.random.default_rng(5)
    x, worst = rng.normal(0.0, np.sqrt(5.0)), 0.0
    for k in range(1, 41):
        x = growth(x, k) + rng.normal(0.0, np.sqrt(10.0))
        z = x**2 / 20 + rng.normal()
        clock["k"] = k
        theirs.predict()
        theirs.sigmas_f = points.sigma_points(theirs.x, theirs.P)
        theirs.update(np.array([z]))
        ours.step([z], 1.0, t=float(k), u=[])
        p = theirs.P[0, 0]
        worst = max(worst, abs(ours.mean[0] - theirs.x[0]) / np.sqrt(p), abs(ours.cov[0, 0] / p - 1))
    # Same arithmetic up to summation order, through 40 steps of a map that stretches
    # differences: agreement to rounding, relative to the filter's own sd and variance.
    print(f"worst relative difference {worst:.2e}")
    assert worst < 1e-9, worst


def test_kalman_and_point_mass_agree_with_filterpy_on_a_linear_map_with_a_gap():
    filterpy_kalman = pytest.importorskip("filterpy.kalman")
    model = zakai.Model.discrete_time("0.9*x", "x", transition_cov=0.5, noise_cov=1.0)
    prior = zakai.Prior.gaussian(0.0, 1.0)
    kalman = zakai.Filter("kalman", model, prior, dt_obs=1.0)
    grid = zakai.Filter("point_mass", model, prior, dt_obs=1.0, domain=[(-8.0, 14.0)], cells=[400])
    theirs = filterpy_kalman.KalmanFilter(dim_x=1, dim_z=1)
    theirs.x, theirs.P = np.array([0.0]), np.array([[1.0]])
    theirs.F, theirs.Q, theirs.H, theirs.R = (np.array([[v]]) for v in (0.9, 0.5, 1.0, 1.0))
    rows = [(1, 0.4), (1, 1.1), (3, 3.9), (1, np.nan), (2, 5.6), (1, 6.3)]
    worst_kalman = worst_grid = 0.0
    for transitions, z in rows:
        for _ in range(transitions):
            theirs.predict()
        if not np.isnan(z):
            theirs.update(np.array([z]))
        for f in (kalman, grid):
            f.step([z], float(transitions))
        sd = np.sqrt(theirs.P[0, 0])
        worst_kalman = max(worst_kalman, abs(kalman.mean[0] - theirs.x[0]) / sd)
        worst_grid = max(worst_grid, abs(grid.mean[0] - theirs.x[0]) / sd)
    print(f"Kalman {worst_kalman:.2e} sd, point mass {worst_grid:.2e} sd")
    assert worst_kalman < 1e-9
    # 400 cells of width 0.055 for a posterior sd near 0.7: measured 5.8e-4 sd in Rust's test.
    assert worst_grid < 2e-3
    with pytest.raises(zakai.errors.FilterError, match="not a whole number"):
        kalman.step([1.0], 0.5)


def test_a_discrete_time_scenario_refuses_the_continuous_time_methods():
    model = zakai.Model.discrete_time("0.9*x", "x", transition_cov=0.5, noise_cov=1.0)
    sc = zakai.Scenario(model, zakai.Prior.gaussian(0.0, 1.0), ["qiem", "point_mass", "pf"],
                        dt_obs=1.0, t_final=20.0, domain=[(-8.0, 8.0)])
    times, states, obs = zakai.simulate(sc, seed=2)
    with pytest.warns(zakai.FilterWarning, match="QIEM failed at row 0"):
        r = zakai.filter(sc, obs, times=times, truth=states)
    row, _, why = r.methods["QIEM"].failure
    assert row == 0 and "continuous time" in why
    assert r.methods["point_mass"].failure is None and r.methods["pf"].failure is None
    with pytest.raises(ConfigError, match="positive semidefinite"):
        zakai.Model.discrete_time("x", "x", transition_cov=-1.0, noise_cov=1.0)


def test_a_mixture_transition_noise_is_carried_by_the_gaussian_sum_filter():
    """Jumps in the signal, ``w_k ~ 0.8 N(0, 0.1) + 0.2 N(1.5, 2)``, on ``x_k = 0.8 x + w_k``
    seen in N(0, 0.5) noise: the Gaussian-sum filter (no pruning, a cap above the 2⁵
    components of five transitions) is the exact mixture recursion written here in NumPy;
    the point-mass filter is within its grid's error of it; the UKF, which takes the
    mixture's mean and variance only, says so."""
    jumps = [(0.8, 0.0, 0.1), (0.2, 1.5, 2.0)]
    model = zakai.Model.discrete("0.8*x", "x", noise_cov=0.5).in_discrete_time(
        transition_mixture=[(w, [m], [[q]]) for w, m, q in jumps]
    )
    prior = zakai.Prior.gaussian(0.0, 1.0)
    gsf = zakai.Filter("gaussian_sum", model, prior, dt_obs=1.0, max_components=64, prune=0.0, merge_cost=0.0)
    grid = zakai.Filter("point_mass", model, prior, dt_obs=1.0, domain=[(-8.0, 16.0)], cells=[800])
    ukf = zakai.Filter("ukf", model, prior, dt_obs=1.0)
    w, m, p = np.array([1.0]), np.array([0.0]), np.array([1.0])
    for z in [0.3, 2.1, -0.4, 1.2, 3.4]:
        w = np.concatenate([w * pi for pi, _, _ in jumps])
        m = np.concatenate([0.8 * m + mu for _, mu, _ in jumps])
        p = np.concatenate([0.64 * p + q for _, _, q in jumps])
        s = p + 0.5
        w = w * np.exp(-0.5 * (z - m) ** 2 / s) / np.sqrt(2 * np.pi * s)
        w, k = w / w.sum(), p / s
        m, p = m + k * (z - m), (1 - k) * p
        mean = float(w @ m)
        var = float(w @ (p + (m - mean) ** 2))
        for f in (gsf, grid, ukf):
            f.step([z], 1.0)
        assert abs(gsf.mean[0] - mean) < 1e-9 and abs(gsf.cov[0, 0] - var) < 1e-9
        assert abs(grid.mean[0] - mean) < 2e-3 * np.sqrt(var)
    assert any("Gaussian mixture" in warning for warning in ukf.warnings)


def test_transition_mixture_and_cov_are_given_once():
    with pytest.raises(ConfigError, match="not both"):
        zakai.Model.discrete("0.8*x", "x", noise_cov=0.5).in_discrete_time(
            transition_cov=1.0, transition_mixture=[(1.0, [0.0], [[1.0]])]
        )
    with pytest.raises(ConfigError, match="weight"):
        zakai.Model.discrete("0.8*x", "x", noise_cov=0.5).in_discrete_time(
            transition_mixture=[(-1.0, [0.0], [[1.0]])]
        )
