"""The posterior of the AR(1) stochastic-volatility model's μ, ρ, σ on 750 simulated daily
returns, in one process (issue 64, item 5):

* Zakai: `zakai.sample` — adaptive random-walk Metropolis on the point-mass filter's
  likelihood (deterministic, converging to the exact likelihood as its grid is refined), 4
  chains started around the maximum-likelihood estimate;
* `particles` (Chopin & Papaspiliopoulos 2020): `mcmc.PMMH` — its adaptive random-walk
  particle marginal Metropolis–Hastings on a bootstrap filter's estimate with `NX` particles,
  one chain as its users run it, 4 runs with different seeds for R-hat.

Both under the same uniform priors μ ~ U(−3, 1), ρ ~ U(0, 0.999), σ ~ U(0.01, 1). Prints each
sampler's wall time, its effective sample sizes (rank-normalised, Vehtari et al. 2021, as
ArviZ computes them, on every run's draws after its burn-in) and effective samples per second,
and how far `particles`' posterior means lie from Zakai's in joint Monte Carlo standard
errors (√(mcse₁² + mcse₂²)).

    target/peers-venv/bin/pip install particles arviz
    maturin build --release -m python/Cargo.toml -o /tmp/wheels
    target/peers-venv/bin/pip install --no-deps --force-reinstall /tmp/wheels/zakai-*.whl
    target/peers-venv/bin/python scripts/peers/sv_posterior.py
"""

import json
import time

import arviz as az
import numpy as np
from particles import distributions as dists
from particles import mcmc
from particles import state_space_models as ssm

import zakai
from sv_pf import data

NX, NITER, BURN, RUNS = 200, 3000, 500, 4
BOUNDS = {"mu": (-3.0, 1.0), "rho": (0.0, 0.999), "sigma": (0.01, 1.0)}


def zakai_posterior(z):
    config = json.loads(zakai.Scenario.from_preset("sv-ar1").to_json())
    config["parameters"] = {name: {"value": v, "bounds": list(BOUNDS[name])}
                            for name, v in (("mu", -1.0), ("rho", 0.9), ("sigma", 0.3))}
    config["model"]["drift"] = ["mu + rho*(x - mu)"]
    config["model"]["diffusion"] = [["sigma"]]
    config["prior"] = {"kind": "gaussian", "mean": ["mu"], "cov": [["sigma^2/(1 - rho^2)"]]}
    config["methods"] = [m for m in config["methods"] if m["method"] == "point_mass"]
    config["time"].pop("t_final", None)
    sc = zakai.Scenario.from_json(json.dumps(config))
    start = time.perf_counter()
    post = zakai.sample(sc, z, "point_mass", draws=2500, warmup=1000, chains=4, seed=1,
                        times=np.arange(len(z), dtype=float))
    return time.perf_counter() - start, post


def particles_posterior(z):
    prior = dists.StructDist({name: dists.Uniform(a=lo, b=hi) for name, (lo, hi) in BOUNDS.items()})
    chains = {name: [] for name in BOUNDS}
    start = time.perf_counter()
    for run in range(RUNS):
        np.random.seed(run + 1)
        sampler = mcmc.PMMH(ssm_cls=ssm.StochVol, prior=prior, data=list(z), Nx=NX, niter=NITER,
                            verbose=0, theta0=None)
        sampler.run()
        for name in BOUNDS:
            chains[name].append(np.asarray(sampler.chain.theta[name])[BURN:])
    return time.perf_counter() - start, {n: np.array(c) for n, c in chains.items()}


def main():
    z = data()
    t_z, post = zakai_posterior(z)
    t_p, chains = particles_posterior(z)
    summary = post.summary()
    print(f"AR(1) SV posterior of mu, rho, sigma on {len(z)} returns")
    print(f"Zakai, random-walk Metropolis on the point-mass likelihood: {t_z:.1f} s, "
          f"{post.evaluations} evaluations")
    for name in BOUNDS:
        row = summary.loc[name]
        ess = min(row["ess_bulk"], row["ess_tail"])
        print(f"  {name:6s} mean {row['mean']:.4f} sd {row['sd']:.4f}  ESS {ess:.0f}  "
              f"{ess / t_z:.1f} ESS/s  R-hat {row['r_hat']:.3f}")
    print(f"particles, PMMH with {NX} particles, {RUNS} runs x {NITER} iterations "
          f"({BURN} burn-in): {t_p:.1f} s")
    idata = az.from_dict(posterior=chains)
    ess_bulk, ess_tail, rhat = az.ess(idata), az.ess(idata, method="tail"), az.rhat(idata)
    for name in BOUNDS:
        draws = chains[name].ravel()
        ess = float(min(ess_bulk[name], ess_tail[name]))
        mcse = draws.std(ddof=1) / np.sqrt(float(ess_bulk[name]))
        row = summary.loc[name]
        gap = (draws.mean() - row["mean"]) / np.hypot(mcse, row["mcse"])
        print(f"  {name:6s} mean {draws.mean():.4f} sd {draws.std(ddof=1):.4f}  ESS {ess:.0f}  "
              f"{ess / t_p:.2f} ESS/s  R-hat {float(rhat[name]):.3f}  "
              f"mean {gap:+.1f} joint MC s.e. from Zakai's")


if __name__ == "__main__":
    main()
