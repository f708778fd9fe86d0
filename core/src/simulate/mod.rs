//! Truth and observation generators. The simulator never knows about filters.
//!
//! * Continuous observations — 000 Algorithm 1 (Euler forward differences):
//!   `x_{k+1} = x_k + f(x_k) Δτ + G v √Δτ`, `y_{k+1} = y_k + h(x_k) Δτ + S^{1/2} w √Δτ`,
//!   `y_0 = 0`, optionally with `inner_steps` Euler–Maruyama steps of `Δτ / inner_steps`
//!   inside each observation interval (with `inner_steps = 1` it is Algorithm 1 exactly).
//! * Continuous–discrete (001 (1)–(2), 003 (5.2)): the same Euler–Maruyama signal, and a
//!   measurement `z_k = h(x_k) + v_k` at every observation time `t_k = k Δτ`, k = 0..N.
//!
//! Random numbers come from one seeded [`SimRng`] (xoshiro256++, seeded through
//! `seed_from_u64`), whose stream is the same on every platform: same seed, same trajectory
//! natively and in wasm.

use alloc::vec;
use alloc::vec::Vec;

pub use crate::random::{rng_from_seed, standard_normal, standard_normal_vector, SimRng};
use nalgebra::DMatrix;

use crate::error::ZakaiError;
use crate::model::{Model, ObservationModel};
use alloc::format;

/// Observation times: N intervals of length Δτ, each simulated with `inner_steps` steps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeGrid {
    /// Δτ, the observation interval.
    pub dt_obs: f64,
    /// N, the number of observation intervals (times τ_0..τ_N).
    pub steps: usize,
    /// Euler–Maruyama steps per observation interval for the truth.
    pub inner_steps: usize,
}

/// A simulated truth with its observations.
#[derive(Clone, Debug)]
pub struct Trajectory {
    /// State dimension.
    pub n: usize,
    /// Observation dimension.
    pub m: usize,
    /// Δτ, the length of every observation interval.
    pub dt_obs: f64,
    /// τ_k = k Δτ, k = 0..N.
    pub times: Vec<f64>,
    /// x(τ_k), row k at `states[k*n..(k+1)*n]`.
    pub states: Vec<f64>,
    /// Row k: the increment y(τ_k) − y(τ_{k−1}) (continuous; row 0 is zero) or z_k (discrete).
    pub observations: Vec<f64>,
    /// Whether observations are increments of a continuous y.
    pub continuous: bool,
    /// k, the known inputs per row of a driven model (0: none).
    pub input_count: usize,
    /// The known inputs the run used, row k (those over `(τ_{k−1}, τ_k]`) at
    /// `inputs[k*input_count..]`.
    pub inputs: Vec<f64>,
}

impl Trajectory {
    /// x(τ_k).
    pub fn state(&self, k: usize) -> &[f64] {
        &self.states[k * self.n..(k + 1) * self.n]
    }
    /// Observation row k (see [`Trajectory::observations`]).
    pub fn observation(&self, k: usize) -> &[f64] {
        &self.observations[k * self.m..(k + 1) * self.m]
    }
    /// N, the number of observation intervals.
    pub fn steps(&self) -> usize {
        self.times.len() - 1
    }
    /// The known inputs of row k (empty for an autonomous model).
    pub fn inputs_at(&self, k: usize) -> &[f64] {
        &self.inputs[k * self.input_count..(k + 1) * self.input_count]
    }
    /// The cumulative observation path y(τ_k) (continuous models), row-major.
    pub fn cumulative_y(&self) -> Vec<f64> {
        let mut y = self.observations.clone();
        for k in 1..self.times.len() {
            for j in 0..self.m {
                y[k * self.m + j] += y[(k - 1) * self.m + j];
            }
        }
        y
    }
}

/// Simulates the model from `x0` over `time`, drawing all noise from `rng`. Fails when the
/// measurements' family has no sampler (a log-density) or is undefined at the true state (a
/// negative Poisson rate or variance), and for a model driven by known inputs (whose series
/// [`simulate_driven`] takes; a model that reads only the time needs none).
pub fn simulate(
    model: &Model,
    x0: &[f64],
    time: TimeGrid,
    rng: &mut SimRng,
) -> Result<Trajectory, ZakaiError> {
    simulate_driven(model, x0, time, &[], rng)
}

