//! The kinds of observation noise a scenario may declare (`model.noise.kind`), described once
//! for every form that edits them — the page builds its noise controls from
//! [`noise_kinds`], `zakai list` prints it — with the fields of each kind as
//! [`ObservationNoiseConfig`](super::ObservationNoiseConfig) reads them (a test holds the two
//! together).

use alloc::vec;
use alloc::vec::Vec;

use serde::Serialize;

/// How a form edits one field of a noise kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum NoiseFieldKind {
    /// An m × m matrix (the identity when absent).
    Matrix,
    /// A Gaussian mixture over the m measurement components.
    Mixture,
    /// One number, or an expression in the scenario's parameters.
    Coefficient,
    /// One expression in the state per observation component.
    Expressions,
    /// One expression in the state (`x`, `x1…xn`) and the measurement (`z`, `z1…zm`).
    Expression,
}

/// One field of a noise kind.
#[derive(Clone, Debug, Serialize)]
pub struct NoiseField {
    /// The key in the scenario's `model.noise` object.
    pub key: &'static str,
    /// A label for a form.
    pub label: &'static str,
    /// Its symbol in the formula (a form's per-component labels: `s1(x) = …`).
    pub symbol: &'static str,
    /// What it is, for a tooltip.
    pub title: &'static str,
    /// How it is edited.
    pub kind: NoiseFieldKind,
    /// The value a form starts from when the kind is chosen (text of a number or
    /// expression; for [`NoiseFieldKind::Expressions`] each component's).
    pub default: &'static str,
}

/// One kind of observation noise.
#[derive(Clone, Debug, Serialize)]
pub struct NoiseKind {
    /// `model.noise.kind`.
    pub kind: &'static str,
    /// A short label for a choice list.
    pub label: &'static str,
    /// The measurement equation, in TeX.
    pub formula: &'static str,
    /// What it models and which methods take it.
    pub summary: &'static str,
    /// Whether the observations are continuous increments (else discrete measurements).
    pub continuous: bool,
    /// Its fields.
    pub fields: Vec<NoiseField>,
}

