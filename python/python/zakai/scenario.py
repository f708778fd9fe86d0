"""A scenario — model, prior, domain, time steps, seed and methods — as the JSON the command
line and the playground read (:class:`Scenario`), the presets, and the method catalogue."""

from __future__ import annotations

import json as _json
from typing import Any, Mapping, Optional, Sequence, Union

from . import _zakai
from .errors import ConfigError
from ._convert import ArrayLike, MethodSpec, _vector, _domain
from .models import Model, Prior






def presets() -> list[str]:
    """Names of the built-in scenarios (the papers' examples), in the command line's order."""
    return [name for name, _ in _zakai.presets()]



def set_memory_cap(cap: Union[int, str]) -> int:
    """Sets the largest memory a scenario's methods may need together — bytes, or text such
    as ``"8GiB"`` (default 1 GiB, the playground's cap). Scenarios are checked against it
    before anything is allocated (:class:`ConfigError`). Returns the previous cap in bytes."""
    return _zakai.set_memory_cap(cap)



def methods() -> list[dict[str, Any]]:
    """Every method: ``key``, names, paper, parameter schema and ``defaults``."""
    return _json.loads(_zakai.catalogue_json())


def noise_kinds() -> list[dict[str, Any]]:
    """Every kind of observation noise a scenario may declare (``model.noise.kind``):
    ``kind``, ``label``, ``formula`` (TeX), ``summary`` (what it models, which methods take
    it), ``continuous`` and its ``fields`` (``key``, ``label``, ``symbol``, ``title``,
    ``kind``, ``default``) — the catalogue the playground's form and ``zakai list`` use. The
    :class:`Model` constructors build each of them."""
    return _json.loads(_zakai.noise_kinds_json())



def _method_config(spec: MethodSpec) -> dict[str, Any]:
    """A full method config from a key (``"pf"``) or a dict ``{"method": "pf", ...}``."""
    if isinstance(spec, str):
        key, params = spec, {}
    elif isinstance(spec, Mapping):
        params = dict(spec)
        key = params.pop("method", None)
        if not isinstance(key, str):
            raise ConfigError("a method dict needs a 'method' key, e.g. {'method': 'pf'}")
    else:
        raise ConfigError(f"a method is a key or a dict, not {type(spec).__name__}")
    return _json.loads(_zakai.method_defaults_json(key, _json.dumps(params)))



# The numbers of each prior kind, in the order a tuple gives them (``("lognormal", 7.0, 1.0)``).
_PRIOR_FIELDS = {
    "uniform": (),
    "normal": ("mean", "sd"),
    "lognormal": ("mu", "sigma"),
    "gamma": ("shape", "rate"),
    "inverse_gamma": ("shape", "scale"),
    "half_normal": ("sd",),
    "beta": ("a", "b"),
}


def _prior(name: str, prior: Any) -> dict[str, Any]:
    """A parameter's prior as JSON, from a dict or a tuple ``(kind, number, …)``."""
    if isinstance(prior, Mapping):
        return dict(prior)
    if isinstance(prior, str):
        prior = (prior,)
    if not isinstance(prior, (tuple, list)) or not prior or prior[0] not in _PRIOR_FIELDS:
        raise ConfigError(
            f"parameters.{name}.prior: give (kind, numbers…) with kind one of "
            f"{', '.join(_PRIOR_FIELDS)}, got {prior!r}"
        )
    kind, *numbers = prior
    fields = _PRIOR_FIELDS[kind]
    if len(numbers) != len(fields):
        raise ConfigError(
            f"parameters.{name}.prior: {kind} takes {len(fields)} number(s) "
            f"({', '.join(fields) or 'none: it is on the bounds'}), got {len(numbers)}"
        )
    return {"kind": kind, **{f: float(v) for f, v in zip(fields, numbers)}}


def _parameter(name: str, value: Any) -> dict[str, Any]:
    """One parameter's JSON from a value, ``(value, (lo, hi))``, ``(value, (lo, hi), prior)``
    or a dict (its ``"prior"`` a dict or a tuple ``(kind, numbers…)``)."""
    if isinstance(value, Mapping):
        out = dict(value)
        if out.get("prior") is not None:
            out["prior"] = _prior(name, out["prior"])
        return out
    bounds = None
    prior = None
    if isinstance(value, (tuple, list)):
        if len(value) not in (2, 3):
            raise ConfigError(
                f"parameters.{name}: give a value, (value, (lower, upper)) or "
                f"(value, (lower, upper), prior), got {value!r}"
            )
        value, bounds, *rest = value
        prior = rest[0] if rest else None
        if bounds is not None:
            lo, hi = bounds
            bounds = [None if lo is None else float(lo), None if hi is None else float(hi)]
    try:
        v = float(value)
    except (TypeError, ValueError) as e:
        raise ConfigError(f"parameters.{name}: the value must be a number, got {value!r}") from e
    out: dict[str, Any] = {"value": v}
    if bounds is not None:
        out["bounds"] = bounds
    if prior is not None:
        out["prior"] = _prior(name, prior)
    return out



