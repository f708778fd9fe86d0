//! Is a model a Yau filtering system in the sense of 002 §2? The three conditions of the
//! direct method, each reported with where it fails:
//!
//! * (C1) `f = l + ∇F` with l affine — by Theorem 2.1 (Yau 1994) the same as a constant curl
//!   `c_ij = ∂f_j/∂x_i − ∂f_i/∂x_j`. With a given `l(x) = Dx + d` the curl of `f − l` must
//!   vanish (`c_ij = D_ji − D_ij`); without one, l is inferred as `l(x) = Cx` with C the
//!   antisymmetric part of the Jacobian of f (constant when (C1) holds). In one dimension
//!   (C1) holds for every f (`F = ∫(f − l)`).
//! * (C2) `Σ h_i²` is a quadratic polynomial.
//! * (C3) `η = Σ f_i² + Σ ∂f_i/∂x_i + Σ h_i²` (7) is a quadratic polynomial.
//!
//! Each condition is decided symbolically when f and h are text expressions with normal forms
//! (`model::symbolic`: polynomials over x and sin, cos, tan, sinh, cosh, tanh, exp of
//! polynomials, with the Pythagorean and exponential identities): the curl's normal forms must
//! be the constants l needs, and Σh², η must normalise to polynomials of degree ≤ 2 — a
//! polynomial normal form of higher degree fails, exactly. So 002's example 4.3 (f = tanh x,
//! h = (x sin x, x cos x)) is proved to have Σh² = x² and η = 1 + x².
//!
//! Otherwise — a closure, a function without a normal form (erfc, sqrt, division by x, …), or
//! a normal form that keeps a function atom and so proves nothing — the condition is tested
//! numerically, on a tensor grid strictly inside the domain (101 points in 1-D, 21² in 2-D,
//! 11³ in 3-D, 7⁴ in 4-D; n ≥ 5 is not checked): the curl with the Jacobians the model
//! provides (exact for expressions within the symbolic budget, tolerance
//! `10⁻⁸(1 + max |∂f|)`; central differences otherwise, `10⁻⁵(1 + max |∂f|)`), and for (C2),
//! (C3) the least-squares quadratic — fitted by SVD in coordinates scaled to [−1, 1]ⁿ — must
//! reproduce every value to `10⁻⁶(1 + max |value|)`. That is not a proof: a function that
//! agrees with a quadratic to that tolerance at every test point passes (a bump narrower than
//! the test grid's spacing would go unseen). Each condition's detail says which way it was
//! decided.

use alloc::format;
use alloc::string::{String, ToString};
use alloc::vec;
use alloc::vec::Vec;
use core::fmt;

use nalgebra::{DMatrix, DVector};

use super::{fmt_point, interior_points, Condition, ConditionReport};
use crate::model::function::Derivatives;
use crate::model::symbolic::{self, Atom, Poly};
use crate::model::Model;

/// Largest state dimension the check runs for.
pub const MAX_DIMENSION: usize = 4;

/// Test points per dimension.
fn per_dimension(n: usize) -> usize {
    match n {
        1 => 101,
        2 => 21,
        3 => 11,
        _ => 7,
    }
}

/// `xᵀAx + bᵀx + c` with A symmetric.
#[derive(Clone, Debug, PartialEq)]
pub struct Quadratic {
    /// A (n × n, symmetric).
    pub a: DMatrix<f64>,
    /// b.
    pub b: DVector<f64>,
    /// c.
    pub c: f64,
}

impl Quadratic {
    /// The value at x.
    pub fn eval(&self, x: &[f64]) -> f64 {
        let x = DVector::from_column_slice(x);
        (x.transpose() * &self.a * &x)[0] + self.b.dot(&x) + self.c
    }
}

impl fmt::Display for Quadratic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.b.len() == 1 {
            return write!(
                f,
                "{:.6} x² {:+.6} x {:+.6}",
                self.a[(0, 0)],
                self.b[0],
                self.c
            );
        }
        write!(
            f,
            "xᵀAx + bᵀx + c with A = {}, b = {}, c = {:.6}",
            fmt_matrix(&self.a),
            fmt_point(self.b.as_slice()),
            self.c
        )
    }
}

