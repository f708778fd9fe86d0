"""The model and the prior: :class:`Model` (drift f, observation h, diffusion G and the
observation noise, as text expressions) and :class:`Prior` (the density of x₀), as the Rust
core's ``Model`` and ``Prior``."""

from __future__ import annotations

import json as _json
from dataclasses import dataclass
from typing import Any, Iterable, Optional, Sequence, Union

from . import _zakai
from ._convert import ArrayLike, _matrix, _vector, _strings, _positive_definite

#: Half-width of the domain chosen around the prior when none is given, in prior sds.
DOMAIN_SDS: float = 8.0


@dataclass(frozen=True)
class Model:
    """A model ``dx = f(x) dt + G dv`` observed continuously (``dy = h(x) dt + dw``) or at
    discrete times (``z_k = h(x_k) + v_k``).

    Build it with :meth:`continuous` or :meth:`discrete`. Expressions are text in ``x``
    (``x1 … xn`` when n > 1) with ``+ - * / ^``, ``sin cos tan exp log sqrt tanh abs`` and
    friends; they are compiled once, with exact derivatives, in Rust.
    """

    config: dict[str, Any]

    @classmethod
    def continuous(
        cls,
        drift: Union[str, Sequence[str]],
        observation: Union[str, Sequence[str]],
        diffusion: Optional[ArrayLike] = None,
        noise_cov: Optional[ArrayLike] = None,
    ) -> "Model":
        """``dx = f dt + G dv``, ``dy = h dt + dw`` with ``E[dw dwᵀ] = S dt``.

        Parameters
        ----------
        drift, observation : str or list of str
            f and h, one expression per component.
        diffusion : array_like, optional
            G (n × n rows; a scalar when n = 1); the identity when absent.
        noise_cov : array_like, optional
            S; the identity when absent.
        """
        cov = None if noise_cov is None else _matrix(noise_cov, "noise_cov")
        return cls._of(drift, observation, diffusion, {"kind": "continuous", "cov": cov})

    @classmethod
    def discrete(
        cls,
        drift: Union[str, Sequence[str]],
        observation: Union[str, Sequence[str]],
        noise_cov: ArrayLike,
        diffusion: Optional[ArrayLike] = None,
    ) -> "Model":
        """``dx = f dt + G dv`` measured as ``z_k = h(x_k) + v_k``, ``v_k ~ N(0, R)``.

        Parameters
        ----------
        noise_cov : array_like
            R (m × m; a scalar when m = 1).
        """
        m = len(_strings(observation, "observation"))
        gaussian = {"weight": 1.0, "mean": [0.0] * m, "cov": _matrix(noise_cov, "noise_cov")}
        return cls._of(drift, observation, diffusion, {"kind": "discrete", "mixture": [gaussian]})

    @classmethod
    def _of(cls, drift: Any, observation: Any, diffusion: Any, noise: dict) -> "Model":
        """The model of these texts, diffusion and noise block (of the scenario JSON)."""
        return cls(
            {
                "drift": _strings(drift, "drift"),
                "observation": _strings(observation, "observation"),
                "diffusion": None if diffusion is None else _matrix(diffusion, "diffusion"),
                "noise": noise,
            }
        )



@dataclass(frozen=True)
class Prior:
    """The density of x₀: :meth:`gaussian`, :meth:`mixture` or :meth:`density` (text)."""

    config: dict[str, Any]

    @classmethod
    def gaussian(cls, mean: ArrayLike, cov: ArrayLike) -> "Prior":
        """N(mean, cov); a scalar cov is a variance when n = 1."""
        c = _matrix(cov, "prior cov")
        _positive_definite(c, "prior cov")
        return cls({"kind": "gaussian", "mean": _vector(mean, "prior mean"), "cov": c})

    @classmethod
    def mixture(cls, components: Iterable[tuple[float, ArrayLike, ArrayLike]]) -> "Prior":
        """Σ wᵢ N(meanᵢ, covᵢ) from ``(weight, mean, cov)`` triples (weights normalised)."""
        return cls(
            {
                "kind": "mixture",
                "components": [
                    {
                        "weight": float(w),
                        "mean": _vector(m, f"prior component {i} mean"),
                        "cov": _positive_definite(
                            _matrix(c, f"prior component {i} cov"), f"prior component {i} cov"
                        ),
                    }
                    for i, (w, m, c) in enumerate(components)
                ],
            }
        )

    @classmethod
    def density(cls, expression: str) -> "Prior":
        """An unnormalised density as text, restricted to the domain (give one)."""
        return cls({"kind": "density", "expression": expression})

    def covering_domain(self, sds: float = DOMAIN_SDS) -> Optional[list[list[float]]]:
        """``mean ± sds·sd`` per component (every mixture component covered), or ``None``
        for a density prior."""
        return _zakai.covering_domain(_json.dumps(self.config), float(sds))
