// The playground's lessons (Learn mode): each a few paragraphs with equations ($…$ inline,
// $$…$$ displayed; rendered by Temml), a scenario and seed chosen so that the run shows what
// the text says (checked by tests/web/e2e.mjs), "try this" actions that change one parameter
// and replay, and what to look for. Papers are cited by authors and year; the reference list
// is at the end.
//
// A lesson's `scenario(preset, method)` returns the config to run from a preset (a deep copy)
// and `method(key, params)` (the catalogue's defaults with `params` over them). A "try this"
// action's `change(config, method)` edits the running config in place; `mc` runs the Monte
// Carlo panel instead.

const methodsOf = (method, list) => list.map(([key, params]) => method(key, params ?? {}));

export const LESSONS = [
  {
    id: 'zakai-equation',
    title: '1. The filtering problem and the Zakai equation',
    preset: 'cubic-sensor-1d',
    seed: 3,
    scenario: (c, method) => {
      c.methods = methodsOf(method, [['qiem', { points: [399], dt: 0.001 }]]);
      return c;
    },
    body: [
      'A signal $x(t)$ moves by a stochastic differential equation, and we see it only through noisy observations:',
      '$$dx = f(x)\\,dt + G\\,dv, \\qquad dy = h(x)\\,dt + dw, \\qquad \\mathbb E\\,dw\\,dw^\\top = S\\,dt,$$',
      'with $v$ and $w$ independent Brownian motions. Filtering asks what the observations $y(s)$, $s \\le t$, tell us about $x(t)$. The full answer is a probability density, the conditional density of $x(t)$; the best estimate in mean square is its mean.',
      'The unnormalised conditional density $\\sigma(t,x)$ solves the Duncan–Mortensen–Zakai equation (Zakai 1969), a linear stochastic partial differential equation:',
      '$$d\\sigma = \\mathcal L^*\\sigma\\,dt + \\sigma\\,h^\\top S^{-1}\\,dy,$$',
      '$$\\mathcal L^*\\sigma = \\tfrac12 \\sum_{i,j} \\partial_i \\partial_j \\big((GG^\\top)_{ij}\\,\\sigma\\big) - \\sum_i \\partial_i (f_i\\,\\sigma).$$',
      'The Fokker–Planck operator $\\mathcal L^*$ spreads the density between observations; the observation term reweights it. The estimate is $\\hat x(t) = \\int x\\,\\sigma(t,x)\\,dx \\big/ \\int \\sigma(t,x)\\,dx$.',
      'The Yau–Yau method splits time at the observation instants $\\tau_k$. On each interval a deterministic equation is solved, $\\partial_t u = \\big(\\mathcal L^* - \\tfrac12 h^\\top S^{-1} h\\big) u$, and at $\\tau_k$ the density is multiplied by the observation factor $\\exp\\!\\big(h^\\top S^{-1}\\,(y(\\tau_k) - y(\\tau_{k-1}))\\big)$. The equation on each interval does not involve the observations, so it can be prepared off-line; the observations enter only through the multiplication, and nothing is assumed Gaussian. Yueh, Lin & Yau (2014) give fast schemes for it (lesson 5).',
      'Here: the cubic sensor $f = 0$, $h = x^3$ (Shi, Chen & Yau 2021, Example 1), solved on a grid of 399 points by QIEM.',
    ],
    lookFor: [
      'The heat strip under the plot is $\\sigma(t,\\cdot)$ over time: bright where $x(t)$ is likely. Its width is the filter\'s uncertainty.',
      'Near $x = 0$ the observation $x^3$ is flat, so it says little: when the truth crosses 0 (at $t \\approx 1$) the strip widens and the estimate lags until $t \\approx 2$, then narrows again once $|x|$ is large.',
      'The current density (right) is not always a bell curve.',
    ],
    tryThis: [
      { label: 'observe 10× more accurately: S = 0.1', change: (c) => { c.model.noise = { kind: 'continuous', cov: [[0.1]] }; } },
      { label: 'observe linearly: h(x) = x', change: (c) => { c.model.observation = ['x']; } },
    ],
  },
  {
    id: 'kalman-bucy',
    title: '2. Kalman–Bucy: the linear case, solved exactly',
    preset: 'cubic-sensor-1d',
    seed: 1,
    scenario: (c, method) => {
      c.model.drift = ['-x'];
      c.model.observation = ['x'];
      c.methods = methodsOf(method, [['kalman'], ['ekf'], ['pf', { particles: 200 }], ['qiem', { points: [399], dt: 0.001 }]]);
      return c;
    },
    body: [
      'When the drift and the observation are linear, $f(x) = Ax$ and $h(x) = Hx$, and the prior is Gaussian, the conditional density stays Gaussian for ever. Its mean and covariance follow the Kalman–Bucy filter (Kalman & Bucy 1961):',
      '$$d\\hat x = A\\hat x\\,dt + P H^\\top S^{-1}\\big(dy - H\\hat x\\,dt\\big), \\qquad \\dot P = AP + PA^\\top + GG^\\top - P H^\\top S^{-1} H P.$$',
      'The gain $K = P H^\\top S^{-1}$ weighs the innovation $dy - H\\hat x\\,dt$ — the part of the observation the filter did not expect. Two ordinary differential equations replace the Zakai equation: this is the exact answer, at microseconds per step.',
      'Here $A = -1$, $H = 1$: an Ornstein–Uhlenbeck signal observed directly. The grid filter (QIEM) solves the Zakai equation without knowing the answer is Gaussian, so agreeing with the Kalman–Bucy filter is a test of the grid: they agree to about $10^{-3}$.',
    ],
    lookFor: [
      'KF, EKF and QIEM on top of each other in the main plot (the EKF is exact for a linear model); the particle filter jitters around them.',
      'In the densities panel every curve is the same bell curve.',
      'The table: the Kalman filter costs microseconds per step, the grid filter tens of microseconds, for the same answer.',
    ],
    tryThis: [
      { label: 'make the sensor cubic: h(x) = x³', change: (c) => { c.model.observation = ['x^3']; } },
      { label: 'a noisier signal: G = 2', change: (c) => { c.model.diffusion = [[2]]; } },
    ],
  },
  {
    id: 'cubic-sensor',
    title: '3. The cubic sensor: why the EKF\'s gain vanishes',
    preset: 'cubic-sensor-1d',
    seed: 3,
    scenario: (c, method) => {
      c.methods = methodsOf(method, [['ekf', { substeps: 4 }], ['ukf', { alpha: 0.05, beta: 2, kappa: 0, substeps: 4 }], ['pf', { particles: 200 }], ['qiem', { points: [399], dt: 0.001 }]]);
      return c;
    },
    body: [
      'The extended Kalman filter linearises $h$ at its own estimate and runs the Kalman–Bucy equations with $H = h\'(\\hat x)$. For the cubic sensor $h(x) = x^3$:',
      '$$K = P\\,h\'(\\hat x)\\,S^{-1} = 3\\hat x^2 P, \\qquad \\dot P = GG^\\top - \\big(3\\hat x^2\\big)^2 P^2 .$$',
      'When $\\hat x$ nears 0 the gain $3\\hat x^2 P$ vanishes: the EKF stops listening to the observations, keeps the sign it had, and its covariance grows only by $GG^\\top$ — it does not know it is lost. The unscented filter replaces the derivative by sigma points but keeps one Gaussian, and fails the same way. The true posterior near 0 is wide and skewed; the grid and particle filters carry it.',
      'A method is marked failed when its error stays above 1 for one time unit (the failure rule, under Time in Explore mode, where it can be changed), or when its numbers stop being finite. A method marked failed by the rule still has its Gaussian: the page draws it on, dashed, from a ✕ at its failure: with this seed the EKF stays near 0, where it was lost, to the end.',
    ],
    lookFor: [
      'The truth crosses 0 at $t \\approx 1$; the EKF and the UKF stay on the old side, and once their error has stayed above 1 for a time unit they are marked failed (at $t \\approx 2.3$–$2.5$), while QIEM and PF(200) follow.',
      'The innovation self-check of the EKF: its normalised innovations leave their χ² band — the filter is overconfident.',
    ],
    tryThis: [
      { label: 'another path: seed 1', change: (c) => { c.seed = 1; } },
      { label: 'more particles: PF(2000)', change: (c) => { for (const m of c.methods) if (m.method === 'pf') m.particles = 2000; } },
    ],
  },
  {
    id: 'particles-grids',
    title: '4. Particles against grids: accuracy against cost',
    preset: 'cubic-sensor-1d',
    seed: 3,
    scenario: (c, method) => {
      c.methods = methodsOf(method, [['pf', { particles: 50 }], ['pf', { particles: 500 }], ['pf', { particles: 5000 }], ['qiem', { points: [399], dt: 0.001 }]]);
      return c;
    },
    body: [
      'A particle filter carries $N$ samples $x_i$ with weights $w_i$ (Gordon, Salmond & Smith 1993): each interval moves every sample by the signal\'s own equation and reweights it by the likelihood of the new observation,',
      '$$w_i \\leftarrow w_i \\exp\\!\\Big(h(x_i)^\\top S^{-1} \\Delta y - \\tfrac12\\, h(x_i)^\\top S^{-1} h(x_i)\\, \\Delta\\tau\\Big), \\qquad \\hat x \\approx \\frac{\\sum_i w_i x_i}{\\sum_i w_i},$$',
      'then resamples when the weights collapse. Its error falls like $1/\\sqrt N$ in any dimension. A grid filter\'s error falls like $\\Delta s^2 + \\Delta t$, but its cost grows like $(1/\\Delta s)^n$ in $n$ dimensions. In one dimension the grid wins; the question in each problem is which reaches a given accuracy for less time.',
    ],
    lookFor: [
      'The table\'s time per step: PF(50) is cheapest, PF(5000) costs about as much as the grid filter.',
      'The error of one run is noisy; run the Monte Carlo panel to compare means over many runs (and see how the table takes them).',
    ],
    tryThis: [
      { label: 'Monte Carlo: 20 runs', mc: 20 },
      { label: 'a coarser grid: 51 points', change: (c) => { for (const m of c.methods) if (m.method === 'qiem') m.points = [51]; } },
    ],
  },
  {
    id: 'yau-yau-grid',
    title: '5. The Yau–Yau method on a grid and its stability conditions',
    preset: 'cubic-sensor-1d',
    seed: 3,
    scenario: (c, method) => {
      c.methods = methodsOf(method, [
        ['qiem', { points: [399], dt: 0.001 }],
        ['iem', { points: [399], dt: 0.001, likelihood: 'in_operator' }],
      ]);
      return c;
    },
    body: [
      'On a grid with spacing $\\Delta s$ and time step $\\Delta t$, Yueh, Lin & Yau (2014) propose two schemes for $\\partial_t u = \\tfrac12 \\Delta u - f\\cdot\\nabla u + q\\,u$ with $q = -\\nabla\\!\\cdot f - \\tfrac12 h^\\top S^{-1} h$. The implicit Euler scheme (IEM) treats everything implicitly; the quasi-implicit scheme (QIEM) keeps the Laplacian implicit, solved by a sine transform, and the rest explicit:',
      '$$\\Big(I - \\tfrac{\\Delta t}{2}\\,\\Delta_h\\Big)\\, u^{k+1} = u^k + \\Delta t\\,\\big(q\\,u^k - f\\cdot\\nabla_h u^k\\big).$$',
      'Their guarantees are conditions on the steps. IEM keeps the density nonnegative (an M-matrix) only if $|q(s)|\\,\\Delta t < 1$ at every node, condition (22). With the observation term inside $q$ (the row IEM here: $q = -\\tfrac12 x^6$) and the box $[-4, 4]$, $|q| = 2048$ at the edge, so $\\Delta t = 10^{-3}$ violates it and the page says so. Zakai\'s default moves $-\\tfrac12 h^2$ into the observation factor, where it is a bounded Gaussian likelihood, and the condition holds for any step.',
    ],
    lookFor: [
      'The warning above the plot: IEM\'s condition (22) is violated, with the grid point and the value (in Explore mode it also sits in the IEM row of the form).',
      'QIEM and IEM give nearly the same estimate here: both are consistent discretisations of the same equation.',
    ],
    tryThis: [
      { label: 'shrink IEM\'s step: Δt = 4·10⁻⁴', change: (c) => { for (const m of c.methods) if (m.method === 'iem') m.dt = 0.0004; } },
      { label: 'a coarse grid: 41 points for QIEM', change: (c) => { for (const m of c.methods) if (m.method === 'qiem') m.points = [41]; } },
    ],
  },
  {
    id: 'two-d',
    title: '6. A 2-D posterior and log-concavity',
    preset: 'yau-2d',
    seed: 1,
    scenario: (c) => c,
    body: [
      'In two dimensions the grid filter\'s density is an image: the heatmap shows the joint posterior of $(x_1, x_2)$ with the truth and every estimate marked. The example is Yueh, Lin & Yau (2014), (33): $f(x) = (-\\cos x_1 - \\sin x_2,\\ \\cos x_1 + \\sin x_2)$ observed through cubic sensors.',
      'Gaussian filters (EKF, UKF) and the MAP filters of Kang, Salmon & Yau (2023) work best when the posterior is log-concave, that is when',
      '$$-\\nabla^2 \\log p(x) \\succeq 0$$',
      'everywhere: then it has one mode and the MAP update is a convex problem. Where the Hessian of $-\\log p$ has a negative eigenvalue the density can bend into a banana or split into modes.',
    ],
    lookFor: [
      'The heatmap: the posterior is not an ellipse when the sensors are flat (near $x_i = 0$).',
      'Turn on the log-concavity layer: the region where $-\\nabla^2 \\log p$ is not positive semidefinite is marked.',
    ],
    tryThis: [
      { label: 'show the log-concavity layer', view: 'lc-layer' },
      { label: 'another path: seed 4', change: (c) => { c.seed = 4; } },
    ],
  },
  {
    id: 'spectral',
    title: '7. The spectral method: off-line and on-line',
    preset: 'cubic-sensor-1d',
    seed: 3,
    scenario: (c, method) => {
      c.methods = methodsOf(method, [['spectral', { offline_basis: 11, online_basis: 16 }], ['qiem', { points: [399], dt: 0.001 }]]);
      return c;
    },
    body: [
      'Shi, Chen & Yau (2021) expand the density in $N$ generalised Legendre functions on the box,',
      '$$\\sigma(t, x) \\approx \\sum_{k=0}^{N-1} c_k(t)\\, \\phi_k(x),$$',
      'and split the work. Off-line, before any observation, the Kolmogorov step is solved once for every basis function and stored as a matrix $A$: over one interval $c \\mapsto A c$. On-line, at each observation, the coefficients are multiplied by the observation factor and projected back onto the basis:',
      '$$c(\\tau_k) = \\Pi\\Big[\\exp\\!\\big(h\\,\\Delta y_k - \\tfrac12 h^2\\, \\Delta\\tau\\big)\\, \\textstyle\\sum_j (A\\,c(\\tau_{k-1}))_j\\, \\phi_j\\Big],$$',
      'a few small matrix products per step and no partial differential equation solved on-line. The price: the basis must resolve the posterior on the whole box. The filter checks the energy in its highest degrees after every step and warns when it exceeds $10^{-3}$.',
    ],
    lookFor: [
      'The table: the spectral filter\'s time per step against QIEM\'s.',
      'Its self-check: with 16 functions on $[-4, 4]$ the energy in the highest degrees exceeds the threshold while the posterior is narrow, and the row says so.',
    ],
    tryThis: [
      { label: 'a larger basis: 32 on-line functions', change: (c) => { for (const m of c.methods) if (m.method === 'spectral') { m.online_basis = 32; m.offline_basis = 24; } } },
      { label: 'a smaller basis: 8 functions', change: (c) => { for (const m of c.methods) if (m.method === 'spectral') { m.online_basis = 8; m.offline_basis = 8; } } },
    ],
  },
];

