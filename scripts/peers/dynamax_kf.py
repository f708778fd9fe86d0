"""Zakai's EKF and UKF beside dynamax's (JAX, `jit` over the whole series) and FilterPy's
(NumPy, its `predict`/`update` loop), on the same data, in one process (issue 61, item 3: "UKF
and EKF: >= 5x dynamax on the 1-D model and on a 4-D constant-velocity target with
range-bearing measurements (also against FilterPy)").

* 1-D: peers.py's UKF model as a map, x_k = x_(k-1) + w_k (Var w = 0.01), z_k = x_k^3 + v_k
  (Var v = 0.1), x_0 ~ N(1, 0.1); 500 measurements.
* 4-D: a constant-velocity target, x = (p1, p2, v1, v2), x_k = F x_(k-1) + w_k with
  F = [[I, dt I], [0, I]] and the white-acceleration Q of q = 0.5, dt = 0.1; measured by range
  and bearing, z = (|p|, atan(p2/p1)) + v, sd 0.1 and 0.01 rad (the target stays where
  p1 > 0: Zakai's expressions have no atan2); 500 measurements from a fixed generator.

* SDE: dx = (x - x^3) dt + 0.7 dv measured every 0.1 as z = x + v (Var v = 0.1), x_0 ~ N(1, 0.1);
  500 measurements of a path simulated here. cd-dynamax (JAX + diffrax, continuous-discrete)
  integrates the EKF's and UKF's moment equations with diffrax's Heun method in steps of
  0.1/8, Zakai with classical RK4 in 4 substeps: 16 drift evaluations per interval on both
  (so the means differ by the two integrators' errors, not by round-off).

dynamax, cd-dynamax and Zakai filter the whole series in one call: dynamax's
`extended_kalman_filter` / `unscented_kalman_filter` and cd-dynamax's `cdnlgssm_filter` under
`jax.jit` (compiled before the clock, 64-bit), Zakai's `Filter.run` (the loop in Rust) on
filters built before the clock (building parses and compiles the model's expressions, as
`jit` compiles the peer's); FilterPy's `ExtendedKalmanFilter` (its Jacobian written
here) and `UnscentedKalmanFilter` (`MerweScaledSigmaPoints`) step in a Python loop, as its
users run it. UKF points alpha = 0.5 (1-D; 1.0 in 4-D and on the SDE), beta = 2, kappa = 0
on all. Prints each one's seconds per step (the least of 5 runs) and the largest difference
of the filtered means, which is round-off when the two compute the same filter.

JAX needs numpy >= 2, so scripts/bench-peers.sh runs this in target/jax-venv, with this
checkout's wheel installed there too.
"""
import json
import time

import jax
import jax.numpy as jnp
import numpy as np
from dynamax.nonlinear_gaussian_ssm import (
    ParamsNLGSSM,
    UKFHyperParams,
    extended_kalman_filter,
    unscented_kalman_filter,
)

from filterpy.kalman import ExtendedKalmanFilter, MerweScaledSigmaPoints, UnscentedKalmanFilter

import zakai

jax.config.update("jax_enable_x64", True)

STEPS, REPEATS = 500, 5


def least(run):
    best = float("inf")
    for _ in range(REPEATS):
        start = time.perf_counter()
        out = run()
        best = min(best, time.perf_counter() - start)
    return best / STEPS, out


def least_fresh(make, z):
    """Zakai's Filter.run over z on REPEATS filters built before the clock: the least time per
    step and the first run's means."""
    filters = [make() for _ in range(REPEATS)]
    best, out = float("inf"), None
    for f in filters:
        start = time.perf_counter()
        means, _ = f.run(z)
        best = min(best, time.perf_counter() - start)
        out = means if out is None else out
    return best / STEPS, out


def one_d():
    rng = np.random.default_rng(1)
    x = 1.0 + np.cumsum(rng.standard_normal(STEPS) * 0.1)
    z = x**3 + rng.standard_normal(STEPS) * np.sqrt(0.1)
    params = ParamsNLGSSM(
        initial_mean=jnp.array([1.0]),
        initial_covariance=jnp.array([[0.1]]),
        dynamics_function=lambda x: x,
        dynamics_covariance=jnp.array([[0.01]]),
        emission_function=lambda x: x**3,
        emission_covariance=jnp.array([[0.1]]),
    )
    model = zakai.Model.discrete_time("x", "x^3", transition_cov=0.01, noise_cov=0.1)
    prior = zakai.Prior.gaussian(1.0, 0.1)
    numpy_model = dict(
        f=lambda x: x, jac_f=np.eye(1), h=lambda x: x**3,
        jac_h=lambda x: np.array([[3 * x[0] ** 2]]), q=np.array([[0.01]]), r=np.array([[0.1]]),
        mean=np.array([1.0]), cov=np.array([[0.1]]),
    )
    return "1-D, z = x^3 + v", params, model, prior, z[:, None], 0.5, numpy_model


