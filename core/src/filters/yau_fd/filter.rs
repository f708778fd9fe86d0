//! The Yau–Yau filter itself: schemes, update, estimate (see the parent module's doc).

use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use nalgebra::DVector;

use super::guarantees::substeps_of;
use super::guarantees::{self, GuaranteeWarning};
use super::iem::SplitIem;
use super::operator::KolmogorovOperator;
use super::qiem::QiemStep;
use super::superposition::Superposition;
use super::update::{observation_factor, CellSamples};
use super::{LikelihoodPlacement, PotentialTerm, Scheme, YauYauParams};
use crate::error::FilterError;
use crate::filters::{Estimate, Filter, LengthCache, Observation, ObservationKind, Observed};
use crate::grid::TensorGrid;
use crate::model::dmz::{ObservedTerms, PartialIncrements};
use crate::model::Model;

#[derive(Clone, Debug)]
enum Solver {
    Iem(SplitIem),
    Qiem(QiemStep),
    Superposition(Superposition),
}

/// A solver with the interval length it is made for and its substeps.
type SolverFor = (f64, usize, Solver);

/// A Yau–Yau finite-difference filter.
///
/// The finite-difference Yau–Yau filters of 000 (Yueh, Lin, Yau).
///
/// Between observations the unnormalised density solves the Kolmogorov equation (2) on a
/// tensor grid with zero Dirichlet boundary (`operator`); at each observation time it is
/// multiplied by the robust-DMZ factor `exp(Δyᵀ S⁻¹ h)` (15). Schemes:
///
/// * [`Scheme::Iem`] — the θ-scheme (12)–(14), Algorithm 2:
///   `[I − αΔt A] Uⁿ = [I + βΔt A] Uⁿ⁻¹`, α + β = 1; in 1-D a tridiagonal (Thomas) solve
///   factored once, in 2-D and 3-D the documented alternative of Lie operator splitting into
///   one such tridiagonal θ-step per dimension (O(Δt) splitting error, the scheme's own order);
/// * [`Scheme::Qiem`] — the quasi-implicit scheme (17)–(18), Algorithm 3: drift and potential
///   explicit, the Laplacian implicit, solved by a DST-I in every dimension (rustfft plans
///   built once, no allocation per step);
/// * [`Scheme::Qiem4`] — the fourth-order 2-D QIEM of (20)–(21), Algorithm 4: 9-point
///   Laplacian diagonalised by the same DSTs, fourth-order first differences for the drift, and
///   (our addition, see `SpectralSolve::new_fourth_order`) the compact right-hand side without
///   which the 9-point stencil is only second order;
/// * [`Scheme::Superposition`] — the superposition technique of §2.5: off-line, QIEM carries
///   Gaussian bumps `e^{−η‖s − c_k‖²}` over one observation interval; on-line, the density is
///   projected onto the bumps by least squares and the prediction is the same combination of
///   their stored solutions (two matrix–vector products per interval, no allocation).
///
/// The potential term `q u` of QIEM is explicit in (18); for steep h (`q = −½ h²` reaches
/// −10⁹ at the edge of a box for h = x⁶) the factor `1 + Δt q` is hugely negative and the
/// scheme is unstable ((31) fails there). [`PotentialTerm::Exponential`] (the default) applies
/// `e^{Δt q}` instead — the same first-order consistency, unconditionally stable for q ≤ 0;
/// [`PotentialTerm::Explicit`] is (18) exactly. The drift stays explicit either way, and a
/// steep one (f = −x³ reaches |f| = 125 at the edge of [−5, 5]) needs `Δt p² ≤ Q` at every
/// node: QIEM, QIEM-4 and the superposition technique's bumps take as many substeps as
/// (31) and that bound ask for on the grid (`qiem_substeps`), at most `dt`
/// long, and report the shortened step among the warnings.
///
/// By default ([`LikelihoodPlacement::InUpdate`]) the `−½hᵀS⁻¹h` part of q moves into the update, whose
/// factor is then the bounded Gaussian likelihood of the increment (see `operator`);
/// [`LikelihoodPlacement::InOperator`] keeps 000's form.
///
/// The update (15) is evaluated in the log domain — `u_i ← exp(a_i + ln u_i − max_j(a_j + ln u_j))`
/// with `a = Δyᵀ S⁻¹ h` — so it neither overflows nor underflows the largest value; the density
/// is then renormalised. Negative values left by the explicit drift are set to zero there. A
/// density whose mass vanishes or turns non-finite is a [`crate::FilterError::MassLost`] /
/// [`crate::FilterError::NonFinite`], never NaN.
///
/// # Example
///
/// ```
/// use zakai::{Filter, Model, Noise, Qiem};
///
/// // The cubic sensor of 000 §4.1: dx = dv, dy = x³ dt + dw, observed every 0.01.
/// let model = Model::from_text(&["0"], &["x^3"], Noise::continuous(1.0)).unwrap();
/// let mut qiem = Qiem::builder(&model)
///     .prior_gaussian(&[0.0], &[[1.0]])
///     .domain(&[(-6.0, 6.0)])
///     .dt(0.01)
///     .build()
///     .unwrap();
/// for dy in [0.002, 0.004, -0.001] {
///     qiem.step_increment(0.01, &[dy]).unwrap();
/// }
/// assert!(qiem.density().is_some() && qiem.estimate().mean[0].is_finite());
/// ```
///
/// # Cost
///
/// Per substep on N nodes in d dimensions: IEM one tridiagonal solve per grid line, O(d · N);
/// QIEM an explicit sweep and a forward and inverse DST per dimension, O(d · N log N); QIEM-4
/// the same with five-point stencils; the superposition technique one product with its
/// precomputed operator. Then the update (15), O(N · m). The grid is checked against the memory
/// cap before anything is allocated.
///
/// # When it fails
///
/// On a box too small for the posterior (mass reaching the edge), a grid too coarse for it
/// (fewer than a few nodes per posterior standard deviation), or substeps beyond the stability
/// conditions (22)/(30)/(31) of 000: each is reported — as a warning for the chosen steps, and by
/// the self-checks while it runs ([`crate::Filter::self_check`]) — rather than returned as a
/// silently wrong density; a density whose mass vanishes or turns non-finite is an error.
#[derive(Clone, Debug)]
pub struct YauYauFilter {
    name: String,
    scheme: Scheme,
    params: YauYauParams,
    grid: TensorGrid,
    op: KolmogorovOperator,
    /// A driven model ([`crate::Inputs`]): the operator is made anew at every step from
    /// the model at the interval's midpoint with its inputs.
    driven: Option<Model>,
    /// The density, normalised to unit mass.
    u: Vec<f64>,
    tmp: Vec<f64>,
    /// Δτ, its substeps and solver.
    solver: Option<SolverFor>,
    /// Solvers for other interval lengths (the remainders of irregular intervals after whole
    /// Δτ), with their substeps; at most [`crate::filters::REMAINDER_PLANS`].
    remainders: LengthCache<(usize, Solver)>,
    /// With the likelihood in the operator, an interval without an increment is the
    /// Fokker–Planck part alone: its operator (q = −∇·f, built on the first such interval)
    /// and its solvers per interval length (at most [`crate::filters::REMAINDER_PLANS`] + 1).
    prediction: Option<(KolmogorovOperator, LengthCache<(usize, Solver)>)>,
    /// The density and estimate a step started from.
    saved: crate::filters::SavedDensity,
    /// The last step's log-likelihood ([`Filter::log_likelihood`]).
    log_likelihood: f64,
    warnings: Vec<GuaranteeWarning>,
    /// The longest substep the scheme takes: `dt`, or shorter where QIEM's stability
    /// conditions (31) ask for it on this grid (`qiem_substeps`).
    step_bound: f64,
    /// Whether even the most substeps leave QIEM's stability conditions violated: mass at
    /// the edge is then the scheme's doing, not the posterior's.
    unstable: bool,
    estimate: Estimate,
    /// Storage of the estimate's moments.
    moments: crate::grid::Moments,
    /// The observation factor's samples inside every cell, when averaged over the cell.
    cell: Option<CellSamples>,
    /// The factor's terms for increments with some components missing.
    partial: PartialIncrements,
    /// The last step's predicted density (before its factor), kept for a smoother.
    predicted: Option<Vec<f64>>,
}

