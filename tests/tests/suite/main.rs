//! Zakai's integration tests, one module per subject, in one test binary: one link instead
//! of thirty, natively and in WebAssembly (`wasm-pack test --node`), where each binary also
//! went through wasm-bindgen and a node process of its own. Run one subject with
//! `cargo test -p zakai-tests --test suite likelihood::`.
//!
//! The counting-allocator tests (`allocation.rs`, `soak.rs`) stay binaries of their own: their
//! global allocator counts every thread's allocations, and other tests would run beside them.

mod config;
mod dimensions;
mod direct;
mod discrete_time;
mod estimates;
mod exact_nonlinear;
mod expressions;
mod fit;
mod fit_coverage;
mod fpe_split;
mod frontier;
mod kalman;
mod layering;
mod likelihood;
mod log_concavity;
mod map_filters;
mod measurement_families;
mod missing_data;
mod monte_carlo_table;
mod own_data;
mod parameters;
mod particle;
// Thousands of likelihood runs a test: natively, once (the sampler's numbers are the core's).
#[cfg(not(target_arch = "wasm32"))]
mod posterior;
mod predictive_checks;
mod properties;
// 000's Monte Carlo reproductions run once, natively, as the stiff property test below.
#[cfg(not(target_arch = "wasm32"))]
mod reproduction_000;
mod self_checks;
mod simulator;
mod smoothing;
mod spectral;
mod spectral_total_degree;
mod state_diffusion;
// The stiff property test (a minute and a half natively) runs once, natively: its numbers are
// the core's, the same in WebAssembly.
#[cfg(not(target_arch = "wasm32"))]
mod stiff_edges;
mod tensor_train;
mod test_attributes;
mod time_and_inputs;
// The playground's wasm `Session`, in a wasm runtime.
#[cfg(target_arch = "wasm32")]
mod wasm_session;
mod yau_yau;
