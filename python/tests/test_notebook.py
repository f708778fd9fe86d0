"""Results that read well in a notebook: every result's repr a line of a few hundred
characters at most (no arrays), and an HTML table for Jupyter."""

import numpy as np
import pytest

import zakai


@pytest.fixture(scope="module")
def level():
    model = zakai.Model.discrete("0", "x", noise_cov="r", diffusion="sqrt(q)")
    sc = zakai.Scenario(model, zakai.Prior.gaussian(0.0, 4.0), ["kalman", "pf"], dt_obs=1.0,
                        t_final=60.0, domain=[(-15, 15)], seed=2,
                        parameters={"q": (0.3, (0, None)), "r": (0.5, (0, None))})
    times, states, z = zakai.simulate(sc)
    return sc, times, states, z


def test_every_result_has_a_short_repr_and_an_html_table(level):
    sc, times, states, z = level
    run = zakai.filter(sc, z, times=times, truth=states, checks=True)
    smoothed = zakai.smooth(sc, z, times=times)
    fit = zakai.fit(sc, z, "kalman", times=times)
    prof = zakai.profile(sc, z, "r", points=5, times=times)
    ahead = zakai.forecast(sc, z, 3, times=times)
    diagnostics = run.methods["KF"].diagnostics()
    shown = [run, run.methods["KF"], smoothed.methods["KF"].smoothed, fit, prof, ahead, diagnostics]
    for obj in shown:
        text = repr(obj)
        assert len(text) < 300, f"{type(obj).__name__}: {len(text)} characters: {text}"
        assert "array(" not in text and "\n" not in text, text
    for obj in [run, fit, prof, ahead, diagnostics]:
        page = obj._repr_html_()
        assert "<table>" in page and len(page) < 20_000, type(obj).__name__
    # The numbers in the table are the result's.
    assert f"{fit.params['q']:.6g}" in fit._repr_html_()
    assert f"{run.methods['KF'].mse:.4g}" in run._repr_html_()
    # Found by catalogue key as by display name.
    assert run.methods["kalman"] is run.methods["KF"]
    assert np.isfinite(fit.aic) and fit.bic > fit.aic


def test_a_filter_pickles_and_steps_on_identically(level):
    import pickle

    sc, times, states, z = level
    model = zakai.Model.discrete("0", "x", noise_cov=0.5, diffusion=0.6)
    for method in ("kalman", "pf", "separation"):
        f = zakai.Filter(method, model, zakai.Prior.gaussian(0.0, 4.0), dt_obs=1.0,
                         domain=[(-15, 15)], seed=9)
        f.run(z[:20, 0])
        f.predict(0.5)
        f.step([z[20, 0]], 0.5)
        twin = pickle.loads(pickle.dumps(f))
        np.testing.assert_array_equal(twin.mean, f.mean)
        for k in range(21, 30):
            f.step([z[k, 0]])
            twin.step([z[k, 0]])
        # The same bits after the same steps (the particle filter's draws included).
        np.testing.assert_array_equal(twin.mean, f.mean)
        np.testing.assert_array_equal(twin.cov, f.cov)
        assert twin.log_likelihood == f.log_likelihood
        # A copy pickles too; a forecast's origin (a run's state) says why it does not.
        assert pickle.loads(pickle.dumps(f.copy())).mean[0] == f.mean[0]
    origin = zakai.forecast(sc, z, 2, times=times)._origin
    with pytest.raises(TypeError, match="forecast's origin"):
        pickle.dumps(origin)


def test_results_plot_with_matplotlib(level):
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    sc, times, states, z = level
    run = zakai.filter(sc, z, times=times, truth=states, checks=True)
    figures = [
        run.plot(),
        run.methods["KF"].plot(),
        run.methods["KF"].diagnostics().plot(),
        zakai.forecast(sc, z, 5, times=times).plot(),
        zakai.profile(sc, z, "r", points=5, times=times).plot(),
        zakai.fit(sc, z, "kalman", times=times).plot(points=7),
    ]
    for fig in figures:
        assert isinstance(fig, matplotlib.figure.Figure)
        assert sum(len(ax.lines) + len(ax.collections) + len(ax.patches) for ax in fig.axes) > 0
    # The run's figure draws every method and the truth, the diagnostics' four panels.
    assert len(figures[0].axes[0].lines) == 1 + len(run.methods)
    assert len(figures[2].axes) == 4
    assert len(figures[5].axes) == 2  # one profile per fitted parameter (q, r)
    plt.close("all")


def test_the_example_notebook_runs(tmp_path):
    """python/examples/nile.ipynb, executed cell by cell in a fresh kernel: every cell runs
    without an error (its outputs are not kept in the repository)."""
    import pathlib

    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("matplotlib")
    path = pathlib.Path(__file__).parents[1] / "examples" / "nile.ipynb"
    nb = nbformat.read(path, as_version=4)
    assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code"), "outputs committed"
    client = nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
    shown = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs]
    # The notebook's tables are HTML (the results' _repr_html_), its plots images.
    assert any("text/html" in o.get("data", {}) for o in shown)
    assert any("image/png" in o.get("data", {}) for o in shown)


def test_densities_over_time_are_kept_and_drawn(level):
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    sc, times, states, z = level
    grid = np.linspace(-6, 6, 121)
    run = zakai.filter(sc, z, times=times, density_grid=grid)
    kf = run.methods["KF"]
    assert kf.densities.shape == (len(times), len(grid))
    # The Kalman filter's density is the Gaussian of its estimate, row by row.
    sd = kf.sds[:, 0]
    gauss = np.exp(-0.5 * ((grid[None, :] - kf.estimates[:, :1]) / sd[:, None]) ** 2) / (
        sd[:, None] * np.sqrt(2 * np.pi))
    np.testing.assert_allclose(kf.densities, gauss, rtol=1e-9, atol=1e-12)
    # Every method's integrates to about one on the grid.
    for m in run.methods.values():
        mass = np.trapezoid(m.densities, grid, axis=1)
        assert np.all(np.abs(mass - 1) < 0.05), (m.name, mass.min(), mass.max())
    fig = kf.plot()
    assert len(fig.axes) == 2 and len(fig.axes[1].collections) == 1
    plt.close("all")
    with pytest.raises(zakai.ConfigError, match="marginals"):
        zakai.filter(sc, z, times=times, density_grid=grid, density_dim=3)