/** The papers Zakai implements, in full, and the classics the lessons cite. */
export const REFERENCES = [
  ['000', 'M.-H. Yueh, W.-W. Lin and S.-T. Yau, “An efficient algorithm of Yau–Yau method for solving nonlinear filtering problems”, Communications in Information and Systems 14(2), 2014.'],
  ['001', 'M. Šimandl and J. Švácha, “Separation approach for numerical solution of the Fokker–Planck equation in estimation problem”, Proceedings of the 16th IFAC World Congress, 2005.'],
  ['002', 'J. Shi, Z. Yang and S. S.-T. Yau, “Direct method for Yau filtering system with nonlinear observations”, International Journal of Control 91(3), 2018.'],
  ['003', 'J. Kang, A. Salmon and S. S.-T. Yau, “Log-concave posterior densities arising in continuous filtering and a maximum a posteriori algorithm”, SIAM Journal on Control and Optimization 61(4), 2023.'],
  ['004', 'J. Shi, X. Chen and S. S.-T. Yau, “A novel real-time filtering method to general nonlinear filtering problem without memory”, IEEE Access 9, 2021.'],
  ['', 'M. Zakai, “On the optimal filtering of diffusion processes”, Zeitschrift für Wahrscheinlichkeitstheorie und verwandte Gebiete 11, 1969.'],
  ['', 'R. E. Kalman and R. S. Bucy, “New results in linear filtering and prediction theory”, Journal of Basic Engineering 83, 1961.'],
  ['', 'N. J. Gordon, D. J. Salmond and A. F. M. Smith, “Novel approach to nonlinear/non-Gaussian Bayesian state estimation”, IEE Proceedings F 140(2), 1993.'],
];
