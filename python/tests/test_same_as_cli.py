"""The same seed gives the same numbers in Python as on the command line, to the last bit."""

import json
import subprocess

import numpy as np
import pytest

import zakai

SEED = 5


def _csv(path):
    return np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


@pytest.mark.parametrize("preset", ["cubic-sensor-1d", "bearings-only"])
def test_simulation_and_every_method_match_the_cli(cli, tmp_path, preset):
    obs_csv, truth_csv = tmp_path / "obs.csv", tmp_path / "truth.csv"
    subprocess.run(
        [cli, "simulate", preset, "--seed", str(SEED), "--format", "csv",
         "--out", obs_csv, "--truth-out", truth_csv],
        check=True,
    )
    out = subprocess.run(
        [cli, "filter", preset, "--observations", obs_csv, "--truth", truth_csv,
         "--seed", str(SEED), "--format", "json"],
        check=True, capture_output=True, text=True,
    ).stdout
    from_cli = json.loads(out)

    times, states, observations = zakai.simulate(preset, seed=SEED)
    obs, truth = _csv(obs_csv), _csv(truth_csv)
    # The CSV carries every digit (Rust's shortest round-trip formatting).
    assert np.array_equal(obs[:, 0], times)
    assert np.array_equal(truth[:, 1:], states)
    assert np.array_equal(obs[:, 1:], observations)

    result = zakai.run(preset, seed=SEED)
    assert [m.name for m in result.methods.values()] == [m["name"] for m in from_cli["methods"]]
    compared = 0
    for ours, theirs in zip(result.methods.values(), from_cli["methods"]):
        rows = len(theirs["estimates"]) // states.shape[1]
        assert np.array_equal(ours.estimates[:rows].ravel(), np.array(theirs["estimates"]))
        # after a failure the rows are NaN, before it every row is there
        assert np.isnan(ours.estimates[rows:]).all()
        assert (ours.failure is None) == (theirs["failure"] is None)
        # The MSE bit for bit, or absent on both sides (a failed method has none).
        assert ours.mse == theirs["mse"]
        compared += rows
    assert compared > len(times)


def test_filter_on_simulated_arrays_equals_run():
    sc = zakai.Scenario.from_preset("cubic-sensor-1d")
    times, states, observations = zakai.simulate(sc, seed=SEED)
    run = zakai.run(sc, seed=SEED)
    # the layout simulate returns, and the N increments alone
    for obs in (observations, observations[1:]):
        rec = zakai.filter(sc, obs, times=times, truth=states, seed=SEED)
        for key, m in run.methods.items():
            assert np.array_equal(m.estimates, rec.methods[key].estimates, equal_nan=True), key
            assert m.mse == rec.methods[key].mse


def test_stepping_filter_equals_the_driver():
    """`Filter` gets the random numbers of the first method of a run with the same seed."""
    sc = zakai.Scenario.from_preset("cubic-sensor-1d")
    sc.methods = [{"method": "pf", "particles": 300}]
    sc.config["failure"]["track_loss"] = None
    times, states, observations = zakai.simulate(sc, seed=SEED)
    run = zakai.run(sc, seed=SEED)
    model = zakai.Model(sc.config["model"])
    prior = zakai.Prior(sc.config["prior"])
    f = zakai.Filter("pf", model, prior, dt_obs=sc.dt_obs, domain=sc.domain, seed=SEED, particles=300)
    means, covs = f.run(observations[1:])
    assert np.array_equal(means, run.methods["PF(300)"].estimates[1:])
    assert np.array_equal(covs, run.methods["PF(300)"].covariances[1:])
