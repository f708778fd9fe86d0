"""Known inputs from Python: the Nile with the Aswan dam as an input. The flow's level drops
around 1899 (Cobb 1978; Durbin & Koopman's intervention example); a local level measured as
``z = x + b·u1 + v`` with ``u1`` = 0 before 1899 and 1 from then on is statsmodels'
``UnobservedComponents(..., exog=u1)``, whose maximum-likelihood estimate is the reference
for Zakai's fit (EKF: exact on this linear model). Then the layouts ``inputs=`` takes
(arrays, a DataFrame), a simulated driven run filtered back, a stepping ``Filter`` given its
time and inputs, and the errors."""

import numpy as np
import pandas as pd
import pytest

import zakai
from zakai.errors import DimensionError


PRIOR = (1120.0, 1e7)


def nile(sm):
    """The Nile's annual flow 1871–1970 (statsmodels' copy), 1890–1892 unknown, and the dam
    input: 1 from 1899 on."""
    data = sm.datasets.nile.load_pandas().data
    years = data["year"].to_numpy(dtype=float)
    flow = data["volume"].to_numpy(dtype=float).copy()
    flow[(years >= 1890) & (years <= 1892)] = np.nan
    dam = (years >= 1899).astype(float)
    return years, flow, dam


def intervention(methods=("ekf",), q=1000.0, r=10000.0, b=0.0):
    """dx = √q dW, z = x + b u1 + v with Var v = r: q, r and b the unknowns."""
    model = zakai.Model.discrete("0", "x + b*u1", noise_cov="r", diffusion="sqrt(q)")
    return zakai.Scenario(
        model.with_inputs("0"),
        zakai.Prior.gaussian(PRIOR[0], PRIOR[1]),
        list(methods),
        dt_obs=1.0,
        domain=[(-2000, 4000)],
        parameters={
            "q": (q, (0, None)),
            "r": (r, (0, None)),
            "b": (b, (None, None)),
        },
    )


def test_the_dam_is_statsmodels_intervention_estimate(sm):
    years, flow, dam = nile(sm)
    # Zakai gets the year 1900 dropped (a step of two years); statsmodels has it missing.
    keep = years != 1900
    fitted = zakai.fit(
        intervention(), flow[keep], "ekf", times=years[keep], inputs=dam[keep]
    )
    sm_flow = flow.copy()
    sm_flow[years == 1900] = np.nan
    mod = sm.tsa.UnobservedComponents(sm_flow, "llevel", exog=dam)
    mod.ssm.initialize_known(np.array([PRIOR[0]]), np.array([[PRIOR[1]]]))
    res = mod.fit(disp=False, method="nm", maxiter=20000, xtol=1e-10, ftol=1e-12)
    r_sm, q_sm, b_sm = res.params  # sigma2.irregular, sigma2.level, beta.x1
    print(fitted)
    print("statsmodels", q_sm, r_sm, b_sm, res.llf)
    assert fitted.params["b"] == pytest.approx(b_sm, rel=1e-3)
    assert fitted.params["r"] == pytest.approx(r_sm, rel=1e-3)
    # With the dam as an input the level needs no noise of its own: both fits put q at its
    # bound 0 (Zakai 1.7e-6, statsmodels 5e-13, against 1002 without the input).
    assert fitted.params["q"] < 1e-2 and q_sm < 1e-2
    # The dam lowered the flow: b is negative by more than three standard errors.
    assert fitted.params["b"] < -3 * fitted.stderr["b"]
    # The same function: statsmodels leaves out the first observation, ln N(z; 1120, 10⁷ + r).
    s = PRIOR[1] + fitted.params["r"]
    first = -0.5 * (np.log(2 * np.pi * s) + (flow[0] - PRIOR[0]) ** 2 / s)
    same_point = mod.loglike([fitted.params["r"], fitted.params["q"], fitted.params["b"]])
    assert fitted.loglik - first == pytest.approx(same_point, rel=1e-9)
    # Without the input the best fit is worse by more than 3 log-likelihood units (measured
    # 9.4: ln L −617.2 against −607.8).
    without = zakai.fit(
        intervention(), flow[keep], "ekf", params=["q", "r"], times=years[keep],
        inputs=np.zeros(keep.sum()),
    )
    assert fitted.loglik - without.loglik > 3.0


