"""The bootstrap particle filter of peers.py's `pf` written in JAX, as its users run one: the
whole series in one `jax.lax.scan` under `jax.jit`, 64-bit floats (issue 61, item 3: "PF on
the cubic sensor: >= 5x the JAX jit PF").

Same work per step as peers.py and Zakai's run: 10^4 particles, cubic sensor dx = dv,
dy = x^3 dt + dw, dt = 0.01, prior N(1, 0.1); one Euler-Maruyama move, weights
exp(h dy - h^2 dt / 2), the weighted mean, systematic resampling at every step. Compiled once
(not timed); then the least of three runs, each waited for (`block_until_ready`).

JAX needs numpy >= 2 and `particles` numpy < 2, so scripts/bench-peers.sh runs this in a venv
of its own (target/jax-venv, `pip install jax`). Prints one JSON object: seconds per step.
"""
import json
import time

import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

STEPS, PARTICLES, DT = 500, 10_000, 0.01


def simulate(steps, dt, rng):
    """A path of dx = dv from x0 = 1 and its increments (as peers.py's `simulate`)."""
    x = 1.0 + np.cumsum(rng.standard_normal(steps) * np.sqrt(dt))
    return x**3 * dt + rng.standard_normal(steps) * np.sqrt(dt)


def filter_fn(particles, dt):
    offsets = jnp.arange(particles)

    def step(carry, dy):
        x, key = carry
        key, move, pick = jax.random.split(key, 3)
        x = x + jnp.sqrt(dt) * jax.random.normal(move, (particles,))
        h = x**3
        logw = h * dy - 0.5 * h * h * dt
        w = jnp.exp(logw - logw.max())
        w = w / w.sum()
        mean = jnp.dot(w, x)
        positions = (jax.random.uniform(pick) + offsets) / particles
        idx = jnp.minimum(jnp.searchsorted(jnp.cumsum(w), positions), particles - 1)
        return (x[idx], key), mean

    @jax.jit
    def run(x0, key, dys):
        return jax.lax.scan(step, (x0, key), dys)[1]

    return run


def main():
    dys = jnp.asarray(simulate(STEPS, DT, np.random.default_rng(1)))
    run = filter_fn(PARTICLES, DT)
    key = jax.random.PRNGKey(1)
    x0 = 1.0 + jnp.sqrt(0.1) * jax.random.normal(key, (PARTICLES,))
    run(x0, key, dys).block_until_ready()  # compile
    best = float("inf")
    for _ in range(3):
        start = time.perf_counter()
        means = run(x0, key, dys).block_until_ready()
        best = min(best, time.perf_counter() - start)
    assert np.all(np.isfinite(np.asarray(means)))
    print(json.dumps({"pf_jax": best / STEPS}))


if __name__ == "__main__":
    main()
