//! Continuous-time prediction between observations, by classical fourth-order Runge–Kutta.
//!
//! Mean and covariance follow moment equations `(dm/dt, dP/dt) = rates(m, P)`: the EKF's
//!   linearised rates (Jazwinski) `dm/dt = f(m)`, `dP/dt = F(m) P + P F(m)ᵀ + Q`,
//!   `F = ∂f/∂x`, or the UKF's sigma-point rates (Särkkä's continuous–discrete UKF).
//! Every intermediate lives in a [`MomentWork`] made once per filter: a step allocates nothing.
//!
//! A discrete-time map `x_k = F(x_(k−1)) + w_k` ([`crate::Dynamics::Discrete`]) is predicted
//! one transition at a time instead ([`transition`]): `m ← F̄`, `P ← C + Q` with the map's
//! moments taken by linearisation (EKF) or by sigma points (UKF).

use alloc::vec;
use alloc::vec::Vec;

use nalgebra::{DMatrix, DVector};

use crate::error::FilterError;
use crate::model::Model;

/// Storage of one RK4 step of the moment equations for an n-dimensional state.
#[derive(Clone, Debug)]
pub(crate) struct MomentWork {
    /// The four stages' rates of m and of P.
    km: [DVector<f64>; 4],
    kp: [DMatrix<f64>; 4],
    /// The point a stage's rates are taken at.
    mt: DVector<f64>,
    pt: DMatrix<f64>,
    /// ∂f/∂x, row-major (the EKF's rates).
    jacobian: Vec<f64>,
    /// The transition's sensitivity, integrated alongside when a smoother asks for it.
    pub sensitivity: Option<Sensitivity>,
}

/// The sensitivity of the prediction `Φ = ∂m(t)/∂m(t₀)` of the linearised dynamics,
/// `dΦ/dt = A(t) Φ` with `A` the drift's linearisation the rates leave in their `jacobian`
/// storage (∂f/∂x at the mean for the EKF, the statistical linearisation for the UKF), and the
/// predicted moments of the last prediction: what an RTS smoother needs of a step
/// ([`crate::Smoother`] (S1)).
#[derive(Clone, Debug)]
pub(crate) struct Sensitivity {
    /// Φ since the step began ([`Sensitivity::begin`]).
    pub phi: DMatrix<f64>,
    /// The predicted mean and covariance (the moments the step started from until it
    /// predicts).
    pub predicted: (DVector<f64>, DMatrix<f64>),
    phit: DMatrix<f64>,
    kphi: [DMatrix<f64>; 4],
    a: DMatrix<f64>,
}

impl Sensitivity {
    /// Storage for an `n`-dimensional state.
    pub(crate) fn new(n: usize) -> Self {
        Sensitivity {
            phi: DMatrix::identity(n, n),
            predicted: (DVector::zeros(n), DMatrix::zeros(n, n)),
            phit: DMatrix::zeros(n, n),
            kphi: core::array::from_fn(|_| DMatrix::zeros(n, n)),
            a: DMatrix::zeros(n, n),
        }
    }

    /// A step begins at (m, P): Φ = I, and the prediction is (m, P) until one is made.
    pub(crate) fn begin(&mut self, m: &DVector<f64>, p: &DMatrix<f64>) {
        self.phi.fill_with_identity();
        self.predicted.0.copy_from(m);
        self.predicted.1.copy_from(p);
    }

    /// `kphi[stage] = A Φ_stage` with A row-major in `a` and `Φ_stage = Φ + along · kphi[prev]`.
    fn stage(&mut self, stage: usize, along: f64, a: &[f64]) {
        let n = self.phi.nrows();
        for i in 0..n {
            for j in 0..n {
                self.a[(i, j)] = a[i * n + j];
            }
        }
        self.phit.copy_from(&self.phi);
        if stage > 0 {
            self.phit
                .zip_apply(&self.kphi[stage - 1], |x, k| *x += k * along);
        }
        self.kphi[stage].gemm(1.0, &self.a, &self.phit, 0.0);
    }
}

impl MomentWork {
    /// Storage for an `n`-dimensional state.
    pub(crate) fn new(n: usize) -> Self {
        MomentWork {
            km: core::array::from_fn(|_| DVector::zeros(n)),
            kp: core::array::from_fn(|_| DMatrix::zeros(n, n)),
            mt: DVector::zeros(n),
            pt: DMatrix::zeros(n, n),
            jacobian: vec![0.0; n * n],
            sensitivity: None,
        }
    }
}

