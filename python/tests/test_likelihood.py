"""The data's log-likelihood from Python: every method's total and per-step terms on a
recorded series with gaps and an irregular step, against a Kalman log-likelihood written here,
and the stepping filter's per-step value."""

import numpy as np
import pytest

import zakai
from test_real_data import flow_series, local_level


def kalman_log_likelihood(z, times, q=400.0, r=400.0, m=1000.0, p=400.0):
    """ln p(z_1..z_N) of the local-level model, by a scalar Kalman filter written here:
    per observed step ln N(z_k; m, P + R) with m and P predicted."""
    total = 0.0
    for k, zk in enumerate(z):
        if k:
            p += q * (times[k] - times[k - 1])
        if np.isnan(zk):
            continue
        s = p + r
        total += -0.5 * ((zk - m) ** 2 / s + np.log(2 * np.pi * s))
        gain = p / s
        m += gain * (zk - m)
        p *= 1 - gain
    return total


def test_every_method_reports_the_log_likelihood_of_recorded_data():
    years, z = flow_series()
    sc = local_level(["kalman", "ukf", "gaussian_sum", {"method": "separation", "cells": [1600]}])
    sc.domain = [(600, 1600)]
    result = zakai.filter(sc, z, times=years - years[0])
    exact = kalman_log_likelihood(z, years - years[0])
    for name, m in result.methods.items():
        assert m.failure is None, f"{name}: {m.failure}"
        assert m.log_likelihoods.shape == (len(z),)
        # The total is the per-step terms' sum; missing years add nothing.
        np.testing.assert_allclose(m.log_likelihood, m.log_likelihoods.sum(), rtol=1e-12)
        assert m.log_likelihoods[5] == 0.0 and m.log_likelihoods[6] == 0.0
    np.testing.assert_allclose(result.methods["KF"].log_likelihood, exact, rtol=1e-9)
    np.testing.assert_allclose(result.methods["GSF"].log_likelihood, exact, rtol=1e-9)
    np.testing.assert_allclose(result.methods["UKF"].log_likelihood, exact, rtol=1e-9)
    grid = [m for n, m in result.methods.items() if n.startswith("SA")][0]
    # The grid filter's normaliser on 1600 cells of [600, 1600]: within 5e-3 of −131 (measured
    # 2.3e-3). Tight enough to catch a misplaced prior: from N(1010, 400) (the mean half a
    # prior sd off) or N(1000, 800) (the variance doubled) the exact value moves by 1.35 and
    # 2.28, and the grid filter's falls outside the tolerance.
    assert abs(grid.log_likelihood - exact) < 5e-3, (grid.log_likelihood, exact)
    model = zakai.Model.discrete("0", "x", noise_cov=400.0, diffusion=20.0)
    for wrong in [(1010.0, 400.0), (1000.0, 800.0)]:
        sc = zakai.Scenario(
            model, zakai.Prior.gaussian(*wrong), [{"method": "separation", "cells": [1600]}],
            dt_obs=1.0, domain=[(600, 1600)],
        )
        off = zakai.filter(sc, z, times=years - years[0]).methods["SA"].log_likelihood
        assert abs(off - exact) > 5e-3, (wrong, off, exact)
        assert abs(off - kalman_log_likelihood(z, years - years[0], m=wrong[0], p=wrong[1])) < 5e-3
    frame = result.to_pandas()
    assert "KF loglik" in frame.columns


def test_the_stepping_filter_gives_each_steps_term():
    years, z = flow_series()
    times = years - years[0]
    model = zakai.Model.discrete("0", "x", noise_cov=400.0, diffusion=20.0)
    f = zakai.Filter("kalman", model, zakai.Prior.gaussian(1000.0, 400.0), dt_obs=1.0)
    terms = []
    for k, zk in enumerate(z):
        f.step([zk], dt=0.0 if k == 0 else times[k] - times[k - 1])
        terms.append(f.log_likelihood)
    np.testing.assert_allclose(sum(terms), kalman_log_likelihood(z, times), rtol=1e-9)
    assert terms[5] == 0.0


def test_log_likelihood_without_keywords_is_the_scenario_as_it_stands():
    """Issue 56, item 2: without parameter keywords, ``log_likelihood`` evaluates the scenario
    at its own values (it returned -inf), and a scenario that declares no parameter has a
    likelihood too (it raised "declares no parameter to fit"); a method that fails on the
    data gives -inf with a FilterWarning naming the failure."""
    years, z = flow_series()
    times = years - years[0]
    exact = kalman_log_likelihood(z, times)
    model = zakai.Model.discrete("0", "x", noise_cov=400.0, diffusion=20.0)
    plain = zakai.Scenario(model, zakai.Prior.gaussian(1000.0, 400.0), ["kalman"], dt_obs=1.0)
    np.testing.assert_allclose(zakai.log_likelihood(plain, z, "kalman", times=times), exact, rtol=1e-9)
    unknowns = zakai.Model.discrete("0", "x", noise_cov="r", diffusion="sqrt(q)")
    declared = zakai.Scenario(
        unknowns, zakai.Prior.gaussian(1000.0, 400.0), ["kalman"], dt_obs=1.0,
        parameters={"q": (400.0, (0, None)), "r": (400.0, (0, None))},
    )
    np.testing.assert_allclose(zakai.log_likelihood(declared, z, "kalman", times=times), exact, rtol=1e-9)
    np.testing.assert_allclose(
        zakai.log_likelihood(declared, z, "kalman", times=times, q=900.0),
        kalman_log_likelihood(z, times, q=900.0),
        rtol=1e-9,
    )
    counts = zakai.Model.poisson("0", "exp(x)", diffusion=0.1)
    poisson = zakai.Scenario(
        counts, zakai.Prior.gaussian(0.0, 1.0), [{"method": "separation", "cells": [200]}],
        dt_obs=1.0, domain=[(-4.0, 4.0)],
    )
    with pytest.warns(zakai.FilterWarning, match="SA"):
        value = zakai.log_likelihood(poisson, np.array([1.0, 2.0, 2.5]), "separation")
    assert value == -np.inf