/// The affine `l(x) = Dx + d` of (C1).
#[derive(Clone, Debug, PartialEq)]
pub struct Affine {
    /// D (n × n).
    pub d_mat: DMatrix<f64>,
    /// d.
    pub d_vec: DVector<f64>,
}

impl Affine {
    /// `l = 0`.
    pub fn zero(n: usize) -> Self {
        Affine {
            d_mat: DMatrix::zeros(n, n),
            d_vec: DVector::zeros(n),
        }
    }
}

/// The outcome of the check: the report, the l used (given or inferred) and, where (C2) and
/// (C3) hold, the quadratics.
#[derive(Clone, Debug, PartialEq)]
pub struct YauSystem {
    /// The three conditions.
    pub report: ConditionReport,
    /// l of (C1), as given or inferred.
    pub linear: Affine,
    /// `Σh²` when it is quadratic.
    pub sum_h2: Option<Quadratic>,
    /// η (7) when it is quadratic.
    pub eta: Option<Quadratic>,
}

impl YauSystem {
    /// The report as one error message naming every failing condition, or None when all hold.
    pub fn failure(&self) -> Option<String> {
        let failing: Vec<String> = self
            .report
            .conditions
            .iter()
            .filter(|c| !c.holds)
            .map(|c| format!("{} fails: {}", c.name, c.detail))
            .collect();
        (!failing.is_empty()).then(|| {
            format!(
                "not a Yau filtering system on the domain: {}",
                failing.join("; ")
            )
        })
    }
}

fn fmt_matrix(m: &DMatrix<f64>) -> String {
    let rows: Vec<String> = m
        .row_iter()
        .map(|r| {
            let v: Vec<f64> = r.iter().copied().collect();
            fmt_point(&v)
        })
        .collect();
    format!("[{}]", rows.join(", "))
}

/// Checks (C1)–(C3) for `model` on `bounds`, with l given or (None) inferred.
pub fn check(model: &Model, bounds: &[(f64, f64)], linear: Option<&Affine>) -> YauSystem {
    let n = model.n;
    let theorem = "Yau filtering system (002 (C1)–(C3))".to_string();
    // Not checked, with the reason: (C1)–(C3) as one failing condition.
    let unchecked = |detail: String| YauSystem {
        report: ConditionReport {
            theorem: theorem.clone(),
            conditions: vec![Condition {
                name: "(C1)–(C3)".into(),
                holds: false,
                detail,
            }],
            note: None,
        },
        linear: linear.cloned().unwrap_or_else(|| Affine::zero(n)),
        sum_h2: None,
        eta: None,
    };
    if model.is_discrete_time() {
        return unchecked(
            "a Yau filtering system is a model in continuous time (002 (1)); this model is a discrete-time map x_k = F(x_(k−1)) + w_k".into(),
        );
    }
    if n > MAX_DIMENSION || bounds.len() != n {
        return unchecked(format!(
            "checked for n ≤ {MAX_DIMENSION} on an n-dimensional domain; the model has n = {n} and the domain {} dimensions",
            bounds.len()
        ));
    }
    let per = per_dimension(n);
    let pts = interior_points(bounds, per);
    let t = Tabulated::new(model, &pts);
    let exact = model.drift.derivatives() == Derivatives::Exact;
    let given = linear.is_some();
    let forms = Forms::of(model);
    let (c1, linear) = curl_condition(&t, &pts, linear, exact, forms.jacobian.as_deref());
    let numbers = Numbers { pts: &pts, bounds };
    let (c2, sum_h2) = quadratic_condition(
        "(C2) Σh² is quadratic",
        "Σh²",
        forms.sum_h2.as_ref(),
        &t.sum_h2,
        &numbers,
    );
    let (c3, eta) = quadratic_condition(
        "(C3) η (7) is quadratic",
        "η",
        forms.eta.as_ref(),
        &t.eta,
        &numbers,
    );
    let note = format!(
        "l(x) = Dx + d with D = {}, d = {} ({}); symbolic: from the expressions' exact normal forms; numerical: tested at {per}^{n} points inside the domain",
        fmt_matrix(&linear.d_mat),
        fmt_point(linear.d_vec.as_slice()),
        if given {
            "given"
        } else {
            "inferred"
        }
    );
    YauSystem {
        report: ConditionReport {
            theorem,
            conditions: vec![c1, c2, c3],
            note: Some(note),
        },
        linear,
        sum_h2,
        eta,
    }
}

