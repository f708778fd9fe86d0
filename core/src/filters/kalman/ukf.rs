//! The unscented Kalman filter ([`Ukf`] documents it).

use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use nalgebra::{DMatrix, DVector};

use super::measurement::{Measurement, MeasurementForm};
use super::{GaussianState, UkfParams};
use crate::error::FilterError;
use crate::filters::{Filter, Observation};
use crate::model::{BatchScratch, Model};

/// Sigma-point weights.
#[derive(Clone, Debug)]
struct Weights {
    spread: f64,
    mean0: f64,
    cov0: f64,
    rest: f64,
}

impl Weights {
    fn mean(&self, i: usize) -> f64 {
        if i == 0 {
            self.mean0
        } else {
            self.rest
        }
    }
}

/// The 2n + 1 sigma points and their images under f or h, as structure of arrays (component
/// j of point i at `[j * count + i]`, the layout of [`crate::model::VectorFunction::eval_batch`]),
/// with the storage of P's Cholesky factor: made once, so that a step allocates nothing.
#[derive(Clone, Debug)]
struct SigmaPoints {
    count: usize,
    points: Vec<f64>,
    images: Vec<f64>,
    factor: DMatrix<f64>,
    scratch: BatchScratch,
}

impl SigmaPoints {
    fn new(n: usize, m: usize) -> Self {
        let count = 2 * n + 1;
        SigmaPoints {
            count,
            points: vec![0.0; n * count],
            images: vec![0.0; n.max(m) * count],
            factor: DMatrix::zeros(n, n),
            scratch: BatchScratch::default(),
        }
    }

    /// Places the sigma points of `N(m, P)` and their images under `f` (in one batch, into
    /// `images`, component-major); returns how many values the images take.
    fn map_points(
        &mut self,
        f: &dyn crate::model::VectorFunction,
        w: &Weights,
        (m, p): (&DVector<f64>, &DMatrix<f64>),
    ) -> Result<usize, FilterError> {
        self.place(w, m, p)?;
        let len = f.output_dim() * self.count;
        f.eval_batch(&self.points, &mut self.images[..len], &mut self.scratch);
        Ok(len)
    }

    /// The sigma points of `N(m, P)`: `m` and `m ± √(n+λ) Lᵢ`.
    fn place(
        &mut self,
        w: &Weights,
        m: &DVector<f64>,
        p: &DMatrix<f64>,
    ) -> Result<(), FilterError> {
        let (n, c) = (m.len(), self.count);
        crate::linalg::lower_cholesky_checked(p, &mut self.factor, "covariance")?;
        let l = self.factor.as_slice();
        for (j, row) in self.points.chunks_exact_mut(c).take(n).enumerate() {
            let (centre, rest) = row.split_first_mut().expect("2n + 1 points");
            let (plus, minus) = rest.split_at_mut(n);
            let mj = m[j];
            *centre = mj;
            // Only the lower triangle of the factor is L: L(j, i) at i n + j for i ≤ j; above
            // it the points keep m's component (m ± 0).
            for i in 0..n {
                let v = if i <= j { l[i * n + j] * w.spread } else { 0.0 };
                plus[i] = mj + v;
                minus[i] = mj - v;
            }
        }
        Ok(())
    }

    /// `out[j] = Σᵢ Wᵢᵐ a[j * count + i]` for the rows of `a`.
    fn mean(&self, w: &Weights, a: &[f64], out: &mut [f64]) {
        for (o, row) in out.iter_mut().zip(a.chunks_exact(self.count)) {
            *o = 0.0;
            for (i, v) in row.iter().enumerate() {
                *o += v * w.mean(i);
            }
        }
    }

    /// `out[(r, s)] = Σᵢ Wᵢᶜ (a_r,i − ma_r)(b_s,i − mb_s)`; one triangle and its mirror
    /// when `a` and `b` are the same points about the same mean.
    fn cross_cov(
        &self,
        w: &Weights,
        (a, ma): (&[f64], &[f64]),
        (b, mb): (&[f64], &[f64]),
        out: &mut DMatrix<f64>,
    ) {
        let c = self.count;
        let symmetric = core::ptr::eq(a, b) && core::ptr::eq(ma, mb);
        for (r, mr) in ma.iter().enumerate() {
            let ar = &a[r * c..(r + 1) * c];
            let first = if symmetric { r } else { 0 };
            for (s, ms) in mb.iter().enumerate().skip(first) {
                let bs = &b[s * c..(s + 1) * c];
                // The centre point's weight differs; the 2n others share one, summed in four
                // running parts (independent additions, not one chain).
                let mut parts = [0.0; 4];
                let (x4, y4) = (ar[1..].chunks_exact(4), bs[1..].chunks_exact(4));
                let tail = x4.remainder().iter().zip(y4.remainder());
                for (x, y) in x4.zip(y4) {
                    for l in 0..4 {
                        parts[l] += (x[l] - mr) * (y[l] - ms);
                    }
                }
                for (l, (x, y)) in tail.enumerate() {
                    parts[l] += (x - mr) * (y - ms);
                }
                let rest = (parts[0] + parts[1]) + (parts[2] + parts[3]);
                let value = w.cov0 * (ar[0] - mr) * (bs[0] - ms) + w.rest * rest;
                out[(r, s)] = value;
                if symmetric {
                    out[(s, r)] = value;
                }
            }
        }
    }

