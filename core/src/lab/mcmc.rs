//! Convergence diagnostics of Markov chains, for posterior samplers: the rank-normalised
//! split-R̂ and the bulk and tail effective sample sizes of Vehtari, Gelman, Simpson,
//! Carpenter & Bürkner (2021), "Rank-normalization, folding, and localization: an improved R̂
//! for assessing convergence of MCMC", Bayesian Analysis 16, 667–718.
//!
//! * **Split chains**: each of the M chains of N draws is cut in two halves (the middle draw
//!   of an odd N dropped): 2M chains of ⌊N/2⌋.
//! * **Rank normalisation**: every draw replaced by `Φ⁻¹((r − 3/8)/(S + 1/4))`, r its rank
//!   among all S draws (ties averaged).
//! * **R̂** of chains of n draws: `√(var⁺/W)`, W the mean within-chain variance,
//!   `var⁺ = (n − 1)/n W + B/n`, B/n the variance of the chain means. The reported R̂ is the
//!   larger of the rank-normalised split chains' (bulk) and of the rank-normalised folded draws'
//!   `|θ − median θ|` (tail).
//! * **ESS** of chains of n draws: `M n / τ`, `τ = −1 + 2 Σ_k P_k`, with
//!   `P_k = ρ_{2k} + ρ_{2k+1}` summed while positive and made monotone (Geyer's initial
//!   monotone sequence), `ρ_t = 1 − (W − mean_m s²_m ρ_{t,m}) / var⁺` from each chain's
//!   autocorrelations. Bulk: of the rank-normalised split chains; tail: the smaller of the
//!   indicators `θ ≤ q₅ %` and `θ ≤ q₉₅ %` on the split chains.

use alloc::vec::Vec;

use crate::filters::predictive::normal_quantile;

/// R̂ and the effective sample sizes of one quantity's chains.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ChainDiagnostics {
    /// The rank-normalised split-R̂ (the larger of bulk and tail).
    pub rhat: f64,
    /// The bulk effective sample size.
    pub ess_bulk: f64,
    /// The tail effective sample size (5 % and 95 % quantiles).
    pub ess_tail: f64,
}

/// The diagnostics of `chains` (each the draws of one chain, all the same length, at least
/// 4); `None` when there are fewer than 4 draws per chain, chains of unequal lengths, or a
/// value that is not finite.
pub fn diagnose(chains: &[&[f64]]) -> Option<ChainDiagnostics> {
    let n = chains.first()?.len();
    if n < 4
        || chains
            .iter()
            .any(|c| c.len() != n || c.iter().any(|v| !v.is_finite()))
    {
        return None;
    }
    let split = split_chains(chains);
    let all: Vec<f64> = split.iter().flatten().copied().collect();
    let median = quantile(&all, 0.5);
    let folded: Vec<Vec<f64>> = split
        .iter()
        .map(|c| c.iter().map(|v| (v - median).abs()).collect())
        .collect();
    let bulk = rank_normalise(&split);
    let tail_rhat = rhat(&rank_normalise(&folded));
    let indicator = |q: f64| -> Vec<Vec<f64>> {
        split
            .iter()
            .map(|c| c.iter().map(|v| f64::from(u8::from(*v <= q))).collect())
            .collect()
    };
    let (q05, q95) = (quantile(&all, 0.05), quantile(&all, 0.95));
    Some(ChainDiagnostics {
        rhat: rhat(&bulk).max(tail_rhat),
        ess_bulk: ess(&bulk),
        ess_tail: ess(&indicator(q05)).min(ess(&indicator(q95))),
    })
}

/// Each chain cut in two halves (the middle draw of an odd length dropped).
fn split_chains(chains: &[&[f64]]) -> Vec<Vec<f64>> {
    let half = chains[0].len() / 2;
    chains
        .iter()
        .flat_map(|c| [c[..half].to_vec(), c[c.len() - half..].to_vec()])
        .collect()
}

/// The `p`-quantile of `values` (linear interpolation between order statistics).
pub fn quantile(values: &[f64], p: f64) -> f64 {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let at = p * (sorted.len() - 1) as f64;
    let (i, frac) = (libm::floor(at) as usize, at - libm::floor(at));
    match sorted.get(i + 1) {
        Some(next) => sorted[i] + frac * (next - sorted[i]),
        None => sorted[i],
    }
}

/// Every draw replaced by `Φ⁻¹((r − 3/8)/(S + 1/4))`, r its average rank among all S draws.
fn rank_normalise(chains: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let mut order: Vec<(f64, usize, usize)> = chains
        .iter()
        .enumerate()
        .flat_map(|(m, c)| c.iter().enumerate().map(move |(i, v)| (*v, m, i)))
        .collect();
    order.sort_by(|a, b| a.0.total_cmp(&b.0));
    let s = order.len() as f64;
    let mut out: Vec<Vec<f64>> = chains.iter().map(|c| alloc::vec![0.0; c.len()]).collect();
    let mut start = 0;
    while start < order.len() {
        let mut end = start + 1;
        while end < order.len() && order[end].0 == order[start].0 {
            end += 1;
        }
        // Ranks start + 1 … end, averaged over the tie.
        let rank = 0.5 * ((start + 1) + end) as f64;
        let z = normal_quantile((rank - 0.375) / (s + 0.25));
        for &(_, m, i) in &order[start..end] {
            out[m][i] = z;
        }
        start = end;
    }
    out
}

