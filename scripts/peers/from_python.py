"""Zakai called from Python doing the peers' work (scripts/peers/peers.py), per step:

* ``step``: one ``zakai.Filter.step`` call per observation from a Python loop (what a
  real-time loop pays: the call, the argument conversion, the Rust step);
* ``run``: every observation in one ``zakai.Filter.run`` call (the loop in Rust; the means
  and covariances come back as arrays).

Same data, particle count, resampling rule (every step), grid and time steps as the peers.
Prints one JSON object: {work: {"step": seconds, "run": seconds}}.
"""
import json
import sys
import time

import numpy as np

import zakai
from peers import best_of, simulate


def timed(make, observations, dt):
    """Least seconds per step over three runs, for both ways of calling."""
    steps = len(observations)
    column = observations.reshape(steps, 1)

    def by_step():
        f = make()
        start = time.perf_counter()
        for k in range(steps):
            f.step(column[k], dt)
        elapsed = time.perf_counter() - start
        assert np.isfinite(f.mean).all()
        return elapsed / steps

    def by_run():
        f = make()
        dts = np.full(steps, dt)
        start = time.perf_counter()
        means, _ = f.run(column, dts)
        elapsed = time.perf_counter() - start
        assert np.isfinite(means).all()
        return elapsed / steps

    return {"step": best_of(3, by_step), "run": best_of(3, by_run)}


def pf(steps=500, dt=0.01):
    _, dy = simulate(steps, dt, np.random.default_rng(1))
    model = zakai.Model.continuous("0", "x^3")
    prior = zakai.Prior.gaussian(1.0, 0.1)
    make = lambda: zakai.Filter(  # noqa: E731
        "pf", model, prior, dt_obs=dt, particles=10_000, ess_threshold=1.0, substeps=1
    )
    return timed(make, dy, dt)


def ukf(steps=500, dt=0.01):
    _, z = simulate(steps, dt, np.random.default_rng(1), discrete_var=0.1)
    model = zakai.Model.discrete("0", "x^3", noise_cov=0.1)
    prior = zakai.Prior.gaussian(1.0, 0.1)
    make = lambda: zakai.Filter(  # noqa: E731
        "ukf", model, prior, dt_obs=dt, alpha=0.5, beta=2.0, kappa=0.0, substeps=1
    )
    return timed(make, z, dt)


def qiem(steps=2000, dt=1e-4):
    _, dy = simulate(steps, dt, np.random.default_rng(1))
    model = zakai.Model.continuous("0", "x^3")
    prior = zakai.Prior.gaussian(1.0, 0.1)
    make = lambda: zakai.Filter(  # noqa: E731
        "qiem", model, prior, dt_obs=dt, domain=[(-4.0, 4.0)], points=[2001], dt=dt
    )
    return timed(make, dy, dt)


if __name__ == "__main__":
    which = sys.argv[1:] or ["pf", "ukf", "qiem"]
    print(json.dumps({name: globals()[name]() for name in which}))
