"""Posterior of (q, r) in the "cubic-sensor-fit" model with dynestyx (NumPyro NUTS on the
marginal likelihood of dynestyx's continuous-discrete EKF, then of its UKF).

Model: dx = -x dt + sqrt(q) dW,  x(0) ~ N(0, 0.25),  z_k = x(t_k)^3 + v_k,  v_k ~ N(0, r),
t_k = 0, 0.2, ..., 60 (301 measurements, the first at t = 0); priors q ~ U(0.01, 4),
r ~ U(0.05, 4). Data: a CSV with columns `t,z1`.

Written against dynestyx 0.7.1 (cd-dynamax 0.5.0 backend, numpyro 0.22, jax 0.12, arviz 1.3):
the likelihood comes from `dsx.Filter` with `ContinuousTimeEKFConfig` / `ContinuousTimeUKFConfig`
at their defaults (filter_state_order="first": the mean/covariance moment ODEs -- the EKF's
linearised ones, the UKF's sigma-point ones -- integrated between measurements by diffrax's
Dopri5 at a constant step dt0 = 0.01, i.e. 20 steps per 0.2 gap; cd-dynamax's default solver),
with recording of filtered states/predictions turned off (only the likelihood is needed).
Note that the EKF linearises h(x) = x^3 at the predicted mean, which starts at 0 where h' = 0:
its gain stays 0, its mean stays 0, and its likelihood, prod_k N(z_k; 0, r), does not depend
on q, so its q-posterior is the prior (cd-dynamax's EKF update is always first order).
The sampler is what dynestyx's `MCMCInference(NUTSConfig(...))` builds -- numpyro NUTS with
init_to_sample and target acceptance 0.8 -- called directly so that chains run sequentially
without a progress bar and warm-up and draws can be timed apart.

Per filter it prints (and with `--json FILE` writes) for q and r: posterior mean, sd, 5 % and
95 % quantiles, bulk and tail ESS (ArviZ, tail at the 5 %/95 % quantiles as in Vehtari et al.
2021), R-hat; the number of divergences and the mean number of leapfrog steps per draw; the
wall time of the whole MCMC run (warm-up + draws, all chains, from the call into numpyro, so
excluding imports and data loading but including JAX tracing/compilation), split into warm-up
and draws, and the part of it JAX spent tracing, lowering and compiling (from jax.monitoring);
and min bulk ESS per second of that wall time, with and without the compile time.

    JAX_PLATFORMS=cpu ~/.cache/zakai/dynestyx-venv/bin/python scripts/peers/cubic_dynestyx.py \
        /tmp/dx/cubic.csv [--chains 4 --draws 1000 --warmup 1000 --seed 1] [--json out.json]
"""

import os

os.environ["JAX_PLATFORMS"] = "cpu"  # before jax is imported

import argparse
import json
import time
import warnings

import jax

jax.config.update("jax_enable_x64", True)

import arviz as az
import dynestyx as dsx
import jax.numpy as jnp
import numpy as np
import numpyro
import numpyro.distributions as dist
from dynestyx.inference.filters import ContinuousTimeEKFConfig, ContinuousTimeUKFConfig
from numpyro.infer import MCMC, NUTS, init_to_sample

PRIOR_Q, PRIOR_R = (0.01, 4.0), (0.05, 4.0)
NO_RECORDING = dict(
    include_predicted_observations=False, record_predicted_observations_mean=False,
    record_predicted_observations_cov=False, record_filtered_states_mean=False,
    record_filtered_states_cov=False, record_filtered_states_cov_diag=False,
    record_filtered_states_chol_cov=False,
)
FILTERS = {"EKF": ContinuousTimeEKFConfig, "UKF": ContinuousTimeUKFConfig}


def model(obs_times, obs_values, filter_config):
    q = numpyro.sample("q", dist.Uniform(*PRIOR_Q))
    r = numpyro.sample("r", dist.Uniform(*PRIOR_R))
    dynamics = dsx.DynamicalModel(
        initial_condition=dist.MultivariateNormal(jnp.zeros(1), 0.25 * jnp.eye(1)),
        state_evolution=dsx.ContinuousTimeStateEvolution(
            drift=lambda x, u, t: -x, diffusion=dsx.ScalarDiffusion(jnp.sqrt(q), bm_dim=1)),
        observation_model=dsx.GaussianObservation(h=lambda x, u, t: x**3, R=r * jnp.eye(1)),
        # The measurement at t = 0: dynestyx sets the model's start time t0 to obs_times[0] (an
        # explicit t0 must equal it; passing t0=0.0 fails under jit in 0.7.1, so it is left to be
        # inferred), and cd-dynamax takes (m0, P0) as the predicted moments at obs_times[0] and
        # conditions on z_0 before its first prediction step. As the prior is at t = 0 =
        # obs_times[0], z_0 updates N(0, 0.25) directly: no special handling is needed.
    )
    with dsx.Filter(filter_config=filter_config):
        dsx.sample("x", dynamics, obs_times=obs_times, obs_values=obs_values)


