"""Zakai's UKF against FilterPy's on a discrete-time problem: the same numbers.

The model is a random walk measured through a nonlinear h (z = x³ + v in 1-D; two nonlinear
sensors in 2-D): Zakai's continuous–discrete prediction is then exactly P ← P + GGᵀΔτ, which
FilterPy does with fx = identity and Q = GGᵀΔτ. FilterPy updates with the propagated sigma
points of the *previous* covariance; Zakai (like Särkkä's continuous–discrete UKF) draws them
from the predicted (m, P), so the FilterPy side redraws them before every update (also the
first, at the prior's time, which FilterPy would make with its unset sigma points).
"""

import numpy as np
import pytest

import zakai

ALPHA, BETA, KAPPA = 0.5, 2.0, 0.0


def _filterpy_ukf(filterpy_kalman, x0, p0, q, r, dt, hx, dim_z):
    n = len(x0)
    points = filterpy_kalman.MerweScaledSigmaPoints(n, alpha=ALPHA, beta=BETA, kappa=KAPPA)
    ukf = filterpy_kalman.UnscentedKalmanFilter(
        dim_x=n, dim_z=dim_z, dt=dt, fx=lambda x, dt: x, hx=hx, points=points
    )
    ukf.x, ukf.P, ukf.Q, ukf.R = np.array(x0, float), np.array(p0, float), q, r
    return ukf, points


CASES = {
    "cubic 1-D": dict(
        drift=["0"], observation=["x^3"], g=np.array([[0.7]]), r=np.array([[0.1]]),
        x0=[0.5], p0=[[1.0]], hx=lambda x: x**3,
    ),
    "two sensors 2-D": dict(
        drift=["0", "0"], observation=["x1 + x2^2", "sin(x1)"],
        g=np.array([[0.3, 0.0], [0.1, 0.4]]), r=np.array([[0.2, 0.05], [0.05, 0.1]]),
        x0=[0.3, -0.2], p0=[[0.5, 0.1], [0.1, 0.4]],
        hx=lambda x: np.array([x[0] + x[1] ** 2, np.sin(x[0])]),
    ),
}


@pytest.mark.parametrize("case", CASES)
def test_ukf_agrees_with_filterpy(case):
    filterpy_kalman = pytest.importorskip("filterpy.kalman")
    c = CASES[case]
    dt, steps = 0.1, 60
    model = zakai.Model.discrete(c["drift"], c["observation"], noise_cov=c["r"], diffusion=c["g"])
    prior = zakai.Prior.gaussian(c["x0"], c["p0"])
    ours = zakai.Filter("ukf", model, prior, dt_obs=dt, alpha=ALPHA, beta=BETA, kappa=KAPPA, substeps=1)

    rng = np.random.default_rng(11)
    n, m = len(c["x0"]), len(c["observation"])
    q = c["g"] @ c["g"].T * dt
    ukf, points = _filterpy_ukf(filterpy_kalman, c["x0"], c["p0"], q, c["r"], dt, c["hx"], m)
    x = rng.multivariate_normal(c["x0"], c["p0"])
    worst = 0.0
    for k in range(steps + 1):
        if k > 0:
            x = x + c["g"] @ rng.standard_normal(n) * np.sqrt(dt)
            ukf.predict()
        ukf.sigmas_f = points.sigma_points(ukf.x, ukf.P)
        z = c["hx"](x) + rng.multivariate_normal(np.zeros(m), c["r"])
        ukf.update(np.atleast_1d(z))
        ours.step(np.atleast_1d(z), 0.0 if k == 0 else dt)
        worst = max(worst, np.max(np.abs(ours.mean - ukf.x)), np.max(np.abs(ours.cov - ukf.P)))
    # Same arithmetic up to summation order: agreement to rounding.
    print(f"{case}: worst difference {worst:.2e}")
    assert worst < 1e-9, worst