def cv_track():
    dt, q = 0.1, 0.5
    f = np.block([[np.eye(2), dt * np.eye(2)], [np.zeros((2, 2)), np.eye(2)]])
    qb = q * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]])
    cov = np.kron(qb, np.eye(2))
    r = np.diag([0.1**2, 0.01**2])
    rng = np.random.default_rng(2)
    x = np.array([10.0, 5.0, 0.5, 1.0])
    chol = np.linalg.cholesky(cov)
    zs = []
    for _ in range(STEPS):
        x = f @ x + chol @ rng.standard_normal(4)
        zs.append([np.hypot(x[0], x[1]), np.arctan(x[1] / x[0])]
                  + rng.standard_normal(2) * np.sqrt(np.diag(r)))
    z = np.array(zs)
    fj = jnp.asarray(f)
    params = ParamsNLGSSM(
        initial_mean=jnp.array([10.0, 5.0, 0.5, 1.0]),
        initial_covariance=jnp.eye(4) * 0.5,
        dynamics_function=lambda x: fj @ x,
        dynamics_covariance=jnp.asarray(cov),
        emission_function=lambda x: jnp.array([jnp.hypot(x[0], x[1]), jnp.arctan(x[1] / x[0])]),
        emission_covariance=jnp.asarray(r),
    )
    model = zakai.Model.discrete_time(
        [f"x1 + {dt}*x3", f"x2 + {dt}*x4", "x3", "x4"],
        ["sqrt(x1^2 + x2^2)", "atan(x2/x1)"],
        transition_cov=cov.tolist(),
        noise_cov=r.tolist(),
    )
    prior = zakai.Prior.gaussian([10.0, 5.0, 0.5, 1.0], (np.eye(4) * 0.5).tolist())

    def jac_h(x):
        rho2 = x[0] ** 2 + x[1] ** 2
        rho = np.sqrt(rho2)
        return np.array([[x[0] / rho, x[1] / rho, 0.0, 0.0],
                         [-x[1] / rho2, x[0] / rho2, 0.0, 0.0]])

    numpy_model = dict(
        f=lambda x: f @ x, jac_f=f,
        h=lambda x: np.array([np.hypot(x[0], x[1]), np.arctan(x[1] / x[0])]),
        jac_h=jac_h, q=cov, r=r, mean=np.array([10.0, 5.0, 0.5, 1.0]), cov=np.eye(4) * 0.5,
    )
    return "4-D constant velocity, range-bearing", params, model, prior, z, 1.0, numpy_model


def filterpy_run(method, m, z, alpha):
    """FilterPy's EKF or UKF over the rows of z (the first a measurement of the prior's
    state, as in the other two); the filtered means."""
    n = len(m["mean"])
    if method == "ekf":
        kf = ExtendedKalmanFilter(dim_x=n, dim_z=z.shape[1])
        kf.F, kf.Q, kf.R = m["jac_f"], m["q"], m["r"]
    else:
        points = MerweScaledSigmaPoints(n, alpha=alpha, beta=2.0, kappa=0.0)
        kf = UnscentedKalmanFilter(dim_x=n, dim_z=z.shape[1], dt=1.0, hx=m["h"],
                                   fx=lambda x, dt: m["f"](x), points=points)
        kf.Q, kf.R = m["q"], m["r"]
    kf.x, kf.P = m["mean"].copy(), m["cov"].copy()
    means = np.empty((len(z), n))
    for k, zk in enumerate(z):
        if k:
            # The EKF's x = F x, P = F P Fᵀ + Q (both maps here are linear); the UKF's
            # sigma points through fx.
            kf.predict()
        elif method == "ukf":
            # The first update is of the prior itself: its sigma points, not moved.
            kf.sigmas_f = kf.points_fn.sigma_points(kf.x, kf.P)
        if method == "ekf":
            kf.update(zk, m["jac_h"], m["h"])
        else:
            kf.update(zk)
        means[k] = kf.x
    return means