class Scenario:
    """A model, prior, domain, time grid and methods: what one run needs.

    The same JSON as the command line's scenario files and the playground's "copy link".
    Fields a user changes most are attributes (``dt_obs``, ``t_final``, ``seed``, ``domain``,
    ``methods``, ``initial_state``); everything else through :attr:`config` (a dict). The
    constructor checks the whole scenario (every expression parsed, every name, dimension
    and bound) and raises :class:`ConfigError` with all problems at once and their field
    paths; a later assignment is checked when the scenario is used (or by :meth:`validate`).

    Parameters
    ----------
    model : Model
    prior : Prior
    methods : list of str or dict
        Method keys (``"ukf"``, ``"pf"``, ``"qiem"``, …, see :func:`methods`) or dicts
        ``{"method": "pf", "particles": 1000}``; parameters left out take their defaults,
        sizes left unset are chosen from the problem.
    dt_obs, t_final : float
        Observation interval Δτ and horizon T (simulations; a recording brings its own times).
    domain : list of (low, high), optional
        The box the grid and spectral methods live on; ``prior mean ± 8 sd`` when absent —
        and, for a 1-D state with Gaussian measurements, narrowed on data to where the
        measurements put it (h within 5 noise sds of their range, widened by the state's
        motion) when that is less than half the prior's box, by :func:`filter`, :func:`smooth`,
        :func:`fit` (whose results' ``chosen_defaults`` then say so), :func:`profile` and
        :func:`log_likelihood` — not by a stepping :class:`Filter`, which sees no data up
        front, nor after a JSON round trip (:meth:`copy` keeps it). A diffuse prior's ±8 sd
        would otherwise leave the posterior between cells; where the data cannot narrow the
        box and a grid method cannot resolve the posterior to expect on it, those functions
        raise :class:`ConfigError` asking for a domain.
    initial_state : array_like, optional
        x₀ of simulations; drawn from the prior when absent.
    parameters : dict, optional
        Named parameters the model's expressions and coefficients may use (the unknowns
        :func:`zakai.fit` estimates): ``{"q": 0.5}``, ``{"q": (0.5, (0, None))}`` with bounds
        (``None`` an open side) or ``{"q": {"value": 0.5, "bounds": [0, None]}}``. Use them
        in expressions (``"-theta*x"``) and in the diffusion, noise covariance and prior as
        text (``diffusion="sqrt(q)"``, ``noise_cov="r"``).
    """

    # The box set around the prior when no domain was given (issue 56): a run on data then
    # narrows it to where the measurements put the state (``_text_for``).
    _prior_box: Optional[list[list[float]]] = None

    def __init__(
        self,
        model: Model,
        prior: Prior,
        methods: Sequence[MethodSpec] = ("ukf",),
        *,
        dt_obs: float = 0.01,
        t_final: float = 1.0,
        domain: Optional[Sequence[Sequence[float]]] = None,
        initial_state: Optional[ArrayLike] = None,
        seed: int = 0,
        name: str = "custom",
        parameters: Optional[Mapping[str, Any]] = None,
    ) -> None:
        prior_box = domain is None
        if domain is None:
            domain = prior.covering_domain()
            if domain is None:
                raise ConfigError(
                    "domain: a density prior needs the domain it lives on"
                    if prior.config.get("kind") == "density"
                    else "domain: none given, and none can be set around this prior"
                )
        self.config: dict[str, Any] = {
            "name": name,
            "model": dict(model.config),
            "prior": dict(prior.config),
            "initial_state": None if initial_state is None else _vector(initial_state, "initial_state"),
            "domain": _domain(domain),
            "time": {"t_final": float(t_final), "dt_obs": float(dt_obs), "inner_steps": 1},
            "seed": int(seed),
            "failure": {"divergence_bound": None, "track_loss": None},
            "methods": [_method_config(m) for m in methods],
        }
        if parameters:
            self.parameters = parameters
        if prior_box:
            self._prior_box = [list(b) for b in self.config["domain"]]
        # Checked where the mistake is made (issue 56): every expression parsed, every name,
        # dimension and bound, all problems at once with their field paths.
        self.validate()

    @classmethod
    def from_json(cls, text: str) -> "Scenario":
        """A scenario from its JSON text (a scenario file, ``zakai show``); checked at once."""
        scenario = cls.__new__(cls)
        normalised, _, _ = _zakai.check_scenario(text)
        scenario.config = _json.loads(normalised)
        return scenario

    @classmethod
    def from_preset(cls, name: str) -> "Scenario":
        """A built-in scenario (see :func:`presets`), e.g. ``"cubic-sensor-1d"``."""
        return cls.from_json(_zakai.preset_json(name))

    def to_json(self, indent: Optional[int] = 2) -> str:
        """The scenario as JSON, readable by ``zakai run <file>`` and the playground."""
        return _json.dumps(self.config, indent=indent, ensure_ascii=False)

    def copy(self) -> "Scenario":
        """An independent copy."""
        copied = Scenario.from_json(self.to_json())
        copied._prior_box = self._prior_box
        return copied

    def validate(self) -> "Scenario":
        """Raises :class:`ConfigError` listing every problem; returns the scenario."""
        _zakai.check_scenario(self._text())
        return self

    def _text(self) -> str:
        return _json.dumps(self.config)

    def _text_for(self, observations: Any, times: Any) -> tuple[str, Optional[str]]:
        """The JSON for a run on ``observations`` (arrays as the extension takes them) and a
        note: when the domain is still the box the constructor set around the prior and the
        measurements put a 1-D state in less than half of it, that narrower box (where h is
        within 5 noise sds of the measured range, widened by the state's motion) — a diffuse
        prior's ±8 sd would leave the posterior between cells. Where the data cannot narrow
        it (n > 1, continuous observations, a non-Gaussian noise) and a grid method cannot
        resolve the posterior to expect on the prior's box, :class:`ConfigError` asks for a
        domain."""
        if self._prior_box is None or self.config["domain"] != self._prior_box:
            return self._text(), None
        found = _zakai.domain_from_data(self._text(), observations, times)
        if found is None:
            return self._text(), None
        domain, note = found
        config = dict(self.config)
        config["domain"] = [list(b) for b in domain]
        return _json.dumps(config), note

    @property
    def name(self) -> str:
        """The scenario's name."""
        return self.config["name"]

    @property
    def dt_obs(self) -> float:
        """Δτ, the observation interval."""
        return self.config["time"]["dt_obs"]

    @dt_obs.setter
    def dt_obs(self, value: float) -> None:
        self.config["time"]["dt_obs"] = float(value)

    @property
    def t_final(self) -> float:
        """T, the horizon of simulations."""
        return self.config["time"]["t_final"]

    @t_final.setter
    def t_final(self, value: float) -> None:
        self.config["time"]["t_final"] = float(value)

    @property
    def parameters(self) -> dict[str, dict[str, Any]]:
        """The named parameters, ``{name: {"value": v, "bounds": [lo, hi]}}`` (a copy; assign
        to change them)."""
        return _json.loads(_json.dumps(self.config.get("parameters", {})))

    @parameters.setter
    def parameters(self, value: Mapping[str, Any]) -> None:
        self.config["parameters"] = {str(k): _parameter(k, v) for k, v in dict(value).items()}

    @property
    def seed(self) -> int:
        """The default seed of :func:`simulate`, :func:`run` and :func:`monte_carlo`."""
        return self.config["seed"]

    @seed.setter
    def seed(self, value: int) -> None:
        self.config["seed"] = int(value)

    @property
    def domain(self) -> list[list[float]]:
        """The box ``[[low, high], …]`` of the grid and spectral methods."""
        return self.config["domain"]

    @domain.setter
    def domain(self, value: Sequence[Sequence[float]]) -> None:
        self.config["domain"] = _domain(value)
        self._prior_box = None  # the user's box, kept as given

    @property
    def initial_state(self) -> Optional[list[float]]:
        """x₀ of simulations, or ``None`` (drawn from the prior)."""
        return self.config["initial_state"]

    @initial_state.setter
    def initial_state(self, value: Optional[ArrayLike]) -> None:
        self.config["initial_state"] = None if value is None else _vector(value, "initial_state")

    @property
    def methods(self) -> list[dict[str, Any]]:
        """The methods' configs (dicts; edit them in place or assign a new list of keys or
        dicts)."""
        return self.config["methods"]

    @methods.setter
    def methods(self, value: Sequence[MethodSpec]) -> None:
        self.config["methods"] = [_method_config(m) for m in value]

    @property
    def method_names(self) -> list[str]:
        """Display names with the sizes that matter (``"PF(200)"``), after validation."""
        return _zakai.check_scenario(self._text())[1]

    @property
    def chosen_defaults(self) -> list[str]:
        """Notes of the sizes chosen from the problem (e.g. the spectral basis)."""
        return _zakai.check_scenario(self._text())[2]

    @property
    def n(self) -> int:
        """State dimension."""
        return len(self.config["model"]["drift"])

    @property
    def m(self) -> int:
        """Observation dimension."""
        return len(self.config["model"]["observation"])

    def __repr__(self) -> str:
        keys = ", ".join(m["method"] for m in self.methods)
        return f"Scenario({self.name!r}, n={self.n}, m={self.m}, methods=[{keys}])"
