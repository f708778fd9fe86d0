"""The Python surface: scenarios, own models, stepping filters, Monte Carlo tables."""

import subprocess
import sys

import numpy as np
import pytest

import zakai


def test_presets_and_scenario_round_trip():
    names = zakai.presets()
    assert "cubic-sensor-1d" in names and len(names) >= 10
    sc = zakai.Scenario.from_preset("cubic-sensor-1d")
    again = zakai.Scenario.from_json(sc.to_json())
    assert again.config == sc.config
    sc.dt_obs, sc.t_final = 0.02, 1.0
    sc.methods = ["ukf", {"method": "pf", "particles": 321}]
    assert sc.method_names == ["UKF", "PF(321)"]
    times, states, obs = zakai.simulate(sc, seed=2)
    assert times.shape == (51,) and states.shape == (51, 1) and obs.shape == (51, 1)
    assert np.allclose(np.diff(times), 0.02) and obs[0, 0] == 0.0


def test_own_linear_model_grid_filter_matches_kalman_bucy():
    """QIEM on the domain chosen from the prior (mean ± 8 sd) against the exact filter."""
    model = zakai.Model.continuous("-x", "x", diffusion=0.8)
    prior = zakai.Prior.gaussian(0.5, 0.2)
    sc = zakai.Scenario(model, prior, ["kalman", {"method": "qiem", "points": [801]}],
                        dt_obs=0.01, t_final=2.0, initial_state=[0.5])
    lo, hi = sc.domain[0]
    assert lo == pytest.approx(0.5 - 8 * np.sqrt(0.2)) and hi == pytest.approx(0.5 + 8 * np.sqrt(0.2))
    result = zakai.run(sc, seed=4)
    kb, qiem = result.methods["KF"], result.methods["QIEM"]
    assert qiem.failure is None and not qiem.concerns
    # The exact filter of the sampled model, written here: x' = e^{−Δ}x + noise of variance
    # 0.64(1 − e^{−2Δ})/2, then the increment Δy = x'Δ + w, Var w = Δ (S = 1).
    dt = 0.01
    a, q = np.exp(-dt), 0.64 * (1 - np.exp(-2 * dt)) / 2
    m, p = 0.5, 0.2
    means, sds = [m], [np.sqrt(p)]
    for dy in result.observations[1:, 0]:
        m, p = a * m, a * a * p + q
        s = dt * dt * p + dt
        gain = p * dt / s
        m, p = m + gain * (dy - dt * m), p - gain * dt * p
        means.append(m)
        sds.append(np.sqrt(p))
    means, sds = np.array(means), np.array(sds)
    # Zakai's Kalman–Bucy filter is this filter (to rounding); QIEM on 801 points agrees with it
    # to about 1e-3 (README; measured 3.3e-4 in the mean, 2.3e-4 in the sd): tolerance 1e-3.
    assert np.max(np.abs(kb.estimates[:, 0] - means)) < 1e-9
    assert np.max(np.abs(kb.sds[:, 0] - sds)) < 1e-9
    assert np.max(np.abs(qiem.estimates[:, 0] - means)) < 1e-3
    assert np.max(np.abs(qiem.sds[:, 0] - sds)) < 1e-3


def test_stepping_filter_mean_cov_density_and_batch_run():
    model = zakai.Model.continuous("0", "x^3")
    prior = zakai.Prior.gaussian(1.0, 0.1)
    sc = zakai.Scenario(model, prior, ["qiem"], dt_obs=0.01, t_final=1.0, domain=[(-4, 4)])
    times, states, obs = zakai.simulate(sc, seed=3)
    one = zakai.Filter("qiem", model, prior, dt_obs=0.01, domain=[(-4, 4)])
    for dy in obs[1:]:
        one.step(dy)
    batch = zakai.Filter("qiem", model, prior, dt_obs=0.01, domain=[(-4, 4)])
    means, covs = batch.run(obs[1:])
    assert np.array_equal(means[-1], one.mean) and np.array_equal(covs[-1], one.cov)
    grid = np.linspace(-4, 4, 2001)
    p = one.density(grid)
    assert p.shape == grid.shape and np.all(p >= 0)
    assert np.trapezoid(p, grid) == pytest.approx(1.0, abs=1e-3)
    assert np.trapezoid(grid * p, grid) == pytest.approx(one.mean[0], abs=1e-3)
    assert one.name == "QIEM" and one.self_check() == []