def compare(case):
    title, params, model, prior, z, alpha, numpy_model = case
    ez = jnp.asarray(z)
    runs = {
        "ekf": jax.jit(lambda e: extended_kalman_filter(
            params, e, output_fields=["filtered_means"]).filtered_means),
        "ukf": jax.jit(lambda e: unscented_kalman_filter(
            params, e, UKFHyperParams(alpha=alpha, beta=2, kappa=0),
            output_fields=["filtered_means"]).filtered_means),
    }
    rows = {}
    for method, run in runs.items():
        run(ez).block_until_ready()  # compile
        peer, means = least(lambda: run(ez).block_until_ready())
        options = dict(substeps=1) if method == "ekf" else dict(
            alpha=alpha, beta=2.0, kappa=0.0, substeps=1)
        # Both take the first row as a measurement of the prior's state (dynamax's first
        # emission is of x_1 ~ N(initial_mean, initial_covariance); Zakai's run() of a fresh
        # discrete-model filter measures at the prior's time first).
        make = lambda: zakai.Filter(method, model, prior, dt_obs=1.0, **options)  # noqa: E731
        ours, zmeans = least_fresh(make, z)
        gap = float(np.max(np.abs(np.asarray(means) - zmeans)))
        numpy_time, numpy_means = least(lambda: filterpy_run(method, numpy_model, z, alpha))
        numpy_gap = float(np.max(np.abs(numpy_means - zmeans)))
        rows[method] = {"zakai": ours, "peers": {"dynamax": [peer, gap],
                                                 "filterpy": [numpy_time, numpy_gap]}}
    return title, rows


def sde():
    """The continuous-discrete EKF and UKF on the SDE, beside cd-dynamax's."""
    import diffrax
    from typing import NamedTuple
    from cd_dynamax import EKFHyperParams, ParamsCDNLGSSM, UKFHyperParams, cdnlgssm_filter
    from cd_dynamax.dynamax.linear_gaussian_ssm.inference import ParamsLGSSMInitial
    from cd_dynamax.src.continuous_discrete_nonlinear_gaussian_ssm.cdnlgssm_utils import (
        LearnableMatrix, LearnableVector, ParamsCDNLGSSMDynamics, ParamsCDNLGSSMEmissions)

    class Drift(NamedTuple):
        params: float

        def f(self, x, u=None, t=None):
            return x - x**3

    class Identity(NamedTuple):
        params: float

        def f(self, x, u=None, t=None):
            return x

    dt, sd, r = 0.1, 0.7, 0.1
    rng = np.random.default_rng(3)
    x, zs = 1.0, []
    for _ in range(STEPS):
        for _ in range(100):
            x += (x - x**3) * dt / 100 + sd * np.sqrt(dt / 100) * rng.standard_normal()
        zs.append(x + np.sqrt(r) * rng.standard_normal())
    z = np.array(zs)[:, None]
    params = ParamsCDNLGSSM(
        initial=ParamsLGSSMInitial(mean=LearnableVector(jnp.array([1.0])),
                                   cov=LearnableMatrix(jnp.array([[0.1]]))),
        dynamics=ParamsCDNLGSSMDynamics(
            drift=Drift(0.0), diffusion_coefficient=LearnableMatrix(jnp.array([[sd]])),
            diffusion_cov=LearnableMatrix(jnp.eye(1)), approx_order=1.0),
        emissions=ParamsCDNLGSSMEmissions(emission_function=Identity(0.0),
                                          emission_cov=LearnableMatrix(jnp.array([[r]]))),
    )
    ez, times = jnp.asarray(z), jnp.asarray((np.arange(STEPS) * dt)[:, None])
    settings = dict(solver=diffrax.Heun(), dt0=dt / 8)
    hyper = {"ekf": EKFHyperParams(diffeqsolve_settings=settings),
             "ukf": UKFHyperParams(alpha=1.0, beta=2, kappa=0.0, diffeqsolve_settings=settings)}
    model = zakai.Model.discrete("x - x^3", "x", noise_cov=r, diffusion=sd)
    prior = zakai.Prior.gaussian(1.0, 0.1)
    rows = {}
    for method, hp in hyper.items():
        run = jax.jit(lambda e, hp=hp: cdnlgssm_filter(
            params, e, times, filter_hyperparams=hp, output_fields=["filtered_means"],
            warn=False).filtered_means)
        run(ez).block_until_ready()  # compile
        peer, means = least(lambda: run(ez).block_until_ready())
        options = dict(substeps=4) if method == "ekf" else dict(
            alpha=1.0, beta=2.0, kappa=0.0, substeps=4)
        make = lambda: zakai.Filter(method, model, prior, dt_obs=dt, **options)  # noqa: E731
        ours, zmeans = least_fresh(make, z)
        gap = float(np.max(np.abs(np.asarray(means) - zmeans)))
        rows[method] = {"zakai": ours, "peers": {"cd-dynamax": [peer, gap]}}
    return "SDE dx = (x - x^3) dt + 0.7 dv, z = x + v, 16 drift evaluations/interval", rows


def main():
    print(json.dumps([compare(case) for case in (one_d(), cv_track())] + [sde()]))


if __name__ == "__main__":
    main()
