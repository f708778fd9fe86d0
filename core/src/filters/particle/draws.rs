//! Where the particle filter's random numbers come from: its own seeded generator, or a
//! vector of standard normals supplied from outside, the auxiliary variables U of the
//! correlated pseudo-marginal method (Deligiannidis, Doucet & Pitt 2018, "The correlated
//! pseudomarginal method", JRSS B 80(5), §2): the likelihood estimate is then a function
//! L̂(θ, U) of the parameters and U ~ N(0, I), and a sampler that moves U by
//! `U' = ρ U + √(1 − ρ²) ε` correlates the estimates of successive proposals.
//!
//! Every random number the filter uses is read from U in order: the prior's draws
//! ([`crate::Prior::sample_from_normals`]), the Euler–Maruyama (or exact-transition)
//! normals, a mixture's component picks and each resampling's uniform as Φ(z). Resampling
//! sorts the particles first ([`hilbert_order`], §4.1 of the paper), so that a small change of
//! θ or U moves the estimate a little instead of reshuffling the ancestors. A run that needs
//! more normals than U holds draws the rest from a generator of its own seed, fresh at every
//! proposal (an independent refresh of those coordinates, which keeps the method exact);
//! [`SuppliedNormals::used`] says how many a run read, so that U can be made that long.

use alloc::sync::Arc;
use alloc::vec::Vec;
use core::sync::atomic::{AtomicUsize, Ordering};

use nalgebra::DVector;
use rand::{Rng, RngExt};

use crate::model::Prior;
use crate::random::{rng_from_seed, NormalZiggurat, SimRng};

/// The auxiliary standard normals U of one likelihood estimate
/// ([`crate::filters::method::BuildContext::supplied`]), and a seed for the normals a run
/// reads beyond them.
#[derive(Debug)]
pub struct SuppliedNormals {
    values: Vec<f64>,
    seed: u64,
    used: AtomicUsize,
}

impl SuppliedNormals {
    /// U from `values` (standard normals), with `seed` for any normals a run reads past them.
    pub fn new(values: Vec<f64>, seed: u64) -> Self {
        SuppliedNormals {
            values,
            seed,
            used: AtomicUsize::new(0),
        }
    }

    /// The normals held.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// The seed of the normals a run reads past those held.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// The most normals any run on these has read (those held and those drawn past them).
    pub fn used(&self) -> usize {
        self.used.load(Ordering::Relaxed)
    }
}

/// The filter's source of random numbers.
#[derive(Clone, Debug)]
pub(super) enum Draws {
    /// Its own generator.
    Generated(SimRng),
    /// The supplied U read from position `at`, then `past` (a generator of U's seed).
    Supplied {
        normals: Arc<SuppliedNormals>,
        at: usize,
        past: SimRng,
    },
}

impl Draws {
    /// A generator from `seed`, or U when one is supplied.
    pub(super) fn new(seed: u64, supplied: Option<&Arc<SuppliedNormals>>) -> Self {
        match supplied {
            None => Draws::Generated(rng_from_seed(seed)),
            Some(u) => Draws::Supplied {
                normals: u.clone(),
                at: 0,
                past: rng_from_seed(u.seed),
            },
        }
    }

    /// Whether the numbers come from a supplied U (resampling then sorts the particles).
    pub(super) fn is_supplied(&self) -> bool {
        matches!(self, Draws::Supplied { .. })
    }

    /// Fills `out` with standard normals (the generator's by the ziggurat `normal`).
    pub(super) fn normals(&mut self, normal: &NormalZiggurat, out: &mut [f64]) {
        match self {
            Draws::Generated(rng) => normal.fill(rng, out),
            Draws::Supplied { .. } => self.supplied(out),
        }
    }

    /// Fills `out` from the supplied normals (nothing for a generator).
    fn supplied(&mut self, out: &mut [f64]) {
        match self {
            Draws::Generated(_) => {}
            Draws::Supplied { normals, at, past } => {
                let held = normals.values.len();
                let from = (*at).min(held);
                let take = (held - from).min(out.len());
                out[..take].copy_from_slice(&normals.values[from..from + take]);
                for v in &mut out[take..] {
                    *v = crate::random::standard_normal(past);
                }
                *at += out.len();
                normals.used.fetch_max(*at, Ordering::Relaxed);
            }
        }
    }

    /// One uniform on [0, 1): the generator's, or Φ(z) of the next normal of U.
    pub(super) fn uniform(&mut self) -> f64 {
        match self {
            Draws::Generated(rng) => rng.random(),
            Draws::Supplied { .. } => {
                let mut z = [0.0];
                self.supplied(&mut z);
                // Φ(z) = erfc(−z/√2)/2, kept below 1.
                (0.5 * libm::erfc(-z[0] * core::f64::consts::FRAC_1_SQRT_2)).min(1.0 - f64::EPSILON)
            }
        }
    }

    /// One draw of x₀ from `prior`: by the generator, or from n + 1 normals of U.
    pub(super) fn prior_draw(&mut self, prior: &Prior, z: &mut Vec<f64>) -> DVector<f64> {
        match self {
            Draws::Generated(rng) => prior.sample(rng),
            Draws::Supplied { .. } => {
                z.resize(prior.dim() + 1, 0.0);
                self.supplied(z);
                prior.sample_from_normals(z)
            }
        }
    }

    /// A seed for another generator derived from this one (the smoother's), which leaves
    /// this one where it is.
    pub(super) fn derived_seed(&self) -> u64 {
        match self {
            Draws::Generated(rng) => rng.clone().next_u64(),
            Draws::Supplied { at, past, .. } => past.clone().next_u64() ^ *at as u64,
        }
    }
}