/// The mean and the variance (n − 1) of a chain.
pub fn mean_and_variance(c: &[f64]) -> (f64, f64) {
    let n = c.len() as f64;
    let mean = c.iter().sum::<f64>() / n;
    (
        mean,
        c.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1.0),
    )
}

/// `(W, var⁺)` of chains of equal length.
fn within_and_pooled(chains: &[Vec<f64>]) -> (f64, f64) {
    let n = chains[0].len() as f64;
    let stats: Vec<(f64, f64)> = chains.iter().map(|c| mean_and_variance(c)).collect();
    let w = stats.iter().map(|s| s.1).sum::<f64>() / stats.len() as f64;
    let means: Vec<f64> = stats.iter().map(|s| s.0).collect();
    let b_over_n = if means.len() > 1 {
        mean_and_variance(&means).1
    } else {
        0.0
    };
    (w, (n - 1.0) / n * w + b_over_n)
}

fn rhat(chains: &[Vec<f64>]) -> f64 {
    let (w, var_plus) = within_and_pooled(chains);
    if w <= 0.0 {
        return if var_plus <= 0.0 { 1.0 } else { f64::INFINITY };
    }
    libm::sqrt(var_plus / w)
}

fn ess(chains: &[Vec<f64>]) -> f64 {
    let m = chains.len();
    let n = chains[0].len();
    let (w, var_plus) = within_and_pooled(chains);
    if w <= 0.0 || var_plus <= 0.0 {
        return f64::NAN;
    }
    let centred: Vec<Vec<f64>> = chains
        .iter()
        .map(|c| {
            let mean = c.iter().sum::<f64>() / n as f64;
            c.iter().map(|v| v - mean).collect()
        })
        .collect();
    let variances: Vec<f64> = chains.iter().map(|c| mean_and_variance(c).1).collect();
    let acov =
        |c: &[f64], t: usize| c[t..].iter().zip(c).map(|(a, b)| a * b).sum::<f64>() / n as f64;
    let c0: Vec<f64> = centred.iter().map(|c| acov(c, 0)).collect();
    let rho = |t: usize| -> f64 {
        let mean: f64 = (0..m)
            .map(|k| {
                if c0[k] > 0.0 {
                    variances[k] * acov(&centred[k], t) / c0[k]
                } else {
                    0.0
                }
            })
            .sum::<f64>()
            / m as f64;
        1.0 - (w - mean) / var_plus
    };
    let mut sum = 0.0;
    let mut previous = f64::INFINITY;
    let mut t = 0;
    while t + 1 < n {
        let pair = rho(t) + rho(t + 1);
        if pair <= 0.0 {
            break;
        }
        let pair = pair.min(previous);
        sum += pair;
        previous = pair;
        t += 2;
    }
    // At least 1/log10(M n), as Stan bounds it (antithetic chains).
    let tau = (-1.0 + 2.0 * sum).max(1.0 / libm::log10((m * n) as f64));
    (m * n) as f64 / tau
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    fn normal(rng: &mut crate::random::SimRng) -> f64 {
        use rand::RngExt;
        let (a, b): (f64, f64) = (rng.random(), rng.random());
        libm::sqrt(-2.0 * libm::log(1.0 - a)) * libm::cos(2.0 * core::f64::consts::PI * b)
    }

    /// Four chains of 1000: independent draws mix (R̂ < 1.01, ESS near 4000); an AR(1) with
    /// ρ = 0.9 has ESS near 4000 (1 − ρ)/(1 + ρ) = 211; a chain stuck elsewhere gives R̂ far
    /// above 1. Seeded; the tolerances are those of the estimators' own spread.
    #[test]
    fn rhat_and_ess_tell_mixed_chains_from_stuck_and_correlated_ones() {
        let mut rng = crate::random::rng_from_seed(5);
        let iid: Vec<Vec<f64>> = (0..4)
            .map(|_| (0..1000).map(|_| normal(&mut rng)).collect())
            .collect();
        let d = diagnose(&iid.iter().map(|c| &c[..]).collect::<Vec<_>>()).unwrap();
        assert!(d.rhat < 1.01, "{d:?}");
        assert!((3200.0..4800.0).contains(&d.ess_bulk), "{d:?}");
        assert!((2500.0..5500.0).contains(&d.ess_tail), "{d:?}");
        let ar: Vec<Vec<f64>> = (0..4)
            .map(|_| {
                let mut x = normal(&mut rng) / libm::sqrt(1.0 - 0.81);
                (0..1000)
                    .map(|_| {
                        x = 0.9 * x + normal(&mut rng);
                        x
                    })
                    .collect()
            })
            .collect();
        let d = diagnose(&ar.iter().map(|c| &c[..]).collect::<Vec<_>>()).unwrap();
        assert!((140.0..300.0).contains(&d.ess_bulk), "{d:?}");
        let mut stuck = iid.clone();
        stuck[3].iter_mut().for_each(|v| *v += 2.0);
        let d = diagnose(&stuck.iter().map(|c| &c[..]).collect::<Vec<_>>()).unwrap();
        assert!(d.rhat > 1.2, "{d:?}");
        assert!(diagnose(&[&[1.0, 2.0, 3.0][..]]).is_none());
        assert!(diagnose(&[&[1.0, 2.0, 3.0, 4.0][..], &[1.0, 2.0, 3.0][..]]).is_none());
    }
}