impl YauYauFilter {
    /// Tabulates the operator and the prior on the grid over `bounds`.
    pub(crate) fn new(
        name: String,
        scheme: Scheme,
        ctx: &crate::filters::method::BuildContext,
        params: &YauYauParams,
    ) -> Result<Self, crate::error::ZakaiError> {
        let dt_obs = ctx.interval(&name)?;
        let (model, prior, bounds) = (ctx.model, ctx.prior, ctx.bounds);
        let mut problems = params.problems(model.n);
        if scheme == Scheme::Superposition {
            problems.extend(params.superposition_problems(model.n));
        }
        if scheme == Scheme::Qiem4 {
            problems.extend(params.fourth_order_problems(model.n));
        }
        if let Some((field, msg)) = problems.into_iter().next() {
            return Err(FilterError::Unsuitable(format!("{name} {field}: {msg}")).into());
        }
        let grid = TensorGrid::new(bounds, &params.shape(model.n))
            .map_err(|e| FilterError::Unsuitable(format!("{e}")))?;
        let driven = model.is_driven().then(|| model.clone());
        // A driven model is tabulated at its start (t = 0, inputs 0) for the checks and
        // warnings below; each step tabulates it anew.
        let start = model.at(0.0, &vec![0.0; model.inputs.unwrap_or(0)])?;
        let model = &start;
        let op = KolmogorovOperator::new(
            model,
            &grid,
            params.likelihood == LikelihoodPlacement::InUpdate,
        )?;
        if op.state_dependent && scheme != Scheme::Iem {
            return Err(FilterError::Unsuitable(format!(
                "{name} needs a constant diffusion G: its DST solve (000 (18)) diagonalises the constant-coefficient ½ Σ Q_dd ∂²/∂s_d², and this model's G depends on the state; IEM's tridiagonal systems take a(x) node by node"
            )).into());
        }
        if !op.cross.is_empty() && scheme == Scheme::Qiem4 {
            return Err(FilterError::Unsuitable(format!(
                "{name} needs a diagonal Q = G Gᵀ: the mixed terms' explicit step is second order and would spoil the fourth-order scheme; QIEM and IEM take them"
            )).into());
        }
        if scheme == Scheme::Qiem4 {
            let (a, b) = (grid.spacing()[0], grid.spacing()[1]);
            if (a - b).abs() > 1e-9 * a || op.diffusion[0] != op.diffusion[1] {
                return Err(FilterError::Unsuitable(format!(
                    "{name}: the 9-point scheme needs square cells and equal diffusion, got Δs = ({a:.4}, {b:.4}) and Q = ({}, {}); make the domain square or adjust the points",
                    op.diffusion[0], op.diffusion[1]
                )).into());
            }
        }
        let u = grid.tabulate(|x| prior.density(x));
        let cell = if params.likelihood_samples > 1 {
            Some(CellSamples::new(
                model,
                &grid,
                params.likelihood_samples,
                params.likelihood == LikelihoodPlacement::InUpdate,
            )?)
        } else {
            None
        };
        let mut filter = YauYauFilter {
            name,
            scheme,
            params: params.clone(),
            tmp: vec![0.0; grid.len()],
            grid,
            op,
            driven,
            saved: crate::filters::SavedDensity::new(u.len(), &Estimate::zeros(model.n)),
            log_likelihood: 0.0,
            u,
            solver: None,
            remainders: LengthCache::new(crate::filters::REMAINDER_PLANS),
            prediction: None,
            warnings: Vec::new(),
            step_bound: params.dt,
            unstable: false,
            cell,
            partial: PartialIncrements::of(model, "the Yau–Yau filters")?,
            estimate: Estimate {
                mean: DVector::zeros(model.n),
                covariance: None,
                map: None,
            },
            moments: crate::grid::Moments::zeros(model.n),
            predicted: None,
        };
        filter.normalise()?;
        filter.prepare(dt_obs)?;
        Ok(filter)
    }