    /// The cross-covariance of the points of the last [`SigmaPoints::place`] with `images`
    /// (component-major), `out[(r, s)] = Σᵢ Wᵢᶜ (χ_r,i − m_r)(a_s,i − ā_s)`, from the points'
    /// construction: `χ₀ − m = 0` and `χ_{±i} − m = ±√(n+λ) Lᵢ`, so that the images' mean
    /// cancels and `out = W √(n+λ) L D` with `D_is = a_s,+i − a_s,−i` — a triangular product in
    /// place of a sum over the 2n + 1 points per entry.
    fn cross_with_points(&self, w: &Weights, images: &[f64], out: &mut DMatrix<f64>) {
        let (n, c) = (self.factor.nrows(), self.count);
        let scale = w.rest * w.spread;
        let l = self.factor.as_slice();
        for (s, row) in images.chunks_exact(c).enumerate() {
            let (plus, minus) = row[1..].split_at(n);
            for r in 0..n {
                // Row r of the lower-triangular L: L(r, i) at i n + r, i ≤ r.
                let v: f64 = (0..=r).map(|i| l[i * n + r] * (plus[i] - minus[i])).sum();
                out[(r, s)] = scale * v;
            }
        }
    }
}

/// The unscented Kalman filter.
///
/// The statistical linearisation `A = C P⁻¹` of a map with cross-covariance
/// `C = Cov(f(x), x)`, into `a` (row-major): `Aᵀ = P⁻¹ Cᵀ` by P's Cholesky factor.
fn linearise(p: &DMatrix<f64>, c: &DMatrix<f64>, a: &mut [f64]) -> Result<(), FilterError> {
    let n = p.nrows();
    let at = crate::linalg::cholesky(p, "covariance")?.solve(&c.transpose());
    for i in 0..n {
        for j in 0..n {
            a[i * n + j] = at[(j, i)];
        }
    }
    Ok(())
}

/// The unscented Kalman filter with van der Merwe's scaled sigma points (α, β, κ as in 003 §5
/// and 004 §4): `λ = α²(n + κ) − n`, points `m` and `m ± √(n+λ) Lᵢ` (L the Cholesky factor of
/// P), weights `W₀ᵐ = λ/(n+λ)`, `W₀ᶜ = W₀ᵐ + 1 − α² + β`, `Wᵢ = 1/(2(n+λ))`.
///
/// A discrete-time map ([`crate::Dynamics::Discrete`]) is predicted by the unscented
/// transform itself, one transition at a time: `m ← Σ Wᵐ F(χᵢ)`,
/// `P ← Σ Wᶜ (F(χᵢ) − m)(F(χᵢ) − m)ᵀ + Q` (Wan & van der Merwe 2000) — or, for a map that
/// is affine over the domain, by `A m + b` and `A P Aᵀ + Q`, which the transform gives exactly
/// for such a map, without evaluating it at the sigma points.
///
/// Prediction integrates the sigma-point moment equations of the continuous–discrete UKF
/// (Särkkä 2007) by RK4: with sigma points χᵢ of (m, P),
/// `dm/dt = Σ Wᵢᵐ f(χᵢ)`, `dP/dt = Σ Wᵢᶜ [(f(χᵢ) − dm/dt)(χᵢ − m)ᵀ + (χᵢ − m)(f(χᵢ) − dm/dt)ᵀ] + Q`
/// (exact for linear drifts, where it reduces to the Kalman–Bucy moment equations). The
/// update uses the observation as a measurement (`measurement`). P is
/// symmetrised after each step; a failed Cholesky factorisation is returned as
/// [`FilterError::NotPositiveDefinite`], never a panic.
///
/// # Example
///
/// ```
/// # #[cfg(feature = "std")] {
/// use zakai::{Filter, Model, Noise, Ukf};
///
/// // dx = −x³ dt + dv, z_k = x_k + v_k (Var v = 0.1) every 0.1.
/// let model = Model::from_text(&["-x^3"], &["x"], Noise::discrete(0.1)).unwrap();
/// let mut ukf = Ukf::builder(&model).prior_gaussian(&[0.0], &[[1.0]]).build().unwrap();
/// for z in [0.3, 0.5, 0.4] {
///     ukf.step_measurement(0.1, &[z]).unwrap();
/// }
/// assert!(ukf.estimate().mean[0] > 0.0);
/// # }
/// ```
///
/// # Cost
///
/// Per RK4 stage, f at the 2n + 1 sigma points and a Cholesky factorisation of P; per update, h
/// at the sigma points and an m × m solve: O(substeps · (n · cost(f) + n³) + m³).
///
/// # When it fails
///
/// Its Gaussian holds one mode: a posterior with two (h = x² with a prior straddling 0, the
/// cubic sensor early on) is averaged into one, whose mean can sit between the modes where the
/// state never is. The sigma points see f and h only within about √(n + λ) standard deviations of
/// the mean. A covariance that is no longer positive definite is an error, never a panic; its
/// self-check watches the innovations ([`crate::Filter::self_check`]).
#[derive(Clone, Debug)]
pub struct Ukf {
    name: String,
    model: Model,
    q: crate::model::ProcessNoise,
    form: MeasurementForm,
    substeps: crate::filters::Substeps,
    weights: Weights,
    state: GaussianState,
    sigma: SigmaPoints,
}