/// f's curl, Σh² and η at the test points.
struct Tabulated {
    /// The state dimension n.
    n: usize,
    /// `curl[p][i * n + j] = ∂f_j/∂x_i − ∂f_i/∂x_j` at point p.
    curl: Vec<Vec<f64>>,
    /// Largest |∂f_i/∂x_j| seen.
    scale: f64,
    sum_h2: Vec<f64>,
    eta: Vec<f64>,
}

impl Tabulated {
    fn new(model: &Model, pts: &[Vec<f64>]) -> Self {
        let (n, m) = (model.n, model.m);
        let (mut f, mut jac, mut h) = (vec![0.0; n], vec![0.0; n * n], vec![0.0; m]);
        let mut t = Tabulated {
            n,
            curl: Vec::with_capacity(pts.len()),
            scale: 0.0,
            sum_h2: Vec::with_capacity(pts.len()),
            eta: Vec::with_capacity(pts.len()),
        };
        for x in pts {
            model.drift.eval(x, &mut f);
            model.drift.jacobian(x, &mut jac);
            model.observation.eval(x, &mut h);
            let h2: f64 = h.iter().map(|v| v * v).sum();
            let divergence: f64 = (0..n).map(|i| jac[i * n + i]).sum();
            t.sum_h2.push(h2);
            t.eta
                .push(f.iter().map(|v| v * v).sum::<f64>() + divergence + h2);
            let mut curl = vec![0.0; n * n];
            for i in 0..n {
                for j in 0..n {
                    curl[i * n + j] = jac[j * n + i] - jac[i * n + j];
                }
            }
            t.curl.push(curl);
            t.scale = jac.iter().fold(t.scale, |a, v| a.max(v.abs()));
        }
        t
    }

    /// The antisymmetric part `½(J − Jᵀ) = −½ curl` of f's Jacobian, averaged over the points.
    fn mean_antisymmetric(&self) -> DMatrix<f64> {
        let n = self.n;
        let mut d = DMatrix::zeros(n, n);
        for curl in &self.curl {
            for i in 0..n {
                for j in 0..n {
                    d[(i, j)] -= 0.5 * curl[i * n + j];
                }
            }
        }
        d / self.curl.len().max(1) as f64
    }
}

/// f's Jacobian, Σh² and η in normal form, each when the expressions it needs have one (else
/// why not).
struct Forms {
    /// `jacobian[i * n + j] = ∂f_i/∂x_j`.
    jacobian: Result<Vec<Poly>, String>,
    sum_h2: Result<Poly, String>,
    eta: Result<Poly, String>,
}

impl Forms {
    fn of(model: &Model) -> Forms {
        let n = model.n;
        let read = |what: &str, texts: Option<&[String]>| -> Result<Vec<Poly>, String> {
            let texts = texts.ok_or_else(|| format!("{what} is not given as text"))?;
            texts
                .iter()
                .map(|t| symbolic::parse(t, n).map_err(|e| format!("{what} `{t}`: {e}")))
                .collect()
        };
        let f = read("f", model.drift.expressions());
        let jacobian = f.as_ref().map_err(Clone::clone).and_then(|f| {
            let mut jacobian = Vec::with_capacity(n * n);
            for fi in f {
                for j in 0..n {
                    jacobian.push(fi.derivative(j).map_err(|e| e.0)?);
                }
            }
            Ok(jacobian)
        });
        let sum_h2 = read("h", model.observation.expressions()).and_then(|h| {
            h.iter().try_fold(Poly::default(), |sum, hi| {
                sum.add(&hi.mul(hi).map_err(|e| e.0)?).map_err(|e| e.0)
            })
        });
        // η = Σ f_i² + Σ ∂f_i/∂x_i + Σh² (7).
        let eta = match (&f, &jacobian, &sum_h2) {
            (Ok(f), Ok(jacobian), Ok(sum_h2)) => {
                f.iter()
                    .enumerate()
                    .try_fold(sum_h2.clone(), |eta, (i, fi)| {
                        let square = fi.mul(fi).map_err(|e| e.0)?;
                        let eta = eta.add(&square).map_err(|e| e.0)?;
                        eta.add(&jacobian[i * n + i]).map_err(|e| e.0)
                    })
            }
            (Err(why), _, _) | (_, Err(why), _) | (_, _, Err(why)) => Err(why.clone()),
        };
        Forms {
            jacobian,
            sum_h2,
            eta,
        }
    }
}

