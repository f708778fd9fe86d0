"""The bootstrap particle filter on the growth model, Zakai's beside `particles`' (Chopin &
Papaspiliopoulos 2020), in one process, on the same data, N = 10^4 (issue 60, item 6).

    x_k = x_(k-1)/2 + 25 x_(k-1)/(1 + x_(k-1)^2) + 8 cos(1.2 k) + w_k,  w_k ~ N(0, 10)
    z_k = x_k^2/20 + v_k,  v_k ~ N(0, 1),  x_0 ~ N(0, 5),  a measurement at k = 0, 1, ..., T

Both resample systematically when the effective sample size falls below N/2 (particles'
default ESSrmin = 0.5; Zakai's ess_threshold = 0.5). Zakai steps through its Python
`Filter.step` (the model reads t, so each step is given its time); particles through
`SMC.run()`. Prints each one's time per step (the least of `REPEATS` runs) and log-likelihood
estimate, which agree within their Monte Carlo error when the two filter the same model.

`bash scripts/bench-peers.sh` runs it (it installs what it needs); by hand, an environment with
`particles` (numpy < 2) and Zakai's wheel:
    python3 -m venv /tmp/pvenv && /tmp/pvenv/bin/pip install particles
    maturin build --release -m python/Cargo.toml -o /tmp/wheels
    /tmp/pvenv/bin/pip install --no-deps /tmp/wheels/zakai-*.whl
    /tmp/pvenv/bin/python scripts/peers/growth_pf.py
"""

import time

import numpy as np
import particles
from particles import distributions as dists
from particles import state_space_models as ssm

import zakai
from side_by_side import compare

N, T, REPEATS = 10_000, 100, 3


def transition(x, k):
    return x / 2 + 25 * x / (1 + x**2) + 8 * np.cos(1.2 * k)


class Growth(ssm.StateSpaceModel):
    """The growth model in particles' terms (its t is our k)."""

    def PX0(self):
        return dists.Normal(loc=0.0, scale=np.sqrt(5.0))

    def PX(self, t, xp):
        return dists.Normal(loc=transition(xp, t), scale=np.sqrt(10.0))

    def PY(self, t, xp, x):
        return dists.Normal(loc=x**2 / 20, scale=1.0)


def data(seed=7):
    rng = np.random.default_rng(seed)
    x = rng.normal(0.0, np.sqrt(5.0))
    z = []
    for k in range(T + 1):
        if k:
            x = transition(x, k) + rng.normal(0.0, np.sqrt(10.0))
        z.append(x**2 / 20 + rng.normal())
    return np.array(z)


def run_particles(z, seed):
    np.random.seed(seed)
    alg = particles.SMC(fk=ssm.Bootstrap(ssm=Growth(), data=list(z)), N=N,
                        resampling="systematic", ESSrmin=0.5, store_history=False, verbose=False)
    start = time.perf_counter()
    alg.run()
    return time.perf_counter() - start, alg.logLt


def run_zakai(z, seed):
    model = zakai.Model.discrete_time("x/2 + 25*x/(1 + x^2) + 8*cos(1.2*t)", "x^2/20",
                                      transition_cov=10.0, noise_cov=1.0)
    f = zakai.Filter("pf", model, zakai.Prior.gaussian(0.0, 5.0), dt_obs=1.0, seed=seed,
                     particles=N, ess_threshold=0.5)
    ll = 0.0
    start = time.perf_counter()
    for k, zk in enumerate(z):
        f.step([zk], 0.0 if k == 0 else 1.0, t=float(k), u=[])
        ll += f.log_likelihood
    return time.perf_counter() - start, ll


def main():
    z = data()
    runs = [("particles (Bootstrap, SMC)", run_particles), ("Zakai (pf, Filter.step)", run_zakai)]
    compare(f"growth model, N = {N}, T = {T} ({len(z)} measurements)", z, runs, REPEATS)


if __name__ == "__main__":
    main()
