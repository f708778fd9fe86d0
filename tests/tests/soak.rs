//! Long runs: every method that applies to the 1-D cubic sensor (004 (44):
//! dx = dv, dy = x³ dt + dw, Δτ = 0.01) steps 10⁶ observation intervals with no NaN and no
//! memory growth. Ignored by default (about two minutes in release); run it with
//!
//! ```text
//! cargo test --release -p zakai-tests --test soak -- --ignored --nocapture
//! ```
//!
//! or `ZAKAI_SOAK=1 bash scripts/test-all.sh`. `ZAKAI_SOAK_INTERVALS` shortens it.
//!
//! The truth is Brownian motion reflected at ±3 so that a million intervals (10⁴ time units,
//! where free Brownian motion would wander ±100) stay inside the grids' box [−4, 4]; the
//! filters still assume the free model, so near the reflection they are mildly wrong, which
//! is part of the stress. A filter that returns an error (EKF and UKF lose the cubic sensor
//! now and then, 004 Table 1) is counted and rebuilt — like the page's reset — and must never
//! have reported a non-finite estimate. Memory: a counting global allocator measures the live
//! heap at a checkpoint after warm-up and at the end; the two must agree to 64 KiB.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicIsize, Ordering};
use zakai_tests::test;

use zakai::lab::experiment::{method_seed, Experiment};
use zakai::lab::scenario::{presets, MethodConfig};
use zakai::simulate::{rng_from_seed, standard_normal};
use zakai::{Filter, Observation, ObservationKind};
use zakai::{IekfParams, IokfParams};

/// Live heap bytes of the whole test binary.
static LIVE: AtomicIsize = AtomicIsize::new(0);

struct Counting;

// SAFETY: every call is forwarded to the system allocator unchanged; only a counter is kept.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        LIVE.fetch_add(layout.size() as isize, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size() as isize, Ordering::Relaxed);
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        LIVE.fetch_add(
            new_size as isize - layout.size() as isize,
            Ordering::Relaxed,
        );
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

const REFLECT: f64 = 3.0;

#[test]
#[ignore = "a million intervals per method: run with --ignored (ZAKAI_SOAK=1 in test-all.sh)"]
fn every_1d_method_runs_a_million_intervals_without_nan_or_memory_growth() {
    let intervals: usize = std::env::var("ZAKAI_SOAK_INTERVALS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000);
    let warm_up = (intervals / 100).max(1);
    let mut config = presets::preset("cubic-sensor-1d").unwrap();
    // One particle filter is enough; add the MAP filters of 003.
    let mut seen_pf = false;
    config.methods.retain(|m| {
        let first = !(matches!(m, MethodConfig::Pf(_)) && seen_pf);
        seen_pf |= matches!(m, MethodConfig::Pf(_));
        first
    });
    config
        .methods
        .push(MethodConfig::Iekf(IekfParams::default()));
    config
        .methods
        .push(MethodConfig::Iokf(IokfParams::default()));
    let experiment = Experiment::new(config).unwrap();
    let (model, prior, bounds) = (
        experiment.model(),
        experiment.prior(),
        experiment.config().bounds(),
    );
    let probes = experiment.config().probe_points();
    let methods: Vec<MethodConfig> = experiment
        .config()
        .methods
        .iter()
        .filter(|m| m.suitability(model, prior, &probes, &bounds).is_none())
        .cloned()
        .collect();
    assert!(methods.len() >= 8, "{} methods apply", methods.len());
    let build = |i: usize, restart: u64| -> Box<dyn Filter> {
        let name = methods[i].display_name();
        experiment
            .build_method(&methods[i], name, method_seed(restart, i))
            .unwrap()
    };
    let mut filters: Vec<Box<dyn Filter>> = (0..methods.len()).map(|i| build(i, 0)).collect();
    let mut restarts = vec![0u64; methods.len()];
    let mut worst_error = vec![0.0f64; methods.len()];

    let dt = experiment.config().time.dt_obs;
    let mut rng = rng_from_seed(20261121);
    let mut x = 1.0;
    let mut value = [0.0];
    let mut checkpoint = None;
    for k in 1..=intervals {
        // Euler–Maruyama for the truth and its observation increment over one interval.
        value[0] = x * x * x * dt + dt.sqrt() * standard_normal(&mut rng);
        x += dt.sqrt() * standard_normal(&mut rng);
        if x.abs() > REFLECT {
            x = x.signum() * (2.0 * REFLECT - x.abs());
        }
        let obs = Observation {
            dt,
            value: &value,
            kind: ObservationKind::Increment,
            inputs: None,
        };
        for (i, filter) in filters.iter_mut().enumerate() {
            match filter.step(&obs) {
                Ok(()) => {
                    let est = filter.estimate();
                    assert!(
                        est.mean.iter().all(|v| v.is_finite()),
                        "{} reported a non-finite estimate at interval {k}",
                        filter.name()
                    );
                    worst_error[i] = worst_error[i].max((est.mean[0] - x).abs());
                }
                Err(_) => {
                    restarts[i] += 1;
                    *filter = build(i, restarts[i]);
                }
            }
        }
        if k == warm_up {
            checkpoint = Some(LIVE.load(Ordering::Relaxed));
        }
    }
    let end = LIVE.load(Ordering::Relaxed);
    let start = checkpoint.unwrap();
    println!(
        "{intervals} intervals; live heap {start} B after {warm_up}, {end} B at the end ({:+} B)",
        end - start
    );
    for (i, f) in filters.iter().enumerate() {
        println!(
            "  {:<10} restarts {:>5}   largest |x̂ − x| {:.3}",
            f.name(),
            restarts[i],
            worst_error[i]
        );
    }
    assert!(
        (end - start).abs() <= 64 << 10,
        "the live heap changed by {} B between interval {warm_up} and {intervals}",
        end - start
    );
    // The largest error over the run, for the methods that track without restarts: the grid
    // filters at most 4 (measured 3.20 over 10⁶ intervals: a moment of sign confusion near
    // x = 0, where h′ = 3x² vanishes; the box is [−4, 4] and the truth stays in [−3, 3]), the
    // particle filter and UKF 4.5 (3.36, 3.06), the spectral filter with 004's coarse basis 6
    // (5.34). The EKF, IEKF and IOKF lose the state for long stretches (23.6, 9.6, 4.1
    // measured) and are only printed.
    for (i, f) in filters.iter().enumerate() {
        let name = f.name();
        let bound = match name {
            "QIEM" | "IEM" | "SPT" => 4.0,
            "UKF" => 4.5,
            _ if name.starts_with("PF") => 4.5,
            "Spectral" => 6.0,
            _ => continue,
        };
        assert!(
            worst_error[i] <= bound,
            "{name}: largest |x̂ − x| {} above {bound}",
            worst_error[i]
        );
    }
    // Grid and spectral methods must never need a restart on this bounded truth.
    for (i, f) in filters.iter().enumerate() {
        let name = f.name();
        if ["QIEM", "IEM", "SPT", "Spectral"].contains(&name) {
            assert_eq!(restarts[i], 0, "{name} failed and was restarted");
        }
    }
}