/// What a normal form says about being a quadratic.
enum Shape {
    /// A polynomial of degree ≤ 2.
    Quadratic(Quadratic),
    /// A polynomial of higher degree (why).
    Not(String),
    /// It keeps a function atom (why).
    Undecided(String),
}

/// The shape of `p` (named `symbol` in messages) in n variables.
fn shape(p: &Poly, n: usize, symbol: &str) -> Shape {
    let shown = p.display(n);
    if !p.is_polynomial() {
        return Shape::Undecided(format!(
            "its normal form {symbol} = {shown} keeps a function"
        ));
    }
    let degree = p.degree();
    if degree > 2 {
        return Shape::Not(format!("{symbol} = {shown} has degree {degree}"));
    }
    let mut q = Quadratic {
        a: DMatrix::zeros(n, n),
        b: DVector::zeros(n),
        c: 0.0,
    };
    for (monomial, c) in p.terms() {
        let vars: Vec<usize> = monomial
            .iter()
            .flat_map(|(atom, k)| match atom {
                Atom::Var(i) => vec![*i; *k as usize],
                Atom::Apply(..) => Vec::new(),
            })
            .collect();
        match vars[..] {
            [] => q.c += c,
            [i] => q.b[i] += c,
            [i, j] if i == j => q.a[(i, i)] += c,
            [i, j] => {
                q.a[(i, j)] += 0.5 * c;
                q.a[(j, i)] += 0.5 * c;
            }
            _ => {}
        }
    }
    Shape::Quadratic(q)
}

/// `∂f_j/∂x_i − ∂f_i/∂x_j` with 1-based indices, as the reports write it.
fn curl_label(i: usize, j: usize) -> String {
    format!("∂f{}/∂x{} − ∂f{}/∂x{}", j + 1, i + 1, i + 1, j + 1)
}

/// (C1) from the curl's normal forms: `Ok` with the condition and l when they decide it,
/// `Err(why)` when a curl keeps a function atom.
fn symbolic_curl(
    name: &str,
    jacobian: &[Poly],
    n: usize,
    linear: Option<&Affine>,
) -> Result<(Condition, Affine), String> {
    let decided = |holds: bool, detail: String, l: Affine| {
        let condition = Condition {
            name: name.into(),
            holds,
            detail: format!("{detail} (symbolic)"),
        };
        Ok((condition, l))
    };
    // curl[i][j] = ∂f_j/∂x_i − ∂f_i/∂x_j for i < j.
    let mut constants = DMatrix::zeros(n, n);
    let mut undecided = None;
    for i in 0..n {
        for j in (i + 1)..n {
            let curl = jacobian[j * n + i]
                .add(&jacobian[i * n + j].scale(-1.0))
                .map_err(|e| e.0)?;
            let label = curl_label(i, j);
            match curl.as_constant() {
                Some(c) => constants[(i, j)] = c,
                None if curl.is_polynomial() => {
                    let l = linear.cloned().unwrap_or_else(|| Affine::zero(n));
                    let detail = format!("{label} = {}, not constant", curl.display(n));
                    return decided(false, detail, l);
                }
                None => {
                    undecided.get_or_insert(format!(
                        "the normal form {label} = {} keeps a function",
                        curl.display(n)
                    ));
                }
            }
        }
    }
    if let Some(why) = undecided {
        return Err(why);
    }
    // D_ij = ½(∂f_i/∂x_j − ∂f_j/∂x_i) = −½ curl[i][j].
    let inferred = Affine {
        d_mat: DMatrix::from_fn(n, n, |i, j| 0.5 * (constants[(j, i)] - constants[(i, j)])),
        d_vec: DVector::zeros(n),
    };
    let l = linear.cloned().unwrap_or(inferred);
    for i in 0..n {
        for j in (i + 1)..n {
            let wanted = l.d_mat[(j, i)] - l.d_mat[(i, j)];
            let found = constants[(i, j)];
            if (found - wanted).abs() > 1e-12 * (1.0 + wanted.abs()) {
                let detail = format!("{} = {found}, but l needs {wanted}", curl_label(i, j));
                return decided(false, detail, l);
            }
        }
    }
    decided(true, "the curl is constant; f − l is a gradient".into(), l)
}

