//! The wall clock the driver times steps with: `performance.now()` (or `Date.now()`).

use wasm_bindgen::prelude::*;
use zakai::lab::experiment::Clock;

#[wasm_bindgen]
extern "C" {
    /// `performance.now()`, bound directly: each filter step is timed, so the clock must cost
    /// little next to a sub-microsecond step (looking `performance` up by name on every call
    /// cost more than the spectral filter's whole step).
    #[wasm_bindgen(js_namespace = performance, js_name = now)]
    fn performance_now() -> f64;
}

/// Whether the global object has `performance.now` (every browser, worker and Node ≥ 16);
/// looked up once.
fn has_performance_now() -> bool {
    static FOUND: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *FOUND.get_or_init(|| {
        js_sys::Reflect::get(&js_sys::global(), &JsValue::from_str("performance"))
            .ok()
            .filter(|p| p.is_object())
            .and_then(|p| js_sys::Reflect::get(&p, &JsValue::from_str("now")).ok())
            .is_some_and(|now| now.is_function())
    })
}

/// Wall-clock time from `performance.now()` (or `Date.now()` where there is none).
pub(crate) struct JsClock;

impl Clock for JsClock {
    fn now(&self) -> f64 {
        let ms = if has_performance_now() {
            performance_now()
        } else {
            js_sys::Date::now()
        };
        ms / 1000.0
    }
}