    /// The grid.
    pub fn grid(&self) -> &TensorGrid {
        &self.grid
    }

    /// The operator, the observation factor's terms and the solver for Δτ made from `model`,
    /// a driven model frozen for the step (the other lengths' solvers are dropped).
    fn retabulate(&mut self, model: &Model) -> Result<(), FilterError> {
        let in_update = self.params.likelihood == LikelihoodPlacement::InUpdate;
        let op = KolmogorovOperator::new(model, &self.grid, in_update)?;
        if op.state_dependent && self.scheme != Scheme::Iem {
            return Err(FilterError::Unsuitable(format!(
                "{} needs a constant diffusion G, and this model's G changes with the time or inputs; IEM's tridiagonal systems take a(x) node by node",
                self.name
            )));
        }
        if self.cell.is_some() {
            self.cell = Some(CellSamples::new(
                model,
                &self.grid,
                self.params.likelihood_samples,
                in_update,
            )?);
        }
        self.partial = PartialIncrements::of(model, "the Yau–Yau filters")?;
        self.op = op;
        self.remainders = LengthCache::new(crate::filters::REMAINDER_PLANS);
        self.prediction = None;
        let dt_obs = self.solver.as_ref().map(|s| s.0).expect("prepared in new");
        self.prepare(dt_obs)
    }

