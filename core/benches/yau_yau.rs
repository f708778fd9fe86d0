//! Criterion benchmarks of the finite-difference Yau–Yau filters of 000: one scheme step
//! (prediction over Δt = Δτ with one substep, the robust update and the moments) on the cubic
//! sensor (1-D, h = x³ on [−10, 10]) and on the 2-D example (33). At the sizes QIEM
//! also runs one interval of ten substeps (Δt = Δτ/10): the difference of the two, over nine,
//! is one pass of Algorithm 3's inner loop (lines 10–15: explicit part, DST, division,
//! inverse DST) without the once-per-interval update (15) and moments.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use zakai::internals::DstPlan;
use zakai::lab::experiment::Experiment;
use zakai::lab::scenario::{presets, MethodConfig};
use zakai::YauYauParams;
use zakai::{Observation, ObservationKind};

/// Grid sizes at which QIEM also runs with ten substeps per interval.
const INNER_LOOP_SIZES: [usize; 3] = [1999, 2001, 256];

fn bench(c: &mut Criterion, preset: &str, domain: Vec<[f64; 2]>, sizes: &[usize], iem: bool) {
    let mut config = presets::preset(preset).expect("preset");
    config.domain = domain;
    config.methods = vec![MethodConfig::from_key("ekf").unwrap()];
    config.time.dt_obs = 0.01;
    let experiment = Experiment::new(config).expect("valid");
    let n = experiment.model().n;
    let dt = 0.01;
    let mut group = c.benchmark_group(format!("{preset} one step (Δt = Δτ = {dt})"));
    for &points in sizes {
        let params = YauYauParams {
            points: vec![points],
            dt,
            ..YauYauParams::default()
        };
        let mut methods = vec![("QIEM", MethodConfig::Qiem(params.clone()))];
        if INNER_LOOP_SIZES.contains(&points) {
            let inner = YauYauParams {
                dt: dt / 10.0,
                ..params.clone()
            };
            methods.push(("QIEM-10-substeps", MethodConfig::Qiem(inner)));
        }
        if iem {
            methods.push(("IEM", MethodConfig::Iem(params)));
        }
        for (label, method) in methods {
            let mut filter = experiment
                .build_method(&method, label.into(), 1)
                .expect("builds");
            let dy = vec![1e-3; experiment.model().m];
            let obs = Observation {
                dt,
                value: &dy,
                kind: ObservationKind::Increment,
                inputs: None,
            };
            let size = (0..n)
                .map(|_| points.to_string())
                .collect::<Vec<_>>()
                .join("x");
            group.bench_with_input(BenchmarkId::new(label, size), &obs, |b, obs| {
                b.iter(|| filter.step(obs).expect("steps"))
            });
        }
    }
    group.finish();
}

/// The superposition technique against QIEM on the cubic sensor: the off-line build (bump
/// solutions over one interval of Δτ = 0.01 with Δt = 10⁻³) and one on-line interval.
fn superposition(c: &mut Criterion) {
    let config = presets::preset("cubic-sensor-1d").expect("preset");
    let experiment = Experiment::new(config).expect("valid");
    let params = YauYauParams {
        points: vec![401],
        dt: 1e-3,
        centres: vec![101],
        ..YauYauParams::default()
    };
    let mut group =
        c.benchmark_group("cubic-sensor-1d superposition (401 points, 101 bumps, Δτ = 10 Δt)");
    group.sample_size(20);
    group.bench_function("SPT off-line build", |b| {
        b.iter(|| {
            experiment
                .build_method(&MethodConfig::Spt(params.clone()), "SPT".into(), 1)
                .expect("builds")
        })
    });
    let dy = [1e-3];
    let obs = Observation {
        dt: 0.01,
        value: &dy,
        kind: ObservationKind::Increment,
        inputs: None,
    };
    for (label, method) in [
        ("SPT on-line interval", MethodConfig::Spt(params.clone())),
        ("QIEM interval", MethodConfig::Qiem(params.clone())),
    ] {
        let mut filter = experiment
            .build_method(&method, label.into(), 1)
            .expect("builds");
        group.bench_function(label, |b| b.iter(|| filter.step(&obs).expect("steps")));
    }
    group.finish();
}

/// The bare transforms of a QIEM step: forward and inverse DST-I along every dimension, the
/// denominator of the step-to-transform ratio (a QIEM step against its two transforms).
fn bare_dst(c: &mut Criterion) {
    let mut group = c.benchmark_group("bare forward + inverse DST-I");
    for shape in [vec![1999usize], vec![2001], vec![254, 254], vec![256, 256]] {
        let len: usize = shape.iter().product();
        let mut plans: Vec<DstPlan> = shape.iter().map(|&n| DstPlan::new(n)).collect();
        let strides: Vec<usize> = shape
            .iter()
            .scan(1, |s, &n| {
                let stride = *s;
                *s *= n;
                Some(stride)
            })
            .collect();
        let mut data: Vec<f64> = (0..len).map(|i| (i as f64 * 0.37).sin()).collect();
        let label = shape
            .iter()
            .map(|n| n.to_string())
            .collect::<Vec<_>>()
            .join("x");
        group.bench_function(label, |b| {
            b.iter(|| {
                for _ in 0..2 {
                    for (plan, &stride) in plans.iter_mut().zip(&strides) {
                        plan.transform_axis(&mut data, stride);
                    }
                }
            })
        });
    }
    group.finish();
}

fn yau_yau(c: &mut Criterion) {
    bench(
        c,
        "yau-cubic-sensor",
        vec![[-10.0, 10.0]],
        &[255, 511, 1023, 1999, 2001, 4095],
        true,
    );
    bench(
        c,
        "yau-2d",
        vec![[-6.0, 6.0], [-6.0, 6.0]],
        &[128, 254, 256],
        false,
    );
}

criterion_group!(benches, yau_yau, bare_dst, superposition);
criterion_main!(benches);