/// [`simulate`] for a driven model ([`crate::Inputs`]) with the known `inputs`, k per
/// row for the N + 1 times (row k held over `(τ_{k−1}, τ_k]`, row 0 read by the measurement
/// at τ₀): each Euler–Maruyama step reads the time at its start, each measurement its own
/// time. An autonomous model takes no inputs. A discrete-time model
/// ([`crate::Dynamics::Discrete`]) makes its transitions instead (Δτ/period of them per
/// interval, each reading the time it reaches and row k's inputs; `inner_steps` is not used).
pub fn simulate_driven(
    model: &Model,
    x0: &[f64],
    time: TimeGrid,
    inputs: &[f64],
    rng: &mut SimRng,
) -> Result<Trajectory, ZakaiError> {
    let (n, m) = (model.n, model.m);
    let k_inputs = model.inputs.unwrap_or(0);
    if inputs.len() != (time.steps + 1) * k_inputs || (model.inputs.is_none() && !inputs.is_empty())
    {
        return Err(ZakaiError::Dimension(format!(
            "the simulation needs {} known inputs ({} rows of k = {k_inputs}), got {}",
            (time.steps + 1) * k_inputs,
            time.steps + 1,
            inputs.len()
        )));
    }
    // The model at time t with the inputs of row k (`None`: the model itself, autonomous).
    let at = |t: f64, k: usize| -> Result<Option<Model>, ZakaiError> {
        match model.inputs {
            None => Ok(None),
            Some(c) => model
                .at(t, &inputs[k * c..(k + 1) * c])
                .map(Some)
                .map_err(|e| ZakaiError::Other(format!("simulating the driven model: {e}"))),
        }
    };

    let inner = time.inner_steps.max(1);
    let dt = time.dt_obs / inner as f64;
    let sqrt_dt = libm::sqrt(dt);
    let obs_sqrt: Option<DMatrix<f64>> = match &model.observations {
        ObservationModel::Continuous { noise_cov } => Some(
            noise_cov
                .clone()
                .cholesky()
                .map(|c| c.l())
                .unwrap_or_else(|| DMatrix::identity(m, m)),
        ),
        ObservationModel::Discrete { .. } => None,
    };
    let steps = time.steps;
    let mut times = Vec::with_capacity(steps + 1);
    let mut states = Vec::with_capacity((steps + 1) * n);
    let mut observations = vec![0.0; (steps + 1) * m];
    let mut x = x0.to_vec();
    let mut fx = vec![0.0; n];
    let mut hx = vec![0.0; m];
    let mut g = vec![0.0; n * n];

    if let ObservationModel::Discrete { density } = &model.observations {
        density.sampler().map_err(ZakaiError::Other)?;
    }
    let measure = |model: &Model, x: &[f64], rng: &mut SimRng, out: &mut [f64], hx: &mut [f64]| {
        if let ObservationModel::Discrete { density } = &model.observations {
            model.observation.eval(x, hx);
            density
                .sample(x, hx, rng, out)
                .map_err(|e| ZakaiError::Other(format!("simulating the measurements: {e}")))?;
        }
        Ok::<(), ZakaiError>(())
    };

    times.push(0.0);
    states.extend_from_slice(&x);
    let start = at(0.0, 0)?;
    measure(
        start.as_ref().unwrap_or(model),
        &x,
        rng,
        &mut observations[0..m],
        &mut hx,
    )?;
    let discrete = model.is_discrete_time();
    for k in 1..=steps {
        let row = &mut observations[k * m..(k + 1) * m];
        if let crate::model::Dynamics::Discrete { period } = model.dynamics {
            // x_j = F(x_(j−1), t_j, u_k) + w_j, w_j ~ N(0, G Gᵀ) (or the model's mixture):
            // the transitions of one Δτ,
            // each at the time it reaches.
            let transitions = model
                .transitions(time.dt_obs)
                .map_err(|e| ZakaiError::Other(format!("simulating the map: {e}")))?;
            let tk = k as f64 * time.dt_obs;
            for j in 0..transitions {
                let t = tk - (transitions - 1 - j) as f64 * period;
                let frozen = at(t, k)?;
                let model = frozen.as_ref().unwrap_or(model);
                model.drift.eval(&x, &mut fx);
                if let Some(w) = &model.transition_mixture {
                    // w_j from the mixture itself.
                    w.sample_into(rng, &mut x);
                    x.iter_mut().zip(&fx).for_each(|(x, f)| *x += f);
                    continue;
                }
                noise_factor(model, &x, t, &mut g)?;
                let xi = standard_normal_vector(rng, n);
                for (i, row) in g.chunks_exact(n).enumerate() {
                    x[i] = fx[i] + row.iter().zip(xi.iter()).map(|(g, xi)| g * xi).sum::<f64>();
                }
            }
        }
        for i in 0..if discrete { 0 } else { inner } {
            let t = (k - 1) as f64 * time.dt_obs + i as f64 * dt;
            let frozen = at(t, k)?;
            let model = frozen.as_ref().unwrap_or(model);
            model.drift.eval(&x, &mut fx);
            if let Some(l) = &obs_sqrt {
                model.observation.eval(&x, &mut hx);
                let w = l * standard_normal_vector(rng, m);
                for j in 0..m {
                    row[j] += hx[j] * dt + w[j] * sqrt_dt;
                }
            }
            noise_factor(model, &x, t, &mut g)?;
            let xi = standard_normal_vector(rng, n);
            for (i, row) in g.chunks_exact(n).enumerate() {
                let v: f64 = row.iter().zip(xi.iter()).map(|(g, xi)| g * xi).sum();
                x[i] += fx[i] * dt + v * sqrt_dt;
            }
        }
        let tk = k as f64 * time.dt_obs;
        let end = at(tk, k)?;
        measure(end.as_ref().unwrap_or(model), &x, rng, row, &mut hx)?;
        times.push(tk);
        states.extend_from_slice(&x);
    }
    Ok(Trajectory {
        n,
        m,
        dt_obs: time.dt_obs,
        times,
        states,
        observations,
        continuous: obs_sqrt.is_some(),
        input_count: k_inputs,
        inputs: inputs.to_vec(),
    })
}

/// G(x) into `g` (row-major), refused where it is not finite.
fn noise_factor(model: &Model, x: &[f64], t: f64, g: &mut [f64]) -> Result<(), ZakaiError> {
    model.diffusion.eval(x, g);
    if g.iter().any(|v| !v.is_finite()) {
        return Err(ZakaiError::Other(format!(
            "simulating the state: the diffusion G(x) is not finite at x = {x:.4?} (t = {t:.4}); write G so that it is defined wherever the state can go (e.g. sqrt(abs(x)) rather than sqrt(x))"
        )));
    }
    Ok(())
}
