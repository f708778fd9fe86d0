# %% [markdown]
# # A tour of zakai from Python
#
# Notebook-style (the `# %%` cells open as a notebook in Jupyter/VS Code); the test command
# runs it as a script. The cubic sensor of Shi, Chen & Yau (2021), Example 1: a random walk
# `dx = dv` seen through `dy = x³ dt + dw`. Near x = 0 the observation is flat (h′(x) = 3x² → 0),
# so filters that linearise lose the state and the posterior turns bimodal.

# %%
import numpy as np

import zakai

model = zakai.Model.continuous(drift="0", observation="x^3")
prior = zakai.Prior.gaussian(mean=1.0, cov=0.1)
scenario = zakai.Scenario(
    model,
    prior,
    methods=["ekf", "ukf", {"method": "pf", "particles": 1000}, "qiem", "spectral"],
    dt_obs=0.01,
    t_final=5.0,
    domain=[(-4.0, 4.0)],
    initial_state=[1.0],
)
print(scenario)
print("sizes chosen from the problem:", scenario.chosen_defaults)

# %% [markdown]
# ## Simulate, then filter the arrays
# `simulate` returns NumPy arrays; `filter` takes any observations of the same layout — yours
# as well (increments Δy per interval for continuous models, measurements for discrete ones).

# %%
times, states, observations = zakai.simulate(scenario, seed=3)
print("times", times.shape, "states", states.shape, "observations", observations.shape)

result = zakai.filter(scenario, observations, times=times, truth=states, seed=3)
print(result.table())

qiem = result.methods["QIEM"]
print("QIEM sd at the end:", qiem.sds[-1], " MSE:", qiem.mse)
for name, m in result.methods.items():
    if m.failure is not None:
        k, t, why = m.failure
        print(f"{name} failed at t = {t:.2f}: {why}")
    for concern in m.concerns:
        print(f"{name} warned: {concern['text']}")

# %% [markdown]
# ## One filter, one observation at a time
# A `Filter` is stepped by hand — the shape a real-time loop has. The density is the
# filter's own (a grid here), on any points.

# %%
f = zakai.Filter("qiem", model, prior, dt_obs=0.01, domain=[(-4.0, 4.0)], points=[401])
for dy in observations[1:]:
    f.step(dy)
grid = np.linspace(-4.0, 4.0, 801)
density = f.density(grid)
print(f"{f.name}: mean {f.mean[0]:+.4f}, sd {np.sqrt(f.cov[0, 0]):.4f}, "
      f"mass {np.trapezoid(density, grid):.6f}, truth {states[-1, 0]:+.4f}")
assert abs(np.trapezoid(density, grid) - 1.0) < 1e-3

# %% [markdown]
# ## Monte Carlo: the papers' table
# Runs in parallel on every core with the GIL released; with pandas it is a DataFrame.

# %%
scenario.t_final = 2.0
table = zakai.monte_carlo(scenario, runs=16, seed=100)
print(table)
try:
    print(table.to_pandas()[["mse_text", "paper_text"]])
except ImportError:
    pass

# %% [markdown]
# ## Errors are exceptions with the position
# %%
try:
    zakai.Filter("ukf", zakai.Model.continuous("-x^^3", "x"), prior, dt_obs=0.01)
except zakai.ExpressionError as e:
    print("ExpressionError:", e)