impl Ukf {
    /// Builds the filter, for observation interval Δτ when the context has one (a step of
    /// another length then takes as many RK4 steps of at most Δτ/substeps as it needs); fails
    /// on invalid parameters.
    pub(crate) fn new(
        name: String,
        ctx: &crate::filters::method::BuildContext,
        params: &UkfParams,
    ) -> Result<Self, FilterError> {
        let (model, prior) = (ctx.model, ctx.prior);
        let n = model.n as f64;
        if let Some((field, msg)) = params.problems(model.n).into_iter().next() {
            return Err(FilterError::Unsuitable(format!("UKF {field}: {msg}")));
        }
        let lambda = params.alpha * params.alpha * (n + params.kappa) - n;
        let weights = Weights {
            spread: libm::sqrt(n + lambda),
            mean0: lambda / (n + lambda),
            cov0: lambda / (n + lambda) + 1.0 - params.alpha * params.alpha + params.beta,
            rest: 0.5 / (n + lambda),
        };
        Ok(Ukf {
            form: MeasurementForm::new(&name, model)?,
            name,
            model: model.clone(),
            q: model.process_noise(),
            substeps: crate::filters::Substeps::new(params.substeps, ctx.dt_obs),
            weights,
            state: GaussianState::initial(prior.mean(), prior.covariance(), &params.init, model.m)
                .with_affine_map(model, ctx.probes),
            sigma: SigmaPoints::new(model.n, model.m),
        })
    }

    /// The sigma-point moment rates at (m, P) into (dm, dP) (see the module doc): f over all
    /// sigma points in one batch. With `linearisation`, also the statistically linearised
    /// drift `A = E[(f(x) − f̄)(x − m)ᵀ] P⁻¹` there (row-major), for the unscented RTS
    /// smoother ([`crate::Smoother`] (S1)).
    fn rates(
        model: &Model,
        q: &crate::model::ProcessNoise,
        w: &Weights,
        sigma: &mut SigmaPoints,
        (m, p): (&DVector<f64>, &DMatrix<f64>),
        (dm, dp): (&mut DVector<f64>, &mut DMatrix<f64>),
        linearisation: Option<&mut [f64]>,
    ) -> Result<(), FilterError> {
        let n = model.n;
        let len = sigma.map_points(&*model.drift, w, (m, p))?;
        let images = &sigma.images[..len];
        sigma.mean(w, images, dm.as_mut_slice());
        sigma.cross_cov(
            w,
            (images, dm.as_slice()),
            (&sigma.points, m.as_slice()),
            dp,
        );
        if let Some(a) = linearisation {
            linearise(p, dp, a)?;
        }
        // dP = C + Cᵀ + Q(m).
        for a in 0..n {
            for b in a..n {
                let (x, y) = (dp[(a, b)], dp[(b, a)]);
                dp[(a, b)] = x + y;
                dp[(b, a)] = y + x;
            }
        }
        q.add_at(m.as_slice(), 1.0, dp);
        Ok(())
    }

