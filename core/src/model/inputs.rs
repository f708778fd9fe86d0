//! Time and known inputs: a driven model ([`Inputs`] documents it).

use alloc::sync::Arc;
use alloc::vec;
use alloc::vec::Vec;

use super::diffusion::Diffusion;
use super::function::{BatchScratch, Derivatives, VectorFunction};
use super::measurement::MeasurementDensity;
use super::{Model, ObservationModel};
use crate::error::FilterError;

/// The time and inputs recorded with an observation: `t = τ_k` and the inputs `u` over the
/// interval `(τ_{k−1}, τ_k]`.
///
/// Time and known inputs: a *driven* model
///
/// ```text
///     dx = f(x, t, u) dt + G(x, t, u) dv,      y or z observed through h(x, t, u)
/// ```
///
/// where `u = (u1, …, uk)` is a series known to the filter — an actuator command, a forcing
/// series — recorded beside the observations. Its functions read the state, then (after the
/// measurement `z` of a log-density) the time `t` and the inputs `u1..uk`, in that order.
///
/// **What a step uses.** The inputs recorded with observation k are those over the interval
/// `(τ_{k−1}, τ_k]` that ends at it, held constant there (a zero-order hold: the convention
/// of the increments, whose row k is also the interval's), and at the measurement `z_k`. The
/// time the dynamics read is held at the interval's midpoint `τ_{k−1} + Δτ/2` (the midpoint
/// rule, second order in Δτ for a drift smooth in t); a measurement at `τ_k` reads `t = τ_k`.
/// Each step therefore sees two *frozen* models ([`Model::at`]; `Observation::frozen` gives
/// the pair): an autonomous model whose functions are the driven ones with `(t, u)` fixed.
///
/// **Which methods.** The EKF, UKF and particle filter take the frozen models step by step;
/// the continuous–discrete grid filters (Šimandl & Švácha 2005, 001) and the Yau–Yau IEM,
/// QIEM and QIEM-4 (Yueh, Lin & Yau 2014, 000) tabulate and factorise their operator anew at
/// every step. Methods whose operator is made once for the whole run refuse a driven model
/// with that reason (the catalogue's `inputs`): the spectral filter's off-line operator
/// (Shi, Chen & Yau 2021, 004 Algorithm 1), the superposition technique (000 §2.5), the
/// direct method's Riccati solution (Shi, Yang & Yau 2018, 002), the Kalman–Bucy and
/// Gaussian-sum filters' fixed matrices — and the IEKF and IOKF (Kang, Salmon & Yau 2023,
/// 003), whose second-mode watch carries the model over several intervals at once.
///
/// A step that fails (inputs missing or not finite, a function undefined at them) leaves the
/// filter's density or moments and estimate as they were.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inputs<'a> {
    /// τ_k, the observation's time.
    pub t: f64,
    /// u1..uk over the interval ending at τ_k.
    pub u: &'a [f64],
}

/// A driven function with its time and inputs fixed: `x ↦ g(x, t, u)` (the fixed values are
/// the last inputs of `inner`).
struct Frozen {
    inner: Arc<dyn VectorFunction>,
    /// t, then u1..uk.
    fixed: Vec<f64>,
    /// The inner function's components compiled with the fixed values folded in, when it has
    /// them ([`VectorFunction::with_inputs_fixed`]): its values at points and batches. Its
    /// derivatives keep to the inner function with the point extended.
    programs: Option<super::FixedPrograms>,
}

impl Frozen {
    fn inputs(&self) -> usize {
        self.inner.input_dim() - self.fixed.len()
    }

    /// `x` followed by the fixed values.
    fn extended(&self, x: &[f64], out: &mut [f64]) {
        let n = self.inputs();
        out[..n].copy_from_slice(&x[..n]);
        out[n..].copy_from_slice(&self.fixed);
    }
}

/// Inputs a frozen function keeps on the stack when it extends a point.
const STACK_INPUTS: usize = 64;

/// `f` with `x` extended by `frozen`'s fixed values, on the stack when short enough.
fn with_extended<R>(frozen: &Frozen, x: &[f64], f: impl FnOnce(&[f64]) -> R) -> R {
    let len = frozen.inner.input_dim();
    if len <= STACK_INPUTS {
        let mut buf = [0.0; STACK_INPUTS];
        frozen.extended(x, &mut buf[..len]);
        f(&buf[..len])
    } else {
        let mut buf = vec![0.0; len];
        frozen.extended(x, &mut buf);
        f(&buf)
    }
}

