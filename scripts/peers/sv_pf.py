"""The bootstrap particle filter on the AR(1) stochastic-volatility model, Zakai's beside
`particles`' (Chopin & Papaspiliopoulos 2020, its `StochVol`), in one process, on the same
750 simulated daily returns, N = 10^4 (issue 61, item 3).

    x_k = mu + rho (x_(k-1) - mu) + sigma w_k,   w_k ~ N(0, 1)
    z_k ~ N(0, exp(x_k)),   x_0 ~ N(mu, sigma^2 / (1 - rho^2))
    mu = -1.02, rho = 0.9702, sigma = 0.178 (particles' GBP/USD values)

Zakai writes it as a discrete-time map (`Model.heteroscedastic(...).in_discrete_time`), so
its particles are drawn from the AR(1) itself, and weighs them with the variance exp(x)
evaluated as a batch. A second Zakai row writes the same model as the SDE whose daily
transition it is, dx = −θ(x − μ) dt + σ_c dv with θ = −ln ρ and σ_c = σ √(2θ/(1 − ρ²)): a
linear SDE with constant G, whose particles Zakai draws from the exact Gaussian transition
over each day (issue 61, item 2) — the same law as the map, so the same log-likelihood within
Monte Carlo error. Both resample systematically when the effective sample size falls
below N/2. Prints each one's time per step (the least of `REPEATS` runs) and log-likelihood
estimate, which agree within their Monte Carlo error when the two filter the same model.

`bash scripts/bench-peers.sh` runs it (it installs what it needs); by hand, an environment with
`particles` (numpy < 2) and a release wheel of Zakai:
    python3 -m venv /tmp/pvenv && /tmp/pvenv/bin/pip install particles
    maturin build --release -m python/Cargo.toml -o /tmp/wheels
    /tmp/pvenv/bin/pip install --no-deps /tmp/wheels/zakai-*.whl
    /tmp/pvenv/bin/python scripts/peers/sv_pf.py
"""

import time

import numpy as np
import particles
from particles import state_space_models as ssm

import zakai
from side_by_side import compare

N, T, REPEATS = 10_000, 750, 3
MU, RHO, SIGMA = -1.02, 0.9702, 0.178


def data(seed=11):
    rng = np.random.default_rng(seed)
    x = rng.normal(MU, SIGMA / np.sqrt(1 - RHO**2))
    z = []
    for k in range(T):
        if k:
            x = MU + RHO * (x - MU) + SIGMA * rng.normal()
        z.append(np.exp(x / 2) * rng.normal())
    return np.array(z)


def run_particles(z, seed):
    np.random.seed(seed)
    model = ssm.StochVol(mu=MU, rho=RHO, sigma=SIGMA)
    alg = particles.SMC(fk=ssm.Bootstrap(ssm=model, data=list(z)), N=N,
                        resampling="systematic", ESSrmin=0.5, store_history=False, verbose=False)
    start = time.perf_counter()
    alg.run()
    return time.perf_counter() - start, alg.logLt


def step_through(f, z):
    """Steps `f` through the returns (the first at the prior's time), timed, with the summed
    log-likelihood."""
    ll = 0.0
    start = time.perf_counter()
    for k, zk in enumerate(z):
        f.step([zk], 0.0 if k == 0 else 1.0)
        ll += f.log_likelihood
    return time.perf_counter() - start, ll


def run_zakai(z, seed):
    model = zakai.Model.heteroscedastic(f"{MU} + {RHO}*(x - ({MU}))", "0", "exp(x)").in_discrete_time(
        transition_cov=SIGMA**2)
    prior = zakai.Prior.gaussian(MU, SIGMA**2 / (1 - RHO**2))
    f = zakai.Filter("pf", model, prior, dt_obs=1.0, seed=seed, particles=N, ess_threshold=0.5)
    return step_through(f, z)


def run_zakai_sde(z, seed):
    theta = -np.log(RHO)
    sigma_c = SIGMA * np.sqrt(2 * theta / (1 - RHO**2))
    model = zakai.Model.heteroscedastic(
        f"-{theta}*(x - ({MU}))", "0", "exp(x)", diffusion=[[sigma_c]])
    prior = zakai.Prior.gaussian(MU, SIGMA**2 / (1 - RHO**2))
    f = zakai.Filter("pf", model, prior, dt_obs=1.0, seed=seed, particles=N, ess_threshold=0.5)
    assert any("exact linear transition" in note for note in f.chosen_defaults), f.chosen_defaults
    return step_through(f, z)


def main():
    z = data()
    runs = [("particles (Bootstrap, SMC)", run_particles), ("Zakai (pf, Filter.step)", run_zakai),
            ("Zakai (pf, SDE form, exact)", run_zakai_sde)]
    compare(f"AR(1) stochastic volatility, N = {N}, T = {T} measurements", z, runs, REPEATS)


if __name__ == "__main__":
    main()
