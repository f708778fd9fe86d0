"""The Python peers of Zakai's baselines, doing the same work per step as the Zakai runs that
scripts/bench-peers.sh times (written for Zakai; see BENCHMARKS.md):

* pf   bootstrap particle filter, 10^4 particles, cubic sensor dx = dv, dy = x^3 dt + dw,
       dt = 0.01, prior N(1, 0.1); one Euler-Maruyama move, weights exp(h dy - h^2 dt / 2),
       systematic resampling at every step, the weighted mean (vectorised NumPy);
* ukf  FilterPy's UnscentedKalmanFilter on z = x^3 + v (Var v = 0.1), random walk x
       (Q = dt = 0.01), van der Merwe points alpha = 0.5, beta = 2, kappa = 0: predict + update;
* qiem the quasi-implicit Yau-Yau step of 000 (18) on 2001 nodes of [-4, 4], f = 0, h = x^3,
       dt = 1e-4: the factor exp(h dy - h^2 dt / 2) (shifted), the Laplacian solved by
       SciPy's DST-I, normalisation, mean;
* qiem2d the same on 256^2 nodes of [-4, 4]^2, h = (x1^3, x2^3), dt = 1e-4: SciPy's dstn/idstn.

Prints one JSON object: seconds per step of each.
"""
import json
import sys
import time

import numpy as np
from scipy.fft import dst, dstn, idst, idstn
from filterpy.kalman import MerweScaledSigmaPoints, UnscentedKalmanFilter


def simulate(steps, dt, rng, discrete_var=None):
    """A path of dx = dv from x0 = 1 and its observations (increments or measurements)."""
    x = 1.0 + np.cumsum(rng.standard_normal(steps) * np.sqrt(dt))
    if discrete_var is None:
        return x, x**3 * dt + rng.standard_normal(steps) * np.sqrt(dt)
    return x, x**3 + rng.standard_normal(steps) * np.sqrt(discrete_var)


def best_of(repeats, run):
    """The least seconds per step over `repeats` runs (as criterion's lower estimates)."""
    return min(run() for _ in range(repeats))


def pf(steps=500, particles=10_000, dt=0.01):
    rng = np.random.default_rng(1)
    _, dy = simulate(steps, dt, rng)

    def run():
        x = 1.0 + np.sqrt(0.1) * rng.standard_normal(particles)
        sd = np.sqrt(dt)
        offsets = np.arange(particles)
        start = time.perf_counter()
        for k in range(steps):
            x += sd * rng.standard_normal(particles)
            h = x**3
            logw = h * dy[k] - 0.5 * h * h * dt
            w = np.exp(logw - logw.max())
            w /= w.sum()
            mean = np.dot(w, x)
            positions = (rng.random() + offsets) / particles
            idx = np.searchsorted(np.cumsum(w), positions)
            np.minimum(idx, particles - 1, out=idx)
            x = x[idx]
        elapsed = time.perf_counter() - start
        assert np.isfinite(mean)
        return elapsed / steps

    return best_of(3, run)


def ukf(steps=500, dt=0.01):
    rng = np.random.default_rng(1)
    _, z = simulate(steps, dt, rng, discrete_var=0.1)

    def run():
        points = MerweScaledSigmaPoints(1, alpha=0.5, beta=2.0, kappa=0.0)
        f = UnscentedKalmanFilter(
            dim_x=1, dim_z=1, dt=dt, hx=lambda x: x**3, fx=lambda x, dt: x, points=points
        )
        f.x = np.array([1.0])
        f.P = np.array([[0.1]])
        f.Q = np.array([[dt]])
        f.R = np.array([[0.1]])
        start = time.perf_counter()
        for k in range(steps):
            f.predict()
            f.update(z[k])
        elapsed = time.perf_counter() - start
        assert np.all(np.isfinite(f.x))
        return elapsed / steps

    return best_of(3, run)


def qiem(steps=2000, nodes=2001, dt=1e-4, bounds=(-4.0, 4.0)):
    rng = np.random.default_rng(1)
    _, dy = simulate(steps, dt, rng)
    ds = (bounds[1] - bounds[0]) / (nodes + 1)
    s = bounds[0] + ds * np.arange(1, nodes + 1)
    h = s**3
    half_hh = 0.5 * h * h * dt
    j = np.arange(1, nodes + 1)
    # (I - dt/2 Laplacian) in DST-I eigenvalues: 1 + dt (2/ds^2) sin^2(j pi / (2 (N + 1))).
    divisor = 1.0 + dt * (2.0 / ds**2) * np.sin(j * np.pi / (2 * (nodes + 1))) ** 2

    def run():
        u = np.exp(-((s - 1.0) ** 2) / 0.2)
        u /= u.sum() * ds
        start = time.perf_counter()
        for k in range(steps):
            a = h * dy[k] - half_hh
            u *= np.exp(a - a.max())
            u = idst(dst(u, type=1) / divisor, type=1)
            np.maximum(u, 0.0, out=u)
            u /= u.sum() * ds
            mean = np.dot(u, s) * ds
        elapsed = time.perf_counter() - start
        assert np.isfinite(mean)
        return elapsed / steps

    return best_of(3, run)


def qiem2d(steps=200, nodes=256, dt=1e-4, bounds=(-4.0, 4.0)):
    rng = np.random.default_rng(1)
    dy = np.stack([simulate(steps, dt, rng)[1] for _ in range(2)], axis=1)
    ds = (bounds[1] - bounds[0]) / (nodes + 1)
    axis = bounds[0] + ds * np.arange(1, nodes + 1)
    # First dimension fastest, as Zakai stores its grid: u[i2, i1].
    x2, x1 = np.meshgrid(axis, axis, indexing="ij")
    h1, h2 = x1**3, x2**3
    half_hh = 0.5 * (h1 * h1 + h2 * h2) * dt
    j = np.arange(1, nodes + 1)
    sin2 = np.sin(j * np.pi / (2 * (nodes + 1))) ** 2
    divisor = 1.0 + dt * (2.0 / ds**2) * (sin2[:, None] + sin2[None, :])

    def run():
        u = np.exp(-((x1 - 1.0) ** 2 + (x2 - 1.0) ** 2) / 0.2)
        u /= u.sum() * ds * ds
        start = time.perf_counter()
        for k in range(steps):
            a = h1 * dy[k, 0] + h2 * dy[k, 1] - half_hh
            u *= np.exp(a - a.max())
            u = idstn(dstn(u, type=1) / divisor, type=1)
            np.maximum(u, 0.0, out=u)
            u /= u.sum() * ds * ds
            mean = (np.sum(u * x1) * ds * ds, np.sum(u * x2) * ds * ds)
        elapsed = time.perf_counter() - start
        assert np.all(np.isfinite(mean))
        return elapsed / steps

    return best_of(3, run)


if __name__ == "__main__":
    which = sys.argv[1:] or ["pf", "ukf", "qiem", "qiem2d"]
    out = {name: globals()[name]() for name in which}
    print(json.dumps(out))
