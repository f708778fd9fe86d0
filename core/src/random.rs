//! Random numbers: the one seeded generator of a run and the platform-independent normal
//! draws every simulator and random filter uses (same seed, same stream natively and in wasm).

use nalgebra::DVector;
use rand::{RngExt, SeedableRng};

/// The generator of every random number in a run (platform-independent stream).
pub type SimRng = rand::rngs::Xoshiro256PlusPlus;

/// A generator from a seed.
pub fn rng_from_seed(seed: u64) -> SimRng {
    SimRng::seed_from_u64(seed)
}

/// One N(0, 1) draw by the Box–Muller transform, computed with `libm` so that the stream of
/// normals is bit-identical on every platform (a ziggurat sampler's `exp` would come from the
/// platform's maths library natively and from Rust's port in wasm).
pub fn standard_normal<R: rand::Rng + ?Sized>(rng: &mut R) -> f64 {
    // u1 in (0, 1] so that ln u1 is finite.
    let u1 = 1.0 - rng.random::<f64>();
    let u2: f64 = rng.random();
    libm::sqrt(-2.0 * libm::log(u1)) * libm::cos(core::f64::consts::TAU * u2)
}

/// A vector of independent N(0, 1) draws.
pub fn standard_normal_vector<R: rand::Rng + ?Sized>(rng: &mut R, d: usize) -> DVector<f64> {
    DVector::from_fn(d, |_, _| standard_normal(rng))
}