    /// Builds the solver for observation interval `dt_obs` (Δt rounded so that it divides it)
    /// and evaluates the guarantees for that step.
    fn prepare(&mut self, dt_obs: f64) -> Result<(), FilterError> {
        let chosen = match self.scheme {
            Scheme::Iem => guarantees::QiemSubsteps {
                substeps: substeps_of(dt_obs, self.params.dt),
                stable: true,
                warning: None,
            },
            _ => guarantees::qiem_substeps(
                &self.op,
                &self.grid,
                dt_obs,
                self.params.dt,
                self.explicit_potential(),
            ),
        };
        let substeps = chosen.substeps;
        self.unstable = !chosen.stable;
        let dt = dt_obs / substeps as f64;
        self.step_bound = dt.min(self.params.dt);
        let solver = match self.scheme {
            Scheme::Iem | Scheme::Qiem | Scheme::Qiem4 => self.stepper(dt),
            Scheme::Superposition => {
                let mut qiem =
                    QiemStep::new(&self.op, &self.grid, dt, PotentialTerm::Exponential, false);
                Solver::Superposition(Superposition::new(&self.grid, &self.params, |u, tmp| {
                    for _ in 0..substeps {
                        qiem.step(&self.grid, u, tmp);
                    }
                })?)
            }
        };
        self.warnings = match self.scheme {
            Scheme::Iem => {
                let mut w = guarantees::m_matrix(&self.op, &self.grid, dt);
                w.extend(guarantees::iem_stability(&self.op, &self.grid));
                w
            }
            Scheme::Qiem | Scheme::Qiem4 | Scheme::Superposition => {
                chosen.warning.into_iter().collect()
            }
        };
        if self.scheme != Scheme::Iem {
            // Every scheme but IEM solves with the DST.
            self.warnings
                .extend(guarantees::transform_length(&self.grid));
        }
        self.solver = Some((dt_obs, substeps, solver));
        Ok(())
    }

    /// Substeps over `interval` of at most the scheme's Δt, shortened as the stability
    /// conditions asked for Δτ.
    fn substeps_for(&self, interval: f64) -> usize {
        substeps_of(interval, self.step_bound)
    }

    /// The potential term the scheme's explicit part takes (the superposition technique
    /// carries its bumps with the exponential one).
    fn explicit_potential(&self) -> PotentialTerm {
        match self.scheme {
            Scheme::Superposition => PotentialTerm::Exponential,
            _ => self.params.potential,
        }
    }

    /// The scheme's step of length `dt` (the superposition technique's remainders: QIEM with
    /// the exponential potential, which its bumps are carried with).
    fn stepper(&self, dt: f64) -> Solver {
        stepper_for(self.scheme, &self.params, &self.op, &self.grid, dt)
    }

    /// Normalises to unit mass and refreshes the estimate.
    fn normalise(&mut self) -> Result<(), FilterError> {
        crate::filters::normalise_on_grid(
            &self.grid,
            &mut self.u,
            &mut self.moments,
            &mut self.estimate,
        )?;
        Ok(())
    }

    /// The robust-DMZ factor (15) in the log domain (see [`observation_factor`]); an increment
    /// with some components missing gets the factor of the observed ones
    /// ([`PartialIncrements`]). Returns the logarithm the factor was divided by.
    fn update(&mut self, dy: &[f64], dt_obs: f64) -> Result<f64, FilterError> {
        if let Some(cell) = &mut self.cell {
            return cell.update(&mut self.u, dy, dt_obs);
        }
        let (u, a) = (&mut self.u, &mut self.tmp);
        Ok(if dy.iter().any(|v| v.is_nan()) {
            let t = self.partial.terms(&self.op.s_inv_h, dy)?;
            observation_factor(u, a, &t, dt_obs)
        } else {
            let (gain, half) = (&self.op.s_inv_h, &self.op.half_hsh);
            observation_factor(u, a, &ObservedTerms { dy, gain, half }, dt_obs)
        })
    }

    /// Carries the density over `interval`: whole intervals Δτ with the solver made for Δτ,
    /// the rest with a solver for its length (made the first time that length occurs and kept
    /// among the last [`crate::filters::REMAINDER_PLANS`]).
    fn propagate(&mut self, interval: f64) {
        self.carry_over(interval, false);
    }

