//! The correlated pseudo-marginal method's auxiliary variables (Deligiannidis, Doucet & Pitt
//! 2018, "The correlated pseudomarginal method", JRSS B 80(5), 839–870): the particle filter's
//! random numbers U ~ N(0, I) become part of the chain's state, and each proposal moves them
//! by the Crank–Nicolson step `U' = ρ U + √(1 − ρ²) ε`, ε ~ N(0, I) (their eq. 9), which
//! leaves N(0, I) invariant, so that the acceptance ratio is that of PMMH with the estimates
//! at (θ, U) and (θ', U'). With ρ near 1 the two estimates share most of their noise and
//! their ratio is far less noisy than with fresh random numbers: fewer particles suffice
//! (their §4: N growing like T^{d/(d+1)} instead of T).

use alloc::format;
use alloc::sync::Arc;
use alloc::vec::Vec;

use crate::error::ZakaiError;
use crate::random::{rng_from_seed, standard_normal, NormalZiggurat, SimRng};
use crate::SuppliedNormals;
use rand::Rng;

/// The most auxiliary normals one chain's state may hold (64 MiB of them): each chain keeps
/// its current U and builds a proposal of the same length at every iteration.
pub const MAX_AUXILIARY: usize = 1 << 23;

/// The proposal's auxiliary variables from the current `u`: the Crank–Nicolson step with
/// correlation `rho`, ε from `rng` by `normal`, and a fresh seed for any normals a run reads
/// past them.
pub(super) fn propose(
    u: &SuppliedNormals,
    rho: f64,
    rng: &mut SimRng,
    normal: &NormalZiggurat,
) -> Arc<SuppliedNormals> {
    let held = u.values();
    let mut values = alloc::vec![0.0; held.len()];
    normal.fill(rng, &mut values);
    let s = libm::sqrt(1.0 - rho * rho);
    for (v, x) in values.iter_mut().zip(held) {
        *v = rho * x + s * *v;
    }
    Arc::new(SuppliedNormals::new(values, rng.next_u64()))
}

/// `u` as long as the normals its run read: those it holds, then the ones the run drew from
/// its seed past them (the same draws, so the state's estimate is still the estimate at it).
/// Errors when that is more than [`MAX_AUXILIARY`].
pub(super) fn materialised(
    u: Arc<SuppliedNormals>,
    method: &str,
) -> Result<Arc<SuppliedNormals>, ZakaiError> {
    let (held, used) = (u.values().len(), u.used());
    if used <= held {
        return Ok(u);
    }
    if used > MAX_AUXILIARY {
        return Err(ZakaiError::TooLarge {
            what: format!(
                "correlated pseudo-marginal steps: {method} reads {used} random numbers per run (particles × moves per observation × observations), each chain's state and proposal holding them all"
            ),
            limit: MAX_AUXILIARY,
            unit: "random numbers",
        });
    }
    let mut past = rng_from_seed(u.seed());
    let mut values: Vec<f64> = Vec::with_capacity(used);
    values.extend_from_slice(u.values());
    values.extend((held..used).map(|_| standard_normal(&mut past)));
    Ok(Arc::new(SuppliedNormals::new(values, past.next_u64())))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    /// The Crank–Nicolson step keeps N(0, 1): from standard normals, the proposal's mean and
    /// variance stay 0 and 1 (within 4 standard errors of 10⁵ draws), and its correlation
    /// with the current values is ρ.
    #[test]
    fn the_crank_nicolson_step_keeps_the_standard_normal() {
        let n = 100_000;
        let (mut rng, normal) = (rng_from_seed(3), NormalZiggurat::new());
        let mut x = alloc::vec![0.0; n];
        normal.fill(&mut rng, &mut x);
        let u = SuppliedNormals::new(x.clone(), 1);
        let rho = 0.9;
        let y = propose(&u, rho, &mut rng, &normal);
        let y = y.values();
        let mean = y.iter().sum::<f64>() / n as f64;
        let var = y.iter().map(|v| v * v).sum::<f64>() / n as f64 - mean * mean;
        let cov = x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>() / n as f64;
        let se = 1.0 / libm::sqrt(n as f64);
        assert!(mean.abs() < 4.0 * se, "{mean}");
        assert!((var - 1.0).abs() < 4.0 * libm::sqrt(2.0) * se, "{var}");
        assert!((cov - rho).abs() < 4.0 * se, "{cov}");
    }
}