/// Every kind, in the order a form lists them.
pub fn noise_kinds() -> Vec<NoiseKind> {
    vec![
        NoiseKind {
            kind: "continuous",
            label: "continuous dy = h dt + dw",
            formula: r"dy = h(x)\,dt + dw,\quad E[dw\,dw^\top] = S\,dt",
            summary: "increments at every Δτ: the Zakai / Yau–Yau setting (000, 002, 004); every method but the continuous–discrete grid filters and the Gaussian sum",
            continuous: true,
            fields: vec![NoiseField {
                key: "cov",
                symbol: "S",
                label: "S, the observation noise intensity",
                title: "S, the observation noise intensity: E[dw dwᵀ] = S dt",
                kind: NoiseFieldKind::Matrix,
                default: "",
            }],
        },
        NoiseKind {
            kind: "discrete",
            label: "discrete z = h(x) + v",
            formula: r"z_k = h(x_k) + v_k,\quad v_k \sim \textstyle\sum_i w_i N(m_i, P_i)",
            summary: "measurements at every Δτ with additive Gaussian or Gaussian-mixture noise (001, 003): the continuous–discrete grid filters (SA, FDM), the particle, Kalman-type and Gaussian-sum filters",
            continuous: false,
            fields: vec![NoiseField {
                key: "mixture",
                symbol: "v",
                label: "v, the measurement noise: a Gaussian mixture",
                title: "the density of the measurement noise v as a Gaussian mixture: weights, means and covariances",
                kind: NoiseFieldKind::Mixture,
                default: "",
            }],
        },
        NoiseKind {
            kind: "poisson",
            label: "counts z ~ Poisson(h(x))",
            formula: r"z_{k,j} \sim \mathrm{Poisson}\big(h_j(x_k)\big)",
            summary: "counts (spikes, cases, photons) with rate h ≥ 0: exact in the SA, FDM and particle filters; the Kalman-type filters use N(h(x), diag h(x̂⁻)) and warn",
            continuous: false,
            fields: vec![],
        },
        NoiseKind {
            kind: "student_t",
            label: "outliers z = h(x) + σ t_ν",
            formula: r"z_{k,j} = h_j(x_k) + \sigma\, t_{\nu}",
            summary: "heavy-tailed noise: exact in the SA, FDM and particle filters; the Kalman-type filters use its variance σ²ν/(ν−2) (ν > 2) and warn",
            continuous: false,
            fields: vec![
                NoiseField {
                    key: "dof",
                symbol: "ν",
                    label: "ν, degrees of freedom",
                    title: "ν > 0: the smaller, the heavier the tails (ν = 1 is Cauchy; ν → ∞ is Gaussian)",
                    kind: NoiseFieldKind::Coefficient,
                    default: "3",
                },
                NoiseField {
                    key: "scale",
                symbol: "σ",
                    label: "σ, scale",
                    title: "σ > 0: the noise is σ times a standard Student-t variable",
                    kind: NoiseFieldKind::Coefficient,
                    default: "0.3",
                },
            ],
        },
        NoiseKind {
            kind: "heteroscedastic",
            label: "variance s(x): z ~ N(h(x), s(x))",
            formula: r"z_{k,j} \sim N\big(h_j(x_k),\, s_j(x_k)\big)",
            summary: "Gaussian noise whose variance depends on the state (stochastic volatility: h = 0, s = e^x): exact in the SA, FDM and particle filters; the Kalman-type filters use s(x̂⁻) and warn",
            continuous: false,
            fields: vec![NoiseField {
                key: "variance",
                symbol: "s",
                label: "s, the variance",
                title: "s(x) > 0, one expression in the state per observation component",
                kind: NoiseFieldKind::Expressions,
                default: "exp(x)",
            }],
        },
        NoiseKind {
            kind: "log_density",
            label: "log-density log p(z | x)",
            formula: r"\log p(z_k \mid x_k) = \ell(x_k, z_k)",
            summary: "any measurement density, as an expression in x and z: the SA, FDM and particle filters only; it cannot be simulated (load observations)",
            continuous: false,
            fields: vec![NoiseField {
                key: "expression",
                symbol: "ℓ",
                label: "log p(z | x) =",
                title: "one expression in the state (x, or x1…xn) and the measurement (z, or z1…zm)",
                kind: NoiseFieldKind::Expression,
                default: "-abs(z - x)/0.3 - log(0.6)",
            }],
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lab::scenario::ObservationNoiseConfig;
    use crate::testing::test;
    use alloc::string::ToString;

    /// Every kind, with its fields at their defaults, is a noise block the scenario reads
    /// (the catalogue and `ObservationNoiseConfig` agree on keys), and no two kinds share a
    /// key.
    #[test]
    fn every_kind_with_its_defaults_is_a_valid_noise_block() {
        let kinds = noise_kinds();
        for k in &kinds {
            let mut block = serde_json::Map::new();
            block.insert("kind".into(), k.kind.into());
            for f in &k.fields {
                let value = match f.kind {
                    NoiseFieldKind::Matrix => serde_json::json!([[1.0]]),
                    NoiseFieldKind::Mixture => {
                        serde_json::json!([{ "weight": 1.0, "mean": [0.0], "cov": [[1.0]] }])
                    }
                    NoiseFieldKind::Coefficient => {
                        serde_json::json!(f.default.parse::<f64>().expect("a number"))
                    }
                    NoiseFieldKind::Expressions => serde_json::json!([f.default]),
                    NoiseFieldKind::Expression => serde_json::json!(f.default),
                };
                block.insert(f.key.into(), value);
            }
            let read: ObservationNoiseConfig =
                serde_json::from_value(serde_json::Value::Object(block.clone()))
                    .unwrap_or_else(|e| panic!("{}: {e}", k.kind));
            assert_eq!(
                matches!(read, ObservationNoiseConfig::Continuous { .. }),
                k.continuous,
                "{}",
                k.kind
            );
            // Written back, the block names the same kind and fields.
            let written = serde_json::to_value(&read).unwrap();
            assert_eq!(written["kind"], k.kind);
            for f in &k.fields {
                assert!(written.get(f.key).is_some(), "{}.{}", k.kind, f.key);
            }
            assert_eq!(written.as_object().unwrap().len(), k.fields.len() + 1);
        }
        let mut keys: Vec<_> = kinds.iter().map(|k| k.kind.to_string()).collect();
        keys.sort();
        keys.dedup();
        assert_eq!(keys.len(), kinds.len());
    }
}
