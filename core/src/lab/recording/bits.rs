//! Numbers carried exactly between processes: every `f64` of a serialised run as its IEEE
//! bits (`u64`), so that NaN — a missing value, a failed method's rows — and the last bit of
//! every estimate survive a JSON round trip (JSON has no NaN, and decimal text need not read
//! back to the same bits in every reader). Used with `#[serde(with = "bits")]` on the fields
//! of [`super::Recording`] and [`crate::lab::experiment::MethodTrack`], which cross to a
//! cluster's workers and back (Python's `monte_carlo(…, executor=…)`).

use alloc::vec::Vec;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// A value made of `f64`s and its bit-exact stand-in.
pub trait Bits: Sized {
    /// The stand-in: `u64` for each `f64`.
    type Repr: Serialize + DeserializeOwned;
    /// To the stand-in.
    fn to_bits(&self) -> Self::Repr;
    /// Back from it.
    fn from_bits(r: Self::Repr) -> Self;
}

impl Bits for f64 {
    type Repr = u64;
    fn to_bits(&self) -> u64 {
        f64::to_bits(*self)
    }
    fn from_bits(r: u64) -> f64 {
        f64::from_bits(r)
    }
}

impl Bits for Vec<f64> {
    type Repr = Vec<u64>;
    fn to_bits(&self) -> Vec<u64> {
        self.iter().map(|v| v.to_bits()).collect()
    }
    fn from_bits(r: Vec<u64>) -> Vec<f64> {
        r.into_iter().map(f64::from_bits).collect()
    }
}

impl<T: Bits> Bits for Option<T> {
    type Repr = Option<T::Repr>;
    fn to_bits(&self) -> Self::Repr {
        self.as_ref().map(Bits::to_bits)
    }
    fn from_bits(r: Self::Repr) -> Self {
        r.map(T::from_bits)
    }
}

/// Serialises `v` as its bits.
pub fn serialize<T: Bits, S: Serializer>(v: &T, s: S) -> Result<S::Ok, S::Error> {
    v.to_bits().serialize(s)
}

/// Reads a value serialised by [`serialize`].
pub fn deserialize<'de, T: Bits, D: Deserializer<'de>>(d: D) -> Result<T, D::Error> {
    T::Repr::deserialize(d).map(T::from_bits)
}