def test_filter_takes_a_dataframe_and_the_grid_filter_agrees(sm):
    years, flow, dam = nile(sm)
    keep = years != 1900
    sc = intervention(("ekf", "separation"), q=1400.0, r=15000.0, b=-250.0)
    inputs = pd.DataFrame({"u1": dam[keep]}, index=years[keep])
    r = zakai.filter(sc, pd.Series(flow[keep], index=years[keep]), inputs=inputs)
    ekf, sa = r.methods["EKF"], r.methods["SA"]
    assert ekf.failure is None and sa.failure is None
    # The exact filter, written here: the level's variance grows by q per year (two over the
    # dropped 1900), and z − b·u1 measures it with variance r.
    m, p = PRIOR
    means, sds = [], []
    for k, (zk, uk) in enumerate(zip(flow[keep], dam[keep])):
        if k:
            p += 1400.0 * (years[keep][k] - years[keep][k - 1])
        if not np.isnan(zk):
            gain = p / (p + 15000.0)
            m, p = m + gain * (zk - (-250.0) * uk - m), p * (1 - gain)
        means.append(m)
        sds.append(np.sqrt(p))
    means, sds = np.array(means), np.array(sds)
    # The EKF is that filter on this linear model (to rounding; its moments integrate
    # exactly); the separation filter on its default grid is within 0.06 of its sd
    # (measured 0.030).
    assert np.max(np.abs(ekf.estimates[:, 0] - means) / sds) < 1e-6
    gap = np.max(np.abs(sa.estimates[:, 0] - means) / sds)
    print(f"SA {gap:.4f} sd from the exact filter")
    assert gap < 0.06, gap
    # x is the level the dam did not change: z − b u1 ≈ x, so after 1899 the filtered
    # level sits near the flow plus 250 (the last flows are near 800; the level near 1050).
    assert abs(ekf.estimates[-1, 0] - (np.nanmean(flow[-10:]) + 250.0)) < 150.0


def test_a_simulated_driven_run_filters_back():
    model = zakai.Model.discrete("-x + 2*u1", "x", noise_cov=0.1, diffusion=0.5)
    sc = zakai.Scenario(
        model.with_inputs("sin(0.5*t)"),
        zakai.Prior.gaussian(0.0, 1.0),
        ["ekf", "kalman"],
        dt_obs=0.25,
        t_final=12.0,
        domain=[(-6, 6)],
    )
    t, x, z, u = zakai.simulate(sc, 4, with_inputs=True)
    assert u.shape == (len(t), 1)
    assert u[0, 0] == 0.0 and u[1, 0] == pytest.approx(np.sin(0.5 * 0.125), abs=1e-15)
    with pytest.warns(zakai.FilterWarning, match="KF failed at row 0"):
        r = zakai.filter(sc, z, times=t, truth=x, inputs=u)
    assert r.methods["EKF"].mse < 0.1
    assert "time-invariant" in r.methods["KF"].failure[2]
    with pytest.warns(zakai.FilterWarning, match="KF failed at row 0"):
        flipped = zakai.filter(sc, z, times=t, truth=x, inputs=-u)
    assert flipped.methods["EKF"].mse > 2 * r.methods["EKF"].mse


def test_missing_or_misshapen_inputs_are_refused(sm):
    years, flow, dam = nile(sm)
    sc = intervention()
    with pytest.raises(DimensionError, match="known inputs"):
        zakai.filter(sc, flow, times=years)
    with pytest.raises(DimensionError, match="input rows"):
        zakai.filter(sc, flow, times=years, inputs=dam[:-1])
    with pytest.raises(DimensionError, match="column"):
        zakai.filter(sc, flow, times=years, inputs=np.c_[dam, dam])
    bad = dam.copy()
    bad[5] = np.nan
    with pytest.raises(zakai.errors.ZakaiError, match="u1"):
        zakai.filter(sc, flow, times=years, inputs=bad)


def test_a_filter_steps_with_its_time_and_inputs():
    model = zakai.Model.discrete("-x + 2*u1", "x", noise_cov=0.1, diffusion=0.5)
    model = model.with_inputs("0")
    pushed = zakai.Filter("ukf", model, zakai.Prior.gaussian(0.0, 1.0), dt_obs=0.5)
    idle = pushed.copy()
    with pytest.raises(zakai.errors.FilterError, match="inputs"):
        pushed.step([0.0], 0.5)
    # Nothing observed, the input on: the mean moves towards 2u = 2 as 2(1 − e^{−t}) (up to
    # the RK4 steps of the moment equations: 2·10⁻⁶ relative measured).
    pushed.predict(0.5, t=0.5, u=[1.0])
    idle.predict(0.5, t=0.5, u=[0.0])
    assert float(pushed.mean[0]) == pytest.approx(2 * (1 - np.exp(-0.5)), rel=1e-5)
    assert float(idle.mean[0]) == pytest.approx(0.0, abs=1e-12)
    pushed.step([1.0], 0.5, t=1.0, u=[1.0])
    assert pushed.log_likelihood is not None and np.isfinite(pushed.log_likelihood)