    /// A discrete-time transition's moments through the sigma points χᵢ of (m, P):
    /// `F̄ = Σ Wᵐ F(χᵢ)`, `Cov F = Σ Wᶜ (F(χᵢ) − F̄)(F(χᵢ) − F̄)ᵀ` (Q is added by the caller),
    /// and with `linearisation` the statistical linearisation `A = Cov(F(x), x) P⁻¹`
    /// (row-major) for the unscented RTS smoother.
    fn map_moments(
        model: &Model,
        w: &Weights,
        sigma: &mut SigmaPoints,
        (m, p): (&DVector<f64>, &DMatrix<f64>),
        (mean, cov): (&mut DVector<f64>, &mut DMatrix<f64>),
        linearisation: Option<&mut [f64]>,
    ) -> Result<(), FilterError> {
        let n = model.n;
        let len = sigma.map_points(&*model.drift, w, (m, p))?;
        let images = &sigma.images[..len];
        sigma.mean(w, images, mean.as_mut_slice());
        sigma.cross_cov(w, (images, mean.as_slice()), (images, mean.as_slice()), cov);
        if let Some(a) = linearisation {
            let mut cross = DMatrix::zeros(n, n);
            sigma.cross_cov(
                w,
                (images, mean.as_slice()),
                (&sigma.points, m.as_slice()),
                &mut cross,
            );
            linearise(p, &cross, a)?;
        }
        Ok(())
    }

    /// The update with h over all sigma points in one batch: `ẑ = Σ Wᵐ scale·h(χᵢ)`,
    /// `P_zz = Σ Wᶜ (zᵢ − ẑ)(zᵢ − ẑ)ᵀ + R`, `P_xz = Σ Wᶜ (χᵢ − m)(zᵢ − ẑ)ᵀ`.
    fn update(
        model: &Model,
        w: &Weights,
        sigma: &mut SigmaPoints,
        state: &mut GaussianState,
        meas: &Measurement,
    ) -> Result<(), FilterError> {
        sigma.place(w, &state.mean, &state.cov)?;
        let c = sigma.count;
        let zs = &mut sigma.images[..model.m * c];
        model
            .observation
            .eval_batch(&sigma.points, zs, &mut sigma.scratch);
        // Missing components read 0 at every point (see [`super::measurement`]).
        for (z, seen) in zs.chunks_exact_mut(c).zip(&meas.observed) {
            let scale = meas.scale;
            z.iter_mut()
                .for_each(|z| *z = if *seen { *z * scale } else { 0.0 });
        }
        let zs = &sigma.images[..model.m * c];
        let parts = &mut state.parts;
        parts.observed = meas.count;
        // ẑ in the residual's storage until the covariances are taken.
        let zhat = parts.residual.as_mut_slice();
        sigma.mean(w, zs, zhat);
        sigma.cross_cov(w, (zs, zhat), (zs, zhat), &mut parts.pzz);
        let noise = meas.noise_cov.as_slice();
        parts.pzz.iter_mut().zip(noise).for_each(|(p, r)| *p += r);
        sigma.cross_with_points(w, zs, &mut parts.pxz);
        for (r, z) in zhat.iter_mut().zip(meas.value.iter()) {
            *r = z - *r;
        }
        state.update(meas)
    }
}

super::smoother::gaussian_filter!(Ukf);

impl Filter for Ukf {
    super::smoother::gaussian_filter_opening!(estimate);

    fn step(&mut self, obs: &Observation) -> Result<(), FilterError> {
        let Ukf {
            name,
            model,
            q,
            form,
            substeps,
            weights,
            state,
            sigma,
        } = self;
        // Checked before anything moves: a refused observation leaves the state.
        let mut driven = super::DrivenStep::of(name, model, obs)?;
        let (step, form) = super::DrivenStep::parts(&mut driven, (model, obs.inputs), q, form);
        let meas = form.at(name, obs)?;
        state.transaction(|state| {
            if obs.dt > 0.0 && step.dynamics.is_discrete_time() {
                let tracking = state.transition().is_some();
                state.predict_transitions(&step, obs.dt, &mut |model, at, moments, a| {
                    Self::map_moments(model, weights, sigma, at, moments, tracking.then_some(a))
                })?;
            } else if obs.dt > 0.0 {
                let tracking = state.transition().is_some();
                state.predict_with(obs.dt, substeps.over(obs.dt), |at, rates, a| {
                    Self::rates(
                        step.dynamics,
                        step.q,
                        weights,
                        sigma,
                        at,
                        rates,
                        tracking.then_some(a),
                    )
                })?;
            }
            match meas {
                Some(meas) => {
                    meas.noise_at(step.measurement, state.mean.as_slice())?;
                    Self::update(step.measurement, weights, sigma, state, meas)
                }
                None => Ok(()),
            }
        })
    }

    fn warnings(&self) -> alloc::vec::Vec<alloc::string::String> {
        super::approximations(&self.form, &self.q, &self.model, &self.name)
    }

    fn self_check(&self, out: &mut Vec<crate::filters::Concern>) {
        self.state.innovations.check(out);
    }
}