/// (C1): the curl of f must be that of l everywhere.
fn curl_condition(
    t: &Tabulated,
    pts: &[Vec<f64>],
    linear: Option<&Affine>,
    exact: bool,
    jacobian: Result<&[Poly], &String>,
) -> (Condition, Affine) {
    let n = t.n;
    let name = "(C1) f = l + ∇F with l affine (Theorem 2.1: constant curl ∂f_j/∂x_i − ∂f_i/∂x_j)";
    let why = match jacobian {
        _ if n == 1 => String::new(),
        Ok(jacobian) => match symbolic_curl(name, jacobian, n, linear) {
            Ok(decided) => return decided,
            Err(why) => why,
        },
        Err(why) => why.clone(),
    };
    let numerical = format!(" (numerical: {why})");
    let l = linear.cloned().unwrap_or_else(|| Affine {
        d_mat: t.mean_antisymmetric(),
        d_vec: DVector::zeros(n),
    });
    let finite = t.curl.iter().flatten().all(|v| v.is_finite()) && t.scale.is_finite();
    if !finite {
        return (
            Condition {
                name: name.into(),
                holds: false,
                detail: "f or its Jacobian is not finite on the domain; shrink it".into(),
            },
            l,
        );
    }
    let tolerance = if exact { 1e-8 } else { 1e-5 } * (1.0 + t.scale);
    // (p, i, j, found, wanted)
    let mut worst = (0.0f64, 0usize, 0usize, 0usize, 0.0, 0.0);
    for (p, curl) in t.curl.iter().enumerate() {
        for i in 0..n {
            for j in (i + 1)..n {
                let wanted = l.d_mat[(j, i)] - l.d_mat[(i, j)];
                let off = (curl[i * n + j] - wanted).abs();
                if off > worst.0 {
                    worst = (off, p, i, j, curl[i * n + j], wanted);
                }
            }
        }
    }
    let holds = worst.0 <= tolerance;
    let detail = if n == 1 {
        "holds for every f in one dimension (F = ∫(f − l))".to_string()
    } else if holds {
        format!(
            "the curl is constant to {:.1e}; f − l is a gradient{numerical}",
            worst.0
        )
    } else {
        let (_, p, i, j, found, wanted) = worst;
        format!(
            "{} = {found:.6} at x = {}, but l needs {wanted:.6} everywhere{numerical}",
            curl_label(i, j),
            fmt_point(&pts[p])
        )
    };
    (
        Condition {
            name: name.into(),
            holds,
            detail,
        },
        l,
    )
}

/// The test points and the domain, for the numerical tests.
struct Numbers<'a> {
    pts: &'a [Vec<f64>],
    bounds: &'a [(f64, f64)],
}

/// (C2)/(C3): the function named `symbol` must be a quadratic polynomial — decided by its
/// normal form when that has no function atom, else tested on its `values` at the points.
fn quadratic_condition(
    name: &str,
    symbol: &str,
    form: Result<&Poly, &String>,
    values: &[f64],
    numbers: &Numbers,
) -> (Condition, Option<Quadratic>) {
    let (pts, bounds) = (numbers.pts, numbers.bounds);
    let condition = |holds: bool, detail: String| Condition {
        name: name.into(),
        holds,
        detail,
    };
    let why = match form.map(|p| (p, shape(p, bounds.len(), symbol))) {
        Ok((p, Shape::Quadratic(q))) => {
            let detail = format!("{symbol} = {} (symbolic)", p.display(bounds.len()));
            return (condition(true, detail), Some(q));
        }
        Ok((_, Shape::Not(detail))) => {
            return (condition(false, format!("{detail} (symbolic)")), None)
        }
        Ok((_, Shape::Undecided(why))) => why,
        Err(why) => why.clone(),
    };
    let numerical = format!(" (numerical: {why})");
    let fail = |detail: String| (condition(false, detail + &numerical), None);
    if let Some(p) = values.iter().position(|v| !v.is_finite()) {
        return fail(format!(
            "not finite at x = {}; shrink the domain",
            fmt_point(&pts[p])
        ));
    }
    let Some((quadratic, worst, at)) = fit_quadratic(values, pts, bounds) else {
        return fail("the least-squares fit failed".into());
    };
    let scale = 1.0 + values.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    if worst > 1e-6 * scale {
        return fail(format!(
            "the best quadratic misses by {worst:.3e} at x = {} (values up to {:.3e})",
            fmt_point(&pts[at]),
            scale - 1.0
        ));
    }
    let detail = format!("{symbol} = {quadratic}{numerical}");
    (condition(true, detail), Some(quadratic))
}

