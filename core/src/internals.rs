//! The modules under the chosen surface. The crate names them from its root
//! (`crate::filters`, a private alias); from outside, only Zakai's own benchmarks, tests and
//! fuzz targets reach them, through this door.

#[path = "error.rs"]
pub mod error;
#[path = "filters/mod.rs"]
pub mod filters;
#[path = "grid/mod.rs"]
pub mod grid;
#[path = "linalg/mod.rs"]
pub mod linalg;
#[path = "model/mod.rs"]
pub mod model;
#[path = "random.rs"]
pub mod random;
#[path = "validate.rs"]
pub mod validate;