/// The EKF's moment rates: `dm/dt = f(m)`, `dP/dt = F(m) P + P F(m)ᵀ + Q(m)` (Q at the mean
/// when G depends on the state), written into
/// `dm`, `dp`; `jacobian` holds n² values.
pub(crate) fn linearized_rates(
    model: &Model,
    q: &crate::model::ProcessNoise,
    jacobian: &mut [f64],
    (m, p): (&DVector<f64>, &DMatrix<f64>),
    (dm, dp): (&mut DVector<f64>, &mut DMatrix<f64>),
) {
    let n = model.n;
    model
        .drift
        .eval_with_jacobian(m.as_slice(), dm.as_mut_slice(), jacobian);
    // (F P)_ij = Σ_k F_ik P_kj, and P Fᵀ = (F P)ᵀ (P symmetric): F P once, then its
    // transpose added (P column-major: column j is P's row j).
    let (p, out) = (p.as_slice(), dp.as_mut_slice());
    if n == 1 {
        // dP/dt = 2 F P: the value of the loops below (x + x = 2x exactly), without them.
        out[0] = 2.0 * (jacobian[0] * p[0]);
    } else {
        for j in 0..n {
            let column = &p[j * n..(j + 1) * n];
            for i in 0..n {
                let row = &jacobian[i * n..(i + 1) * n];
                out[j * n + i] = row.iter().zip(column).map(|(f, p)| f * p).sum();
            }
        }
        for j in 0..n {
            for i in 0..=j {
                let s = out[j * n + i] + out[i * n + j];
                out[j * n + i] = s;
                out[i * n + j] = s;
            }
        }
    }
    match q.constant() {
        Some(q) => out.iter_mut().zip(q.as_slice()).for_each(|(o, q)| *o += q),
        None => q.add_at(m.as_slice(), 1.0, dp),
    }
}

/// Integrates `(dm/dt, dP/dt) = rates(m, P)` over `dt` in `substeps` RK4 steps, in place;
/// `rates((m, P), (dm, dP), jacobian)` writes the rates at (m, P), with n² values of scratch
/// in which it leaves the drift's linearisation A (row-major) when the work tracks the
/// [`Sensitivity`] (which is then integrated alongside).
pub(crate) fn rk4_moments(
    m: &mut DVector<f64>,
    p: &mut DMatrix<f64>,
    dt: f64,
    substeps: usize,
    work: &mut MomentWork,
    mut rates: impl FnMut(
        (&DVector<f64>, &DMatrix<f64>),
        (&mut DVector<f64>, &mut DMatrix<f64>),
        &mut [f64],
    ) -> Result<(), FilterError>,
) -> Result<(), FilterError> {
    let h = dt / substeps as f64;
    let MomentWork {
        km,
        kp,
        mt,
        pt,
        jacobian,
        sensitivity,
    } = work;
    for _ in 0..substeps {
        for stage in 0..4 {
            if stage == 0 {
                rates((m, p), (&mut km[0], &mut kp[0]), jacobian)?;
                if let Some(s) = sensitivity.as_mut() {
                    s.stage(0, 0.0, jacobian);
                }
                continue;
            }
            // Stages 2 and 3 at half a step along the previous rates, stage 4 at a whole one.
            let along = if stage == 3 { h } else { 0.5 * h };
            along_rates(
                mt.as_mut_slice(),
                m.as_slice(),
                km[stage - 1].as_slice(),
                along,
            );
            along_rates(
                pt.as_mut_slice(),
                p.as_slice(),
                kp[stage - 1].as_slice(),
                along,
            );
            rates((mt, pt), (&mut km[stage], &mut kp[stage]), jacobian)?;
            if let Some(s) = sensitivity.as_mut() {
                s.stage(stage, along, jacobian);
            }
        }
        let sixth = h / 6.0;
        // x += h/6 (k₁ + 2k₂ + 2k₃ + k₄).
        let combine = |x: &mut [f64], k: [&[f64]; 4]| {
            for (i, x) in x.iter_mut().enumerate() {
                *x += sixth * (k[0][i] + 2.0 * (k[1][i] + k[2][i]) + k[3][i]);
            }
        };
        combine(m.as_mut_slice(), core::array::from_fn(|s| km[s].as_slice()));
        combine(p.as_mut_slice(), core::array::from_fn(|s| kp[s].as_slice()));
        if let Some(s) = sensitivity.as_mut() {
            let Sensitivity { phi, kphi, .. } = s;
            combine(
                phi.as_mut_slice(),
                core::array::from_fn(|s| kphi[s].as_slice()),
            );
        }
        crate::linalg::symmetrize(p);
    }
    if let Some(s) = sensitivity.as_mut() {
        s.predicted.0.copy_from(m);
        s.predicted.1.copy_from(p);
    }
    Ok(())
}