    /// [`YauYauFilter::propagate`], or with `transposed` its transpose (the remainder first,
    /// then the whole intervals, each with its solver transposed).
    fn carry_over(&mut self, interval: f64, transposed: bool) {
        let (built_for, _, _) = self.solver.as_ref().expect("prepared in new");
        let (whole, rest) = crate::filters::whole_intervals(interval, *built_for);
        let whole_intervals = |f: &mut Self| {
            for _ in 0..whole {
                let (_, substeps, solver) = f.solver.as_mut().expect("prepared in new");
                solver.run(*substeps, &f.grid, (&mut f.u, &mut f.tmp), transposed);
            }
        };
        if !transposed {
            whole_intervals(self);
        }
        if rest > 0.0 {
            if !self.remainders.bring_to_front(rest) {
                let substeps = self.substeps_for(rest);
                let solver = self.stepper(rest / substeps as f64);
                self.remainders.insert(rest, (substeps, solver));
            }
            let (substeps, solver) = self.remainders.front();
            solver.run(
                *substeps,
                &self.grid,
                (&mut self.u, &mut self.tmp),
                transposed,
            );
        }
        if transposed {
            whole_intervals(self);
        }
    }

    /// Carries the density over `interval` without an increment when the likelihood is in
    /// the operator: the Kolmogorov equation (2) of 000 with q = −∇·f alone (the term
    /// −½hᵀS⁻¹h belongs to the observation, which did not come), in steps of at most the
    /// scheme's Δt, with the scheme's solver for that operator (made the first time the
    /// length occurs).
    fn predict_without_likelihood(&mut self, interval: f64) {
        self.predict_without_likelihood_in(interval, false);
    }

    /// [`YauYauFilter::predict_without_likelihood`], or with `transposed` its transpose.
    fn predict_without_likelihood_in(&mut self, interval: f64, transposed: bool) {
        let keep = crate::filters::REMAINDER_PLANS + 1;
        let term = self.explicit_potential();
        let (op, cache) = self
            .prediction
            .get_or_insert_with(|| (self.op.without_observation_term(), LengthCache::new(keep)));
        if !cache.bring_to_front(interval) {
            let substeps = match self.scheme {
                Scheme::Iem => substeps_of(interval, self.params.dt),
                _ => {
                    guarantees::qiem_substeps(op, &self.grid, interval, self.step_bound, term)
                        .substeps
                }
            };
            let solver = stepper_for(
                self.scheme,
                &self.params,
                op,
                &self.grid,
                interval / substeps as f64,
            );
            cache.insert(interval, (substeps, solver));
        }
        let (substeps, solver) = cache.front();
        solver.run(
            *substeps,
            &self.grid,
            (&mut self.u, &mut self.tmp),
            transposed,
        );
    }

    /// What [`YauYauFilter::advance`] does to the density over `obs.dt` before the factor
    /// (15) — or with `transposed` its transpose — applied to `values`.
    fn carry_values(
        &mut self,
        obs: &Observation,
        values: &mut Vec<f64>,
        transposed: bool,
    ) -> Result<(), FilterError> {
        let observed = obs.check(
            &self.name,
            ObservationKind::Increment,
            self.op.s_inv_h.len(),
        )?;
        if obs.dt > 0.0 {
            core::mem::swap(&mut self.u, values);
            if observed != Observed::All
                && self.params.likelihood == LikelihoodPlacement::InOperator
            {
                self.predict_without_likelihood_in(obs.dt, transposed);
            } else {
                self.carry_over(obs.dt, transposed);
            }
            core::mem::swap(&mut self.u, values);
            if values.iter().any(|v| !v.is_finite()) {
                return Err(FilterError::NonFinite {
                    what: "density carried by the smoother",
                });
            }
        }
        Ok(())
    }

