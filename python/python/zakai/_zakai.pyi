"""Type stubs of the compiled core (`zakai._zakai`); use the `zakai` package above it."""

from typing import Any, Callable, Optional, Union

import numpy as np
import numpy.typing as npt

__version__: str

def presets() -> list[tuple[str, str]]: ...
def preset_json(name: str) -> str: ...
def catalogue_json() -> str: ...
def noise_kinds_json() -> str: ...
def check_scenario(json: str) -> tuple[str, list[str], list[str]]: ...
def covering_domain(prior: str, sds: float) -> Optional[list[list[float]]]: ...
def set_memory_cap(cap: Union[int, str]) -> int: ...
def method_defaults_json(key: str, params: str) -> str: ...
def simulate(
    json: str, seed: int
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64]]: ...
def run(json: str, seed: int) -> dict[str, Any]: ...
def filter_recorded(
    json: str,
    observations: npt.NDArray[np.float64],
    times: Optional[npt.NDArray[np.float64]],
    truth: Optional[npt.NDArray[np.float64]],
    seed: int,
    smooth: bool = False,
    inputs: Optional[npt.NDArray[np.float64]] = None,
    checks: bool = False,
    marginals: Optional[tuple[int, list[float]]] = None,
) -> dict[str, Any]: ...
def ljung_box(errors: list[float], lags: int) -> Optional[tuple[float, float, int]]: ...
def pit_uniformity(pit: list[float]) -> Optional[tuple[float, float, int]]: ...
def forecast_recorded(
    json: str,
    observations: npt.NDArray[np.float64],
    times: Optional[npt.NDArray[np.float64]],
    seed: int,
    steps: int,
    dt: float,
    level: float,
    inputs: Optional[npt.NDArray[np.float64]] = None,
) -> tuple[float, str, dict[str, Any], "Stepper"]: ...
def monte_carlo_json(
    json: str, runs: int, seed: int, progress: Optional[Callable[[int, int], Any]] = None
) -> str: ...
def run_json(json: str, seed: int) -> str: ...
def monte_carlo_from_runs(json: str, runs: list[str], seed: int) -> str: ...
def log_likelihood(
    json: str,
    observations: npt.NDArray[np.float64],
    times: Optional[npt.NDArray[np.float64]],
    method: int,
    names: list[str],
    seed: int,
    point: list[float],
    inputs: Optional[npt.NDArray[np.float64]] = None,
) -> float: ...
def scenario_log_likelihood(
    json: str,
    observations: npt.NDArray[np.float64],
    times: Optional[npt.NDArray[np.float64]],
    method: int,
    seed: int,
    inputs: Optional[npt.NDArray[np.float64]] = None,
) -> tuple[float, Optional[str]]: ...
def fit(
    json: str,
    observations: npt.NDArray[np.float64],
    times: Optional[npt.NDArray[np.float64]],
    method: int,
    names: list[str],
    seed: int,
    evaluator: Optional[Any] = None,
) -> dict[str, Any]: ...
def sample(
    json: str,
    observations: npt.NDArray[np.float64],
    times: Optional[npt.NDArray[np.float64]],
    method: int,
    names: list[str],
    seed: int,
    draws: int,
    warmup: int,
    chains: int,
    sampler: str,
    common: bool,
    fit_start: bool,
    evaluator: Optional[Any] = None,
    inputs: Optional[npt.NDArray[np.float64]] = None,
    surrogate: Optional[int] = None,
) -> str: ...
def prior_density(json: str, lo: float, hi: float, x: list[float]) -> list[float]: ...
def profile(
    json: str,
    observations: npt.NDArray[np.float64],
    times: Optional[npt.NDArray[np.float64]],
    parameter: str,
    values: Optional[list[float]],
    points: int,
    seed: int,
    refit: list[str],
    evaluator: Optional[Any] = None,
) -> tuple[list[float], list[dict[str, Any]]]: ...

class Stepper:
    def __init__(self, scenario: str, seed: int) -> None: ...
    def step(self, observation: npt.NDArray[np.float64], dt: float) -> None: ...
    def run(
        self, observations: npt.NDArray[np.float64], dts: npt.NDArray[np.float64]
    ) -> tuple[npt.NDArray[np.float64], Optional[npt.NDArray[np.float64]]]: ...
    @property
    def name(self) -> str: ...
    @property
    def n(self) -> int: ...
    @property
    def m(self) -> int: ...
    @property
    def continuous(self) -> bool: ...
    @property
    def chosen_defaults(self) -> list[str]: ...
    @property
    def warnings(self) -> list[str]: ...
    @property
    def mean(self) -> npt.NDArray[np.float64]: ...
    @property
    def cov(self) -> Optional[npt.NDArray[np.float64]]: ...
    @property
    def map(self) -> Optional[npt.NDArray[np.float64]]: ...
    @property
    def footprint(self) -> Optional[dict[str, Any]]: ...
    def self_check(self) -> list[dict[str, Any]]: ...
    def forecast(self, steps: int, dt: float, level: float) -> dict[str, Any]: ...
    def density(self, grid: npt.NDArray[np.float64], dim: int = 0) -> npt.NDArray[np.float64]: ...
    def density2d(
        self,
        xs: npt.NDArray[np.float64],
        ys: npt.NDArray[np.float64],
        dims: tuple[int, int] = (0, 1),
    ) -> npt.NDArray[np.float64]: ...