/// The least-squares quadratic through `(pts, values)`, fitted in `ξ = (x − centre)/half-width`
/// and returned in x, with the largest miss and where.
fn fit_quadratic(
    values: &[f64],
    pts: &[Vec<f64>],
    bounds: &[(f64, f64)],
) -> Option<(Quadratic, f64, usize)> {
    let n = bounds.len();
    let centre: Vec<f64> = bounds.iter().map(|b| 0.5 * (b.0 + b.1)).collect();
    let half: Vec<f64> = bounds.iter().map(|b| 0.5 * (b.1 - b.0)).collect();
    // Monomials 1, ξ_i, ξ_i ξ_j (i ≤ j).
    let mut pairs = Vec::new();
    for i in 0..n {
        for j in i..n {
            pairs.push((i, j));
        }
    }
    let cols = 1 + n + pairs.len();
    let xi = |x: &[f64], d: usize| (x[d] - centre[d]) / half[d];
    let row = |x: &[f64]| -> Vec<f64> {
        let mut r = Vec::with_capacity(cols);
        r.push(1.0);
        r.extend((0..n).map(|d| xi(x, d)));
        r.extend(pairs.iter().map(|&(i, j)| xi(x, i) * xi(x, j)));
        r
    };
    let rows: Vec<f64> = pts.iter().flat_map(|x| row(x)).collect();
    let design = DMatrix::from_row_slice(pts.len(), cols, &rows);
    let rhs = DVector::from_column_slice(values);
    // Least squares by Householder QR, not nalgebra's `svd(true, true)`, which can return
    // wrong singular values (dimforge/nalgebra#1172); points that do not determine a
    // quadratic (fewer than its coefficients, or a rank-deficient design) give no fit.
    if pts.len() < cols {
        return None;
    }
    let qr = design.clone().qr();
    let r = qr.r();
    let largest = r.diagonal().amax();
    if r.diagonal().iter().any(|v| v.abs() <= 1e-12 * largest) {
        return None;
    }
    let coef = r.solve_upper_triangular(&(qr.q().transpose() * &rhs))?;
    let residual = &design * &coef - &rhs;
    let (at, worst) = residual
        .iter()
        .enumerate()
        .fold(
            (0, 0.0f64),
            |(k, w), (p, r)| {
                if r.abs() > w {
                    (p, r.abs())
                } else {
                    (k, w)
                }
            },
        );
    // Back to x: ξ = W⁻¹(x − c) gives A = W⁻¹A_ξW⁻¹, b = W⁻¹b_ξ − 2Ac,
    // c₀ = c_ξ + cᵀAc − b_ξᵀW⁻¹c.
    let mut a = DMatrix::zeros(n, n);
    for (k, &(i, j)) in pairs.iter().enumerate() {
        let v = coef[1 + n + k] / (half[i] * half[j]);
        if i == j {
            a[(i, i)] = v;
        } else {
            a[(i, j)] = 0.5 * v;
            a[(j, i)] = 0.5 * v;
        }
    }
    let c = DVector::from_column_slice(&centre);
    let b_xi = DVector::from_fn(n, |d, _| coef[1 + d] / half[d]);
    let ac = &a * &c;
    let b = &b_xi - &ac * 2.0;
    let c0 = coef[0] + c.dot(&ac) - b_xi.dot(&c);
    Some((Quadratic { a, b, c: c0 }, worst, at))
}