def test_the_tensor_train_filter_reports_what_it_holds():
    """Four independent cubic sensors stay a product: rank one, 4 × 32 numbers for a grid of
    32⁴ points; a Kalman-type filter holds no compressed density."""
    d = 4
    model = zakai.Model.continuous([f"-0.4*x{i}" for i in range(1, d + 1)],
                                   [f"x{i}^3" for i in range(1, d + 1)])
    prior = zakai.Prior.gaussian([1.0] * d, np.eye(d) * 0.5)
    tt = zakai.Filter("tensor_train", model, prior, dt_obs=0.01, points=[32],
                      domain=[(-4, 4)] * d)
    for _ in range(5):
        tt.step(np.full(d, 0.01))
    f = tt.footprint
    assert f["numbers"] == 4 * 32 and f["grid_points"] == 32.0 ** 4
    assert f["ranks"] == [1] * 5 and f["peak_ranks"] == [1] * 5
    assert zakai.Filter("ukf", model, prior, dt_obs=0.01).footprint is None


def test_density2d_shape_and_mass():
    model = zakai.Model.continuous(["0", "0"], ["x1", "x2"])
    f = zakai.Filter("ukf", model, zakai.Prior.gaussian([0, 1], [[1, 0.3], [0.3, 0.5]]), dt_obs=0.1)
    xs, ys = np.linspace(-6, 6, 241), np.linspace(-5, 7, 121)
    d = f.density2d(xs, ys)
    assert d.shape == (121, 241)
    assert np.trapezoid(np.trapezoid(d, xs, axis=1), ys) == pytest.approx(1.0, abs=1e-3)


def test_spectral_default_basis_is_chosen_from_the_problem_and_reported():
    """The rule (the spectral filter's docs): N = ⌈4 L / σ₀⌉ Legendre functions for the
    domain's half-width L and the prior's sd σ₀, at least 004's 16 and at most 128 — checked
    here on a case of each kind against the size the filter reports it chose."""
    model = zakai.Model.continuous("tanh(x)", "x")
    for half, variance, expected in [(12, 0.25, 96), (2, 1.0, 16), (12, 0.01, 128)]:
        rule = min(max(int(np.ceil(4 * half / np.sqrt(variance))), 16), 128)
        assert rule == expected
        f = zakai.Filter(
            "spectral", model, zakai.Prior.gaussian(0.0, variance), dt_obs=0.01,
            domain=[(-half, half)],
        )
        notes = [n for n in f.chosen_defaults if "basis" in n]
        assert len(notes) == 1 and f"basis {rule} per dimension" in notes[0], f.chosen_defaults


def test_self_checks_warn_with_the_number():
    """A particle filter measuring sharply (R = 1e-6 against a prior sd of 2) collapses onto a
    few particles: its effective-sample-size check says so, with the value."""
    sc = zakai.Scenario(zakai.Model.discrete("0", "x", noise_cov=1e-6), zakai.Prior.gaussian(0, 4),
                        [{"method": "pf", "particles": 1000}],
                        dt_obs=0.1, t_final=1.0, initial_state=[1.0])
    result = zakai.run(sc, seed=1)
    pf = result.methods["PF(1000)"]
    assert pf.warned
    c = pf.concerns[0]
    assert c["steps"] > 0 and c["worst"] < c["threshold"] and c["check"] in c["text"]