    /// The step of [`Filter::step`] once `obs` is checked (it may fail half-way); returns the
    /// step's log-likelihood: the logarithm of the mass the factor (15) leaves, relative to
    /// the mass it was applied to — the predicted density's (the normaliser
    /// `∫ exp(ΔyᵀS⁻¹h − ½hᵀS⁻¹hΔτ) p(x | past) dx`), or, when the operator carried the
    /// interval's −½hᵀS⁻¹h (likelihood in the operator, 000 (4)), the unit mass the
    /// interval started from (mass that leaves the box then counts against it).
    fn advance(&mut self, obs: &Observation, observed: Observed) -> Result<f64, FilterError> {
        let mut factor = None;
        if obs.dt > 0.0 {
            // With the likelihood in the operator, only a fully observed increment has its
            // −½hᵀS⁻¹h there; otherwise the Fokker–Planck part alone, and the observed
            // components' factor with their ½h_Oᵀ S_OO⁻¹ h_O.
            let in_operator = self.params.likelihood == LikelihoodPlacement::InOperator;
            if observed != Observed::All && in_operator {
                self.predict_without_likelihood(obs.dt);
            } else {
                self.propagate(obs.dt);
            }
            if let Some(kept) = &mut self.predicted {
                kept.copy_from_slice(&self.u);
            }
            if observed != Observed::Nothing {
                // The factor keeps only positive values (negative ones, left by a scheme
                // outside its positivity condition or by SPT's projection, become 0).
                let before = if in_operator && observed == Observed::All {
                    1.0
                } else {
                    self.grid.positive_mass(&self.u)
                };
                let shift = self.update(obs.value, obs.dt)?;
                factor = Some((shift, before));
            }
        } else if let Some(kept) = &mut self.predicted {
            kept.copy_from_slice(&self.u);
        }
        self.normalise()?;
        Ok(match factor {
            Some((shift, before)) => libm::log(self.moments.mass) + shift - libm::log(before),
            None => 0.0,
        })
    }
}

/// [`YauYauFilter::stepper`] for the operator `op`.
fn stepper_for(
    scheme: Scheme,
    params: &YauYauParams,
    op: &KolmogorovOperator,
    grid: &TensorGrid,
    dt: f64,
) -> Solver {
    match scheme {
        Scheme::Iem => Solver::Iem(SplitIem::new(op, grid, dt, params.alpha)),
        Scheme::Qiem | Scheme::Qiem4 => Solver::Qiem(QiemStep::new(
            op,
            grid,
            dt,
            params.potential,
            scheme == Scheme::Qiem4,
        )),
        Scheme::Superposition => Solver::Qiem(QiemStep::new(
            op,
            grid,
            dt,
            PotentialTerm::Exponential,
            false,
        )),
    }
}

impl Solver {
    /// `substeps` steps (the superposition technique: its whole interval at once), or with
    /// `transposed` their transpose (the backward step of a smoother).
    fn run(
        &mut self,
        substeps: usize,
        grid: &TensorGrid,
        (u, tmp): (&mut Vec<f64>, &mut Vec<f64>),
        transposed: bool,
    ) {
        match self {
            Solver::Iem(tri) => {
                for _ in 0..substeps {
                    match transposed {
                        false => tri.step(grid, u, tmp),
                        true => tri.step_transposed(grid, u, tmp),
                    }
                }
            }
            Solver::Qiem(qiem) => {
                for _ in 0..substeps {
                    match transposed {
                        false => qiem.step(grid, u, tmp),
                        true => qiem.step_transposed(grid, u, tmp),
                    }
                }
            }
            // The whole interval at once: project onto the bumps, combine their solutions.
            Solver::Superposition(spt) => match transposed {
                false => spt.apply(u),
                true => spt.apply_transposed(u),
            },
        }
    }
}

impl crate::filters::smoothing::GridTransition for YauYauFilter {
    fn grid_density(&self) -> (&TensorGrid, &[f64]) {
        (&self.grid, &self.u)
    }

    #[cfg(test)]
    fn carry(&mut self, obs: &Observation, values: &mut Vec<f64>) -> Result<(), FilterError> {
        self.carry_values(obs, values, false)
    }

    fn carry_back(&mut self, obs: &Observation, values: &mut Vec<f64>) -> Result<(), FilterError> {
        self.carry_values(obs, values, true)
    }

    crate::filters::smoothing::density_storage!();
}

impl Filter for YauYauFilter {
    crate::filters::kept_estimate_accessors!(density in u);

    fn smoother(
        &self,
        plan: &crate::filters::smoothing::SmoothingPlan,
    ) -> Result<alloc::boxed::Box<dyn crate::filters::smoothing::Smoother>, FilterError> {
        if self.driven.is_some() {
            return Err(crate::filters::smoothing::no_smoother(
                &self.name,
                "its backward pass replays one operator for every interval, and a driven model's changes with the time and inputs (not implemented)",
            ));
        }
        crate::filters::smoothing::grid_smoother(self, plan)
    }