class CompileClock:
    """Sums the durations JAX reports for top-level tracing, lowering and XLA compilation."""

    EVENTS = ("/jax/core/compile/jaxpr_trace_duration",
              "/jax/core/compile/jaxpr_to_mlir_module_duration",
              "/jax/core/compile/backend_compile_duration")

    def __init__(self):
        self.seconds = 0.0

    def _listen(self, event, duration, **_):
        if event in self.EVENTS:
            self.seconds += duration

    def __enter__(self):
        jax.monitoring.register_event_duration_secs_listener(self._listen)
        return self

    def __exit__(self, *exc):
        jax.monitoring.unregister_event_duration_listener(self._listen)


def timed(fn, mcmc):
    with CompileClock() as clock:
        start = time.perf_counter()
        fn()
        jax.block_until_ready(mcmc.last_state)
        return time.perf_counter() - start, clock.seconds


def run_filter(name, times, z, chains, draws, warmup, seed):
    config = FILTERS[name](**NO_RECORDING)
    mcmc = MCMC(NUTS(model, init_strategy=init_to_sample, target_accept_prob=0.8),
                num_warmup=warmup, num_samples=draws, num_chains=chains,
                chain_method="sequential", progress_bar=False)
    args = (times, z, config)
    with warnings.catch_warnings():
        # dynestyx 0.7.1 puts the drift (an equinox bound method whose module holds sqrt(q)) in a
        # static equinox field and equinox warns on every trace; values and gradients are right
        # (checked against finite differences and an independent EKF).
        warnings.filterwarnings("ignore", "A JAX array is being set as static")
        t_warm, c_warm = timed(lambda: mcmc.warmup(jax.random.PRNGKey(seed), *args), mcmc)
        t_draw, c_draw = timed(lambda: mcmc.run(mcmc.post_warmup_state.rng_key, *args,
                                                extra_fields=("diverging", "num_steps")), mcmc)
    samples = mcmc.get_samples(group_by_chain=True)
    post = {k: np.asarray(samples[k]) for k in ("q", "r")}
    tree = az.from_dict({"posterior": post})
    ess_bulk = az.ess(tree, method="bulk")
    ess_tail = az.ess(tree, method="tail", prob=(0.05, 0.95))
    rhat = az.rhat(tree)
    params = {}
    for k, x in post.items():
        q05, q95 = np.quantile(x, [0.05, 0.95])
        params[k] = dict(mean=float(x.mean()), sd=float(x.std(ddof=1)), q05=float(q05),
                         q95=float(q95), ess_bulk=float(ess_bulk[k]),
                         ess_tail=float(ess_tail[k]), r_hat=float(rhat[k]))
    extra = mcmc.get_extra_fields()
    wall, compile_s = t_warm + t_draw, c_warm + c_draw
    min_ess = min(p["ess_bulk"] for p in params.values())
    return dict(
        filter=name, params=params,
        divergences=int(np.sum(extra["diverging"])),
        leapfrog_per_draw=float(np.mean(extra["num_steps"])),
        wall_s=wall, warmup_s=t_warm, draws_s=t_draw, compile_s=compile_s,
        ess_per_s=min_ess / wall, ess_per_s_excl_compile=min_ess / (wall - compile_s),
    )


def report(res):
    print(f"{res['filter']}: wall {res['wall_s']:.1f} s (warm-up {res['warmup_s']:.1f} s + "
          f"draws {res['draws_s']:.1f} s; of which JAX trace/compile {res['compile_s']:.1f} s)  "
          f"divergences {res['divergences']}  leapfrog steps/draw {res['leapfrog_per_draw']:.1f}")
    print(f"  min bulk ESS/s {res['ess_per_s']:.2f} (excluding compile "
          f"{res['ess_per_s_excl_compile']:.2f})")
    for k, p in res["params"].items():
        print(f"  {k}  mean {p['mean']:.4f}  sd {p['sd']:.4f}  5% {p['q05']:.4f}  "
              f"95% {p['q95']:.4f}  ESS bulk {p['ess_bulk']:.0f} tail {p['ess_tail']:.0f}  "
              f"R-hat {p['r_hat']:.4f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("csv", nargs="?", default="/tmp/dx/cubic.csv")
    ap.add_argument("--chains", type=int, default=4)
    ap.add_argument("--draws", type=int, default=1000)
    ap.add_argument("--warmup", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--filters", default="EKF,UKF")
    ap.add_argument("--json")
    a = ap.parse_args()
    data = np.genfromtxt(a.csv, delimiter=",", names=True)
    times, z = jnp.asarray(data["t"]), jnp.asarray(data["z1"])
    print(f"dynestyx {dsx.__version__}, {len(z)} measurements on [{times[0]:g}, {times[-1]:g}], "
          f"{a.chains} chains x {a.draws} draws after {a.warmup} warm-up, seed {a.seed}")
    results = []
    for name in a.filters.split(","):
        results.append(run_filter(name, times, z, a.chains, a.draws, a.warmup, a.seed))
        report(results[-1])
    if a.json:
        with open(a.json, "w") as f:
            json.dump(dict(dynestyx=dsx.__version__, data=a.csv, chains=a.chains, draws=a.draws,
                           warmup=a.warmup, seed=a.seed, results=results), f, indent=2)


if __name__ == "__main__":
    main()