/// `out = x + along · k` (a stage's point from the state and the previous stage's rates).
#[inline]
fn along_rates(out: &mut [f64], x: &[f64], k: &[f64], along: f64) {
    for ((o, x), k) in out.iter_mut().zip(x).zip(k) {
        *o = x + along * k;
    }
}

/// A transition's moments through the map, `(F̄, Cov F, A)` into `(mean, cov, a)` with `A` the
/// map's linearisation (row-major n², its Jacobian at the mean for the EKF, the statistical
/// linearisation `Cov(F(x), x) P⁻¹` for the UKF) — what [`transition`] asks of a filter.
pub(crate) type MapMoments<'a> = dyn FnMut(
        &Model,
        (&DVector<f64>, &DMatrix<f64>),
        (&mut DVector<f64>, &mut DMatrix<f64>),
        &mut [f64],
    ) -> Result<(), FilterError>
    + 'a;

/// One transition of a discrete-time map, in place: `m ← F̄`, `P ← Cov F + Q(m)` (Q at the
/// mean the transition starts from), from `moments`; with the [`Sensitivity`] tracked,
/// `Φ ← A Φ` and the predicted moments.
pub(crate) fn transition(
    model: &Model,
    q: &crate::model::ProcessNoise,
    m: &mut DVector<f64>,
    p: &mut DMatrix<f64>,
    work: &mut MomentWork,
    moments: &mut MapMoments<'_>,
) -> Result<(), FilterError> {
    let MomentWork {
        km,
        kp,
        jacobian,
        sensitivity,
        ..
    } = work;
    moments(model, (m, p), (&mut km[0], &mut kp[0]), jacobian)?;
    q.add_at(m.as_slice(), 1.0, &mut kp[0]);
    // A mixture noise by its moments: its covariance is G Gᵀ (in q), its mean added here.
    if let Some(w) = &model.transition_mixture {
        km[0] += w.mean();
    }
    crate::linalg::small::copy(m.as_mut_slice(), km[0].as_slice());
    crate::linalg::small::copy(p.as_mut_slice(), kp[0].as_slice());
    crate::linalg::symmetrize(p);
    if let Some(s) = sensitivity.as_mut() {
        s.stage(0, 0.0, jacobian);
        s.phi.copy_from(&s.kphi[0]);
        s.predicted.0.copy_from(m);
        s.predicted.1.copy_from(p);
    }
    Ok(())
}

/// The EKF's moments of a transition: `F̄ = F(m)`, `Cov F = J P Jᵀ`, `A = J = ∂F/∂x(m)`.
pub(crate) fn linearized_map(
    model: &Model,
    (m, p): (&DVector<f64>, &DMatrix<f64>),
    (mean, cov): (&mut DVector<f64>, &mut DMatrix<f64>),
    jacobian: &mut [f64],
) -> Result<(), FilterError> {
    let n = model.n;
    model.drift.eval(m.as_slice(), mean.as_mut_slice());
    model.drift.jacobian(m.as_slice(), jacobian);
    // J P Jᵀ entry by entry (no temporaries: a step allocates nothing).
    for a in 0..n {
        for b in a..n {
            let mut sum = 0.0;
            for k in 0..n {
                let row: f64 = (0..n).map(|l| p[(k, l)] * jacobian[b * n + l]).sum();
                sum += jacobian[a * n + k] * row;
            }
            cov[(a, b)] = sum;
            cov[(b, a)] = sum;
        }
    }
    Ok(())
}