/// The order of N particles (component j of particle i at `particles[j * N + i]`) along a
/// curve through the state space, into `order`: by value in one dimension, along the Hilbert
/// curve in more (Deligiannidis, Doucet & Pitt 2018, §4.1; Gerber & Chopin 2015 map the
/// cloud to the unit cube by a logistic function of each standardised component, as here).
/// `keys` is work space.
pub(super) fn hilbert_order(
    particles: &[f64],
    n: usize,
    order: &mut Vec<usize>,
    keys: &mut Vec<u128>,
) {
    let count = particles.len() / n.max(1);
    order.clear();
    order.extend(0..count);
    if n == 1 {
        order.sort_unstable_by(|&a, &b| particles[a].total_cmp(&particles[b]));
        return;
    }
    let bits = (128 / n).min(32) as u32;
    let cells = (1u64 << bits) as f64;
    keys.clear();
    keys.resize(count, 0);
    let mut coords = alloc::vec![0u64; n];
    let moments: Vec<(f64, f64)> = (0..n)
        .map(|j| {
            let x = &particles[j * count..(j + 1) * count];
            let mean = x.iter().sum::<f64>() / count as f64;
            let var = x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / count as f64;
            (mean, if var > 0.0 { libm::sqrt(var) } else { 1.0 })
        })
        .collect();
    for (i, key) in keys.iter_mut().enumerate() {
        for (j, c) in coords.iter_mut().enumerate() {
            let (mean, sd) = moments[j];
            let s = 1.0 / (1.0 + libm::exp(-(particles[j * count + i] - mean) / sd));
            *c = ((s * cells) as u64).min((1u64 << bits) - 1);
        }
        *key = hilbert_index(&mut coords, bits);
    }
    order.sort_unstable_by_key(|&i| keys[i]);
}

/// The index along the Hilbert curve of the point with `bits`-bit integer coordinates
/// `x` (overwritten): Skilling's transform of the axes to the "transposed" index (Skilling
/// 2004, "Programming the Hilbert curve", AIP Conf. Proc. 707, §3), whose bits, read from the
/// most significant across the coordinates, are the index.
fn hilbert_index(x: &mut [u64], bits: u32) -> u128 {
    let n = x.len();
    let top = 1u64 << (bits - 1);
    // Inverse undo of the excess work.
    let mut q = top;
    while q > 1 {
        let p = q - 1;
        for i in 0..n {
            if x[i] & q != 0 {
                x[0] ^= p;
            } else {
                let t = (x[0] ^ x[i]) & p;
                x[0] ^= t;
                x[i] ^= t;
            }
        }
        q >>= 1;
    }
    // Gray encode.
    for i in 1..n {
        x[i] ^= x[i - 1];
    }
    let mut t = 0;
    let mut q = top;
    while q > 1 {
        if x[n - 1] & q != 0 {
            t ^= q - 1;
        }
        q >>= 1;
    }
    for v in x.iter_mut() {
        *v ^= t;
    }
    let mut index = 0u128;
    for b in (0..bits).rev() {
        for v in x.iter() {
            index = (index << 1) | ((v >> b) & 1) as u128;
        }
    }
    index
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    /// The Hilbert curve of order 1 and 2 in the plane visits the cells in the order of its
    /// drawing (Skilling 2004, Fig. 1): consecutive indices are neighbouring cells, and every
    /// cell has one index.
    #[test]
    fn the_hilbert_index_walks_through_neighbours() {
        for (n, bits) in [(2usize, 3u32), (3, 2)] {
            let side = 1u64 << bits;
            let cells = side.pow(n as u32) as usize;
            let mut by_index = alloc::vec![None; cells];
            for c in 0..cells {
                let coords: Vec<u64> = (0..n)
                    .map(|j| (c as u64 / side.pow(j as u32)) % side)
                    .collect();
                let h = hilbert_index(&mut coords.clone(), bits) as usize;
                assert!(by_index[h].is_none(), "index {h} twice");
                by_index[h] = Some(coords);
            }
            for w in by_index.windows(2) {
                let (a, b) = (w[0].as_ref().unwrap(), w[1].as_ref().unwrap());
                let step: u64 = a.iter().zip(b).map(|(p, q)| p.abs_diff(*q)).sum();
                assert_eq!(step, 1, "{a:?} → {b:?} in {n}-D");
            }
        }
    }

    /// Supplied normals are read in order, the run's count recorded, and the ones past U
    /// come from U's seed (the same for two readers of the same U).
    #[test]
    fn supplied_normals_are_read_in_order_then_drawn() {
        let u = Arc::new(SuppliedNormals::new(alloc::vec![0.5, -1.0, 2.0], 7));
        let (mut a, mut b) = (Draws::new(0, Some(&u)), Draws::new(1, Some(&u)));
        let mut out = [0.0; 5];
        let normal = NormalZiggurat::new();
        a.normals(&normal, &mut out);
        assert_eq!(&out[..3], &[0.5, -1.0, 2.0]);
        let mut again = [0.0; 5];
        b.normals(&normal, &mut again);
        assert_eq!(out, again);
        assert_eq!(u.used(), 5);
        // Φ(0) = 1/2.
        let zero = Arc::new(SuppliedNormals::new(alloc::vec![0.0], 1));
        assert!((Draws::new(0, Some(&zero)).uniform() - 0.5).abs() < 1e-15);
    }
}