    fn self_check(&self, out: &mut Vec<crate::filters::Concern>) {
        let from = out.len();
        crate::filters::grid_self_check(&self.grid, &self.u, &self.estimate, out);
        self.remainders.check(out);
        if let Some((_, cache)) = &self.prediction {
            cache.check(out);
        }
        if self.unstable {
            for c in out[from..]
                .iter_mut()
                .filter(|c| c.check == crate::filters::self_check::BOUNDARY_MASS_CHECK)
            {
                c.advice = "the density reaches the edge of the box, where QIEM's stability conditions (31) fail at any step it would take (see the warnings): the explicit drift there amplifies round-off, and a wider box makes |f| at its edge larger; shrink the domain or use IEM";
            }
            return;
        }
        if self.params.likelihood == LikelihoodPlacement::InOperator {
            // With −½hᵀS⁻¹h in q the implicit step damps the tails by (1 + |q|Δt)⁻¹ per step
            // instead of e^{−|q|Δt}: mass at the edge is then the time step's doing, and a
            // wider box (larger |q| at its edge) would make it worse.
            for c in out[from..]
                .iter_mut()
                .filter(|c| c.check == crate::filters::self_check::BOUNDARY_MASS_CHECK)
            {
                c.advice = "the density reaches the edge of the box: with the likelihood in the operator the implicit step damps −½hᵀS⁻¹h at the edge as (1 + |q|Δt)⁻¹ per step instead of e^(−|q|Δt), so the tails are too heavy; shrink Δt or use likelihood = in_update (widening the box makes |q| at its edge larger)";
            }
        }
    }

    fn step(&mut self, obs: &Observation) -> Result<(), FilterError> {
        let observed = obs.check(
            &self.name,
            ObservationKind::Increment,
            self.op.s_inv_h.len(),
        )?;
        if let Some(model) = &self.driven {
            let (dynamics, _) = obs.frozen(model)?.expect("a driven model");
            self.retabulate(&dynamics)?;
        }
        self.saved.save(&self.u, &self.estimate);
        let result = self.advance(obs, observed);
        let (u, estimate) = (&mut self.u, &mut self.estimate);
        self.saved
            .settle(result, u, estimate, &mut self.log_likelihood)
    }

    fn warnings(&self) -> Vec<String> {
        self.warnings.iter().map(|w| w.message.clone()).collect()
    }
}

#[cfg(all(test, feature = "std"))]
mod tests {
    use super::*;
    use crate::model::Noise;
    use crate::testing::test;

    /// A model with a strong drift f = 3 sin 2x and h = x on [−3, 3], its operator on `points`
    /// nodes, and the (22) warnings for `dt`.
    fn operator(points: usize, dt: f64) -> (TensorGrid, KolmogorovOperator, usize) {
        let model =
            Model::from_text(&["3*sin(2*x)"], &["x"], Noise::continuous(1.0)).expect("model");
        let grid = TensorGrid::new(&[(-3.0, 3.0)], &[points]).expect("grid");
        let op = KolmogorovOperator::new(&model, &grid, false).expect("operator");
        let warnings = guarantees::m_matrix(&op, &grid, dt).len();
        (grid, op, warnings)
    }

    /// The most negative value after 30 IEM steps from a single spike (every nonnegative
    /// vector is a sum of spikes).
    fn lowest_after_steps(points: usize, dt: f64) -> (f64, usize) {
        let (grid, op, warnings) = operator(points, dt);
        let iem = SplitIem::new(&op, &grid, dt, 1.0);
        let mut lowest = f64::INFINITY;
        for spike in [points / 3, points / 2] {
            let mut u = vec![0.0; grid.len()];
            u[spike] = 1.0;
            let mut tmp = vec![0.0; grid.len()];
            for _ in 0..30 {
                iem.step(&grid, &mut u, &mut tmp);
                lowest = u.iter().copied().fold(lowest, f64::min);
            }
        }
        (lowest, warnings)
    }

    /// 000 Theorem (22): when the M-matrix condition holds the implicit step maps nonnegative
    /// densities to nonnegative ones — exactly, in floating point, since the Thomas algorithm on
    /// an M-matrix only adds nonnegative terms. When it fails (Δs too coarse for the drift:
    /// |p|Δs/Q = 3 · 0.375 > 1) the same spike produces negative values, which shows the
    /// check is the one that matters.
    #[test]
    fn iem_is_nonnegative_exactly_when_22_holds() {
        let (lowest, warnings) = lowest_after_steps(201, 0.05);
        assert_eq!(warnings, 0);
        assert!(
            lowest >= 0.0,
            "negative value {lowest:e} although (22) holds"
        );
        let (lowest, warnings) = lowest_after_steps(15, 0.05);
        assert!(warnings > 0, "(22) should be violated on the coarse grid");
        assert!(lowest < 0.0, "expected a negative value, lowest {lowest:e}");
    }