/// A discrete-time map that is affine, `F(x) = A x + b` over the domain
/// ([`super::linear::affine_over`]): a transition's moments are then exact, `F̄ = A m + b`,
/// `Cov F = A P Aᵀ` with linearisation `A` — what the EKF's Jacobian and the UKF's sigma
/// points both give (the unscented transform is exact for an affine map), here without
/// evaluating F and its Jacobian, or F at 2n + 1 points, at every transition.
#[derive(Clone, Debug)]
pub(crate) struct AffineMap {
    a: DMatrix<f64>,
    b: DVector<f64>,
    /// Aᵀ (column-major: A row by row, the linearisation a tracked [`Sensitivity`] reads).
    at: DMatrix<f64>,
    /// P Aᵀ.
    pat: DMatrix<f64>,
}

impl AffineMap {
    /// The map of an autonomous discrete-time `model` whose F is affine over `probes`, else
    /// `None` (a driven model's map changes with its inputs).
    pub(crate) fn of(model: &Model, probes: &[Vec<f64>]) -> Option<Self> {
        if !model.is_discrete_time() || model.is_driven() {
            return None;
        }
        let (a, b) = super::linear::affine_over(&*model.drift, probes)?;
        let n = a.nrows();
        Some(AffineMap {
            at: a.transpose(),
            pat: DMatrix::zeros(n, n),
            a,
            b,
        })
    }

    /// The transition's moments `(A m + b, A P Aᵀ, A)` into `(mean, cov, jacobian)`: a
    /// [`MapMoments`] for the filter's own map.
    pub(crate) fn moments(
        &mut self,
        (m, p): (&DVector<f64>, &DMatrix<f64>),
        (mean, cov): (&mut DVector<f64>, &mut DMatrix<f64>),
        jacobian: &mut [f64],
    ) {
        crate::linalg::small::affine_moments(
            m.len(),
            (self.a.as_slice(), self.b.as_slice()),
            (m.as_slice(), p.as_slice()),
            self.pat.as_mut_slice(),
            (mean.as_mut_slice(), cov.as_mut_slice()),
        );
        jacobian.copy_from_slice(self.at.as_slice());
    }
}

#[cfg(test)]
mod tests {
    use super::AffineMap;
    use crate::model::{Model, Noise};
    use crate::testing::test;
    use nalgebra::{DMatrix, DVector};

    fn map(drift: &[&str]) -> Model {
        let observation: alloc::vec::Vec<&str> = drift.iter().map(|_| "x1").collect();
        Model::from_text(drift, &observation[..1], Noise::discrete(1.0))
            .unwrap()
            .discrete_time(1.0)
            .unwrap()
    }

    /// An affine map is found with its A and b, and its moments are `A m + b` and `A P Aᵀ`
    /// computed here by hand; a map that bends anywhere on the box, a continuous-time drift
    /// and a map without probes are not taken for affine.
    #[test]
    fn an_affine_map_gives_its_exact_moments_and_only_it() {
        let probes = crate::filters::method::probe_points(&[(-3.0, 3.0), (-2.0, 5.0)]);
        let mut affine =
            AffineMap::of(&map(&["x1 + 0.1*x2 - 1", "0.9*x2 + 2"]), &probes).expect("affine");
        let (m, p) = (
            DVector::from_vec(alloc::vec![0.5, -1.5]),
            DMatrix::from_row_slice(2, 2, &[2.0, 0.3, 0.3, 0.7]),
        );
        let (mut mean, mut cov, mut jacobian) = (DVector::zeros(2), DMatrix::zeros(2, 2), [0.0; 4]);
        affine.moments((&m, &p), (&mut mean, &mut cov), &mut jacobian);
        let a = DMatrix::from_row_slice(2, 2, &[1.0, 0.1, 0.0, 0.9]);
        let expected_mean = &a * &m + DVector::from_vec(alloc::vec![-1.0, 2.0]);
        let expected_cov = &a * &p * a.transpose();
        assert!((mean - expected_mean).amax() < 1e-14);
        assert!((cov - expected_cov).amax() < 1e-14);
        assert_eq!(jacobian, [1.0, 0.1, 0.0, 0.9]);
        // Bends only far from 0 (x1³/1000 is 0.027 at the box's edge): still not affine.
        assert!(AffineMap::of(&map(&["x1 + x1^3/1000", "x2"]), &probes).is_none());
        assert!(AffineMap::of(&map(&["x1", "x2"]), &[]).is_none());
        let sde = Model::from_text(&["-x1", "x2"], &["x1"], Noise::discrete(1.0)).unwrap();
        assert!(AffineMap::of(&sde, &probes).is_none());
    }
}
