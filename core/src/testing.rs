//! The attribute the unit tests are marked with: the standard `#[test]` natively and
//! `wasm_bindgen_test` on wasm32, so that `wasm-pack test --node` in `core/` runs the same
//! tests in WebAssembly (the page's target) as `cargo test` runs natively.

#[cfg(not(target_arch = "wasm32"))]
pub(crate) use core::prelude::v1::test;
#[cfg(target_arch = "wasm32")]
pub(crate) use wasm_bindgen_test::wasm_bindgen_test as test;