    /// Every scheme's backward step is the transpose of its forward step, ⟨T a, b⟩ =
    /// ⟨a, Tᵀ b⟩ to rounding: IEM, QIEM and SPT in 1-D and 2-D, QIEM4 in 2-D, over Δτ, over
    /// an irregular 1.7 Δτ (whole intervals and a remainder), and with the likelihood in the
    /// operator for an increment with a component missing (the Fokker–Planck part alone).
    #[test]
    fn the_backward_step_is_the_transposed_forward_step() {
        use crate::filters::smoothing::GridTransition;
        use crate::model::GaussianMixture;
        let cases: [(&[&str], &[&str], Scheme, LikelihoodPlacement); 7] = [
            (
                &["-x^3 + x"],
                &["x", "x^2"],
                Scheme::Iem,
                LikelihoodPlacement::InUpdate,
            ),
            (
                &["-x^3 + x"],
                &["x", "x^2"],
                Scheme::Qiem,
                LikelihoodPlacement::InOperator,
            ),
            (
                &["-x^3 + x"],
                &["x", "x^2"],
                Scheme::Superposition,
                LikelihoodPlacement::InUpdate,
            ),
            (
                &["x2", "-sin(x1) - 0.5*x2"],
                &["x1", "x2"],
                Scheme::Iem,
                LikelihoodPlacement::InOperator,
            ),
            (
                &["x2", "-sin(x1) - 0.5*x2"],
                &["x1", "x2"],
                Scheme::Qiem,
                LikelihoodPlacement::InUpdate,
            ),
            (
                &["x2", "-sin(x1) - 0.5*x2"],
                &["x1", "x2"],
                Scheme::Qiem4,
                LikelihoodPlacement::InUpdate,
            ),
            (
                &["x2", "-sin(x1) - 0.5*x2"],
                &["x1", "x2"],
                Scheme::Superposition,
                LikelihoodPlacement::InOperator,
            ),
        ];
        for (drift, obs, scheme, likelihood) in cases {
            let n = drift.len();
            let model = Model::from_text(drift, obs, Noise::continuous(0.5)).expect("model");
            let prior = crate::model::Prior::Mixture(
                GaussianMixture::gaussian(DVector::zeros(n), nalgebra::DMatrix::identity(n, n))
                    .expect("prior"),
            );
            let params = YauYauParams {
                points: vec![if n == 1 { 41 } else { 17 }],
                dt: 0.004,
                likelihood,
                centres: vec![if n == 1 { 15 } else { 6 }],
                ..Default::default()
            };
            let bounds = vec![(-3.0, 3.0); n];
            let ctx = crate::filters::method::BuildContext {
                model: &model,
                prior: &prior,
                seed: 0,
                probes: &[],
                bounds: &bounds,
                dt_obs: Some(0.01),
                supplied: None,
            };
            let mut f = YauYauFilter::new("t".into(), scheme, &ctx, &params).expect("filter");
            let len = f.grid().len();
            let a: Vec<f64> = (0..len).map(|i| libm::sin(i as f64 * 0.37) + 1.1).collect();
            let b: Vec<f64> = (0..len).map(|i| libm::cos(i as f64 * 0.91)).collect();
            let partial = [0.01, f64::NAN];
            for (dt, value) in [
                (0.01, &[0.01, 0.02][..]),
                (0.017, &[0.01, 0.02][..]),
                (0.01, &partial[..]),
            ] {
                let o = Observation::increment(dt, value);
                let (mut ta, mut tb) = (a.clone(), b.clone());
                f.carry(&o, &mut ta).expect("forward");
                f.carry_back(&o, &mut tb).expect("backward");
                let left: f64 = ta.iter().zip(&b).map(|(x, y)| x * y).sum();
                let right: f64 = a.iter().zip(&tb).map(|(x, y)| x * y).sum();
                let scale: f64 = ta.iter().map(|v| v.abs()).sum::<f64>() + 1.0;
                assert!(
                    (left - right).abs() < 1e-11 * scale,
                    "{scheme:?} {likelihood:?} n = {n}, Δτ = {dt}, {value:?}: {left} vs {right}"
                );
            }
        }
    }
}
