"""Bad input raises an exception of zakai.errors with the command line's message."""

import json

import numpy as np
import pytest

import zakai
from zakai.errors import ConfigError, DimensionError, ExpressionError, FilterError, ZakaiError


def test_expression_error_names_the_field_and_position():
    # Refused where the mistake is made (issue 56, item 5): the Model constructor parses
    # every expression; names, which may be a scenario's parameters, wait for the Scenario.
    with pytest.raises(ExpressionError) as e:
        zakai.Model.continuous(["x +* 2"], ["x"])
    assert "model.drift" in str(e.value) and "position" in str(e.value)
    assert e.value.problems and e.value.problems[0][0].startswith("model.drift")
    assert isinstance(e.value, ValueError) and isinstance(e.value, ZakaiError)
    with pytest.raises(ExpressionError, match=r"position 3 .*`\(` is never closed"):
        zakai.Model.discrete("exp(x", "x", noise_cov=1.0)
    with pytest.raises(ExpressionError, match=r"`\*\*` is not an operator here: write powers with `\^`"):
        zakai.Model.discrete("-x**3", "x", noise_cov=1.0)
    model = zakai.Model.discrete("-thta*x", "x", noise_cov=1.0)  # a name: the scenario's to check
    with pytest.raises(ConfigError, match="unknown variable `thta`"):
        zakai.Scenario(model, zakai.Prior.gaussian(0, 1), parameters={"theta": 1.0})


def test_the_prior_constructors_check_what_they_are_given():
    # Issue 56, item 5: a density prior's syntax at once, with its field and position; its
    # names wait for the scenario (the state's names depend on the model).
    with pytest.raises(ExpressionError, match=r"prior.expression: .*position"):
        zakai.Prior.density("exp(-x^2")
    with pytest.raises(ExpressionError, match=r"`\*\*` is not an operator here"):
        zakai.Prior.density("exp(-x**2)")
    zakai.Prior.density("exp(-(x1^2 + x2^2))")  # names: the scenario's to check
    with pytest.raises(ConfigError, match="component 1 weight: must be nonnegative and finite, got -0.5"):
        zakai.Prior.mixture([(1.0, 0.0, 1.0), (-0.5, 1.0, 1.0)])
    with pytest.raises(ConfigError, match="positive finite sum, got 0.0"):
        zakai.Prior.mixture([(0.0, 0.0, 1.0)])
    with pytest.raises(ConfigError, match="component 0 weight: a number, not 'a'"):
        zakai.Prior.mixture([("a", 0.0, 1.0)])
    with pytest.raises(ConfigError, match="needs at least one"):
        zakai.Prior.mixture([])


def test_unknown_variable_is_an_expression_error():
    with pytest.raises(ExpressionError, match="unknown variable `y`"):
        zakai.Filter("ukf", zakai.Model.continuous("y", "x"), zakai.Prior.gaussian(0, 1), dt_obs=0.1)


def test_every_config_problem_at_once_with_field_paths():
    sc = zakai.Scenario.from_preset("cubic-sensor-1d")
    sc.methods[2]["particles"] = 0
    sc.dt_obs = -1.0
    with pytest.raises(ConfigError) as e:
        zakai.run(sc)
    fields = [f for f, _ in e.value.problems]
    assert "methods[2].particles" in fields and "time.dt_obs" in fields


def test_unknown_preset_method_and_parameter():
    with pytest.raises(ConfigError, match="unknown preset `nope`"):
        zakai.Scenario.from_preset("nope")
    with pytest.raises(ConfigError, match="unknown method `kf2`"):
        zakai.Filter("kf2", zakai.Model.continuous("0", "x"), zakai.Prior.gaussian(0, 1), dt_obs=0.1)
    with pytest.raises(ConfigError, match="has no parameter `particle`"):
        zakai.Filter("pf", zakai.Model.continuous("0", "x"), zakai.Prior.gaussian(0, 1), dt_obs=0.1,
                     particle=10)


def test_invalid_json_is_a_config_error():
    with pytest.raises(ConfigError, match="invalid scenario JSON"):
        zakai.Scenario.from_json('{"name": 1}')
    text = zakai.Scenario.from_preset("cubic-sensor-1d").to_json()
    broken = json.loads(text)
    broken["model"]["noise"] = {"kind": "loud"}
    with pytest.raises(ConfigError, match="loud"):
        zakai.Scenario.from_json(json.dumps(broken))


def test_wrong_shapes_are_dimension_errors():
    sc = zakai.Scenario.from_preset("cubic-sensor-1d")
    times, states, obs = zakai.simulate(sc, seed=1)
    with pytest.raises(DimensionError, match="column"):
        zakai.filter(sc, np.zeros((len(times) - 1, 2)), times=times)
    with pytest.raises(DimensionError, match="increment rows"):
        zakai.filter(sc, obs[2:], times=times)
    with pytest.raises(DimensionError, match="truth"):
        zakai.filter(sc, obs, times=times, truth=states[1:])
    f = zakai.Filter("ukf", zakai.Model.continuous("0", "x"), zakai.Prior.gaussian(0, 1), dt_obs=0.1)
    with pytest.raises(DimensionError, match="m = 1"):
        f.step([0.1, 0.2])
    with pytest.raises(DimensionError, match="component 1"):
        f.density(np.linspace(-1, 1, 5), dim=1)


def test_bad_times_and_steps_are_config_errors():
    sc = zakai.Scenario.from_preset("cubic-sensor-1d")
    times, _, obs = zakai.simulate(sc, seed=1)
    bad = times.copy()
    bad[3] = bad[2]
    with pytest.raises(ConfigError, match="times"):
        zakai.filter(sc, obs, times=bad)
    f = zakai.Filter("ukf", zakai.Model.continuous("0", "x"), zakai.Prior.gaussian(0, 1), dt_obs=0.1)
    with pytest.raises(ConfigError, match="dt"):
        f.step([0.1], float("nan"))
    with pytest.raises(ConfigError, match="seed"):
        zakai.run(sc, seed=-1)


def test_a_grid_filter_takes_another_interval_and_refuses_a_bad_one_keeping_its_state():
    f = zakai.Filter("qiem", zakai.Model.continuous("0", "x"), zakai.Prior.gaussian(0, 1),
                     dt_obs=0.01, points=[201])
    f.step([0.01])
    before = f.mean.copy()
    for bad in (-0.01, float("nan"), float("inf")):
        with pytest.raises((FilterError, ConfigError)):
            f.step([0.01], bad)
        assert np.array_equal(f.mean, before)
    with pytest.raises(FilterError):
        f.step([float("inf")], 0.01)
    assert np.array_equal(f.mean, before)
    f.step([0.01], 0.025)  # two Δτ and a remainder
    assert not np.array_equal(f.mean, before)


def test_grids_beyond_the_memory_cap_are_refused_before_allocating():
    previous = zakai.set_memory_cap("1MiB")
    try:
        with pytest.raises(ConfigError, match="memory"):
            zakai.Filter("qiem", zakai.Model.continuous(["0", "0"], ["x1", "x2"]),
                         zakai.Prior.gaussian([0, 0], np.eye(2)), dt_obs=0.01, points=[2001, 2001])
    finally:
        zakai.set_memory_cap(previous)
    with pytest.raises(ConfigError, match="memory_cap"):
        zakai.set_memory_cap("lots")