def test_monte_carlo_table_pandas_and_parallel():
    sc = zakai.Scenario.from_preset("cubic-sensor-1d")
    sc.t_final = 1.0
    sc.methods = ["ukf", {"method": "pf", "particles": 200}]
    table = zakai.monte_carlo(sc, runs=8, seed=10)
    assert [r["name"] for r in table.rows] == ["UKF", "PF(200)"]
    assert all(r["runs"] == 8 for r in table.rows)
    # the table's MSE is the mean over the runs of each run's MSE
    single = [zakai.run(sc, seed=s).methods["PF(200)"].mse for s in range(10, 18)]
    assert table.rows[1]["mse"] == pytest.approx(np.mean(single), rel=1e-12)
    assert "PF(200)" in str(table) and table.how_means_are_taken in str(table)
    # failed runs sit beside the MSE (the UKF loses the cubic sensor in some runs)
    for r in table.rows:
        assert ("†" in r["mse_text"]) == (0 < r["failed"] < r["runs"]), r["mse_text"]
    pd = pytest.importorskip("pandas")
    frame = table.to_pandas()
    assert isinstance(frame, pd.DataFrame) and frame.loc["PF(200)", "runs"] == 8


# The GIL test's body, run in a child interpreter: a build that held the GIL through the runs
# would leave its threads waiting for it for ever, and only a process can be stopped then.
GIL_PROBE = """
import sys, threading
import zakai

sc = zakai.Scenario.from_preset("cubic-sensor-1d")
sc.methods = [{"method": "pf", "particles": 200}]
started, main_ran = threading.Event(), threading.Event()
callers, seen = [], []

def progress(done, runs):
    callers.append(threading.get_ident())
    started.set()
    seen.append(main_ran.wait(timeout=120))

out = {}

def job():
    out["caller"] = threading.get_ident()
    out["table"] = zakai.monte_carlo(sc, runs=8, seed=1, progress=progress)

worker = threading.Thread(target=job, daemon=True)
worker.start()
if not started.wait(timeout=120):
    sys.exit("no progress callback: the GIL was never released")
main_ran.set()
worker.join(timeout=300)
if worker.is_alive():
    sys.exit("the Monte Carlo job did not finish")
assert len(callers) == 8 and all(seen), seen
# Every callback came from a thread of the Rust job, not the Python thread that called it.
assert out["caller"] not in callers, "a callback ran on the calling thread"
assert out["table"].rows[0]["runs"] == 8
print("ok")
"""


def test_monte_carlo_releases_the_gil():
    """The runs take place on Rust's own threads with the GIL released: each progress callback
    (made from one of those threads, which must take the GIL to make it) waits for an event
    that only the main thread sets, after it has seen a callback begin. Were the GIL held by
    the calling thread through the runs, no callback could start (the threads would wait for
    the GIL for ever): the child process would not finish and the timeout fails the test. No
    clock is read; the timeouts only keep a broken build from hanging the suite."""
    try:
        done = subprocess.run(
            [sys.executable, "-c", GIL_PROBE], capture_output=True, text=True, timeout=600
        )
    except subprocess.TimeoutExpired:
        pytest.fail("the Monte Carlo job never let another Python thread run (GIL held?)")
    assert done.returncode == 0 and done.stdout.strip() == "ok", done.stdout + done.stderr


def test_a_progress_callback_that_raises_stops_nothing_and_is_raised():
    sc = zakai.Scenario.from_preset("cubic-sensor-1d")
    sc.methods = [{"method": "pf", "particles": 100}]
    calls = []

    def progress(done, runs):
        calls.append((done, runs))
        raise ValueError("from the callback")

    with pytest.raises(ValueError, match="from the callback"):
        zakai.monte_carlo(sc, runs=3, seed=1, progress=progress)
    assert sorted(calls) == [(1, 3), (2, 3), (3, 3)]
    with pytest.raises(zakai.ConfigError, match="progress"):
        zakai.monte_carlo(sc, runs=3, seed=1, progress=3)


def test_monte_carlo_table_names_coinciding_rows_and_paper_values():
    sc = zakai.Scenario.from_preset("cubic-sensor-1d")
    sc.methods = [m for m in sc.methods if m["method"] in ("qiem", "iem", "pf")]
    table = zakai.monte_carlo(sc, runs=2, seed=1)
    assert any(n.startswith("IEM = QIEM in every run") for n in table.notes())
    frame = pytest.importorskip("pandas") and table.to_pandas()
    assert frame.loc["PF(200)", "paper_text"] == "0.9115 (MSE)"
    assert frame.loc["QIEM", "paper_text"] == ""