impl VectorFunction for Frozen {
    fn input_dim(&self) -> usize {
        self.inputs()
    }
    fn output_dim(&self) -> usize {
        self.inner.output_dim()
    }
    fn eval(&self, x: &[f64], out: &mut [f64]) {
        match &self.programs {
            Some(p) => {
                let n = self.inputs();
                for (o, program) in out.iter_mut().zip(&p.0) {
                    *o = program.eval(&x[..n]);
                }
            }
            None => with_extended(self, x, |x| self.inner.eval(x, out)),
        }
    }
    /// The first n columns of the driven function's Jacobian.
    fn jacobian(&self, x: &[f64], out: &mut [f64]) {
        let (n, full, m) = (self.inputs(), self.inner.input_dim(), self.output_dim());
        let mut whole = vec![0.0; m * full];
        with_extended(self, x, |x| self.inner.jacobian(x, &mut whole));
        for i in 0..m {
            out[i * n..(i + 1) * n].copy_from_slice(&whole[i * full..i * full + n]);
        }
    }
    /// The leading n × n block of the driven function's Hessian.
    fn hessian(&self, i: usize, x: &[f64], out: &mut [f64]) {
        let (n, full) = (self.inputs(), self.inner.input_dim());
        let mut whole = vec![0.0; full * full];
        with_extended(self, x, |x| self.inner.hessian(i, x, &mut whole));
        for j in 0..n {
            out[j * n..(j + 1) * n].copy_from_slice(&whole[j * full..j * full + n]);
        }
    }
    fn derivatives(&self) -> Derivatives {
        self.inner.derivatives()
    }
    /// The programs with the fixed values folded in, over the points; otherwise the points
    /// followed by one row per fixed value (structure of arrays), evaluated by the driven
    /// function's own batch.
    fn eval_batch(&self, points: &[f64], out: &mut [f64], scratch: &mut BatchScratch) {
        let n = self.inputs();
        if let Some(p) = &self.programs {
            let table = p.0.iter().map(Some);
            return super::expression::eval_programs_batch(table, n, points, out, scratch);
        }
        let k = points.len() / n.max(1);
        let mut extended = Vec::with_capacity(self.inner.input_dim() * k);
        extended.extend_from_slice(&points[..n * k]);
        for v in &self.fixed {
            extended.extend(core::iter::repeat_n(*v, k));
        }
        self.inner.eval_batch(&extended, out, scratch);
    }
}

/// `g` with `fixed` appended to its inputs.
fn freeze(g: &Arc<dyn VectorFunction>, fixed: &[f64]) -> Arc<dyn VectorFunction> {
    let first = g.input_dim() - fixed.len();
    Arc::new(Frozen {
        inner: g.clone(),
        fixed: fixed.to_vec(),
        programs: g.with_inputs_fixed(first, fixed),
    })
}

impl Model {
    /// The model at time `t` with inputs `u`: every function with `(t, u)` fixed, an
    /// autonomous model of the same state. An autonomous model is returned as it is. Fails
    /// when `u` does not have the model's k inputs or a value is not finite.
    pub fn at(&self, t: f64, u: &[f64]) -> Result<Model, FilterError> {
        let Some(k) = self.inputs else {
            return Ok(self.clone());
        };
        if u.len() != k {
            return Err(FilterError::BadObservation(alloc::format!(
                "the model reads {k} inputs u1..u{k}, and {} were given",
                u.len()
            )));
        }
        if let Some(i) = (0..k).find(|&i| !u[i].is_finite()) {
            return Err(FilterError::BadObservation(alloc::format!(
                "input u{} is {}: a driven model needs every input at every step",
                i + 1,
                u[i]
            )));
        }
        if !t.is_finite() {
            return Err(FilterError::BadObservation(alloc::format!(
                "the time t is {t}"
            )));
        }
        let mut fixed = vec![t];
        fixed.extend_from_slice(u);
        let diffusion = match &self.diffusion {
            Diffusion::Constant(g) => Diffusion::Constant(g.clone()),
            Diffusion::StateDependent(g) => Diffusion::StateDependent(freeze(g, &fixed)),
        };
        let observations = match &self.observations {
            ObservationModel::Discrete { density } => ObservationModel::Discrete {
                density: match density {
                    MeasurementDensity::Heteroscedastic(s) => {
                        MeasurementDensity::Heteroscedastic(freeze(s, &fixed))
                    }
                    MeasurementDensity::LogDensity(l) => {
                        MeasurementDensity::LogDensity(freeze(l, &fixed))
                    }
                    other => other.clone(),
                },
            },
            continuous => continuous.clone(),
        };
        Ok(Model {
            n: self.n,
            m: self.m,
            drift: freeze(&self.drift, &fixed),
            observation: freeze(&self.observation, &fixed),
            diffusion,
            observations,
            inputs: None,
            dynamics: self.dynamics,
            transition_mixture: self.transition_mixture.clone(),
        })
    }
}
