// The playground's lessons (Learn mode): each a few paragraphs with equations ($…$ inline,
// $$…$$ displayed; rendered by Temml), a scenario and seed chosen so that the run shows what
// the text says (checked by tests/web/e2e.mjs), "try this" actions that change one parameter
// and replay, and what to look for. Papers are cited by authors and year; the reference list
// is at the end.
//
// A lesson's `scenario(preset, method)` returns the config to run from a preset (a deep copy)
// and `method(key, params)` (the catalogue's defaults with `params` over them). The failure
// rule's track-loss test is off unless the lesson is about it (`trackLoss: true`). A "try
// this" action's `change(config, method)` edits the running config in place; `mc` runs the
// Monte Carlo panel, `check` the convergence check, `likelihood` the Likelihood view and
// `posterior` the Posterior view's sampler instead, `view` turns on a view; its
// `expect` says what the changed run shows (asserted by tests/web/lessons.mjs). `opens` lists
// the panels (<details> ids) the lesson's text refers to, opened with the lesson; `speed` the
// observation intervals played per frame (5 unless given), one kept density per frame.

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
      '$$\\begin{gathered}dx = f(x)\\,dt + G\\,dv, \\\\ dy = h(x)\\,dt + dw, \\\\ \\mathbb E\\,dw\\,dw^\\top = S\\,dt,\\end{gathered}$$',
      'with $v$ and $w$ independent Brownian motions. Filtering asks what the observations $y(s)$, $s \\le t$, tell us about $x(t)$. The full answer is a probability density, the conditional density of $x(t)$; the best estimate in mean square is its mean.',
      'The unnormalised conditional density $\\sigma(t,x)$ solves the Duncan–Mortensen–Zakai equation (Zakai 1969), a linear stochastic partial differential equation:',
      '$$d\\sigma = \\mathcal L^*\\sigma\\,dt + \\sigma\\,h^\\top S^{-1}\\,dy,$$',
      '$$\\mathcal L^*\\sigma = \\tfrac12 \\sum_{i,j} \\partial_i \\partial_j \\big((GG^\\top)_{ij}\\,\\sigma\\big) - \\sum_i \\partial_i (f_i\\,\\sigma).$$',
      'The Fokker–Planck operator $\\mathcal L^*$ spreads the density between observations; the observation term reweights it. The estimate is $\\hat x(t) = \\int x\\,\\sigma(t,x)\\,dx \\big/ \\int \\sigma(t,x)\\,dx$.',
      'The Yau–Yau method splits time at the observation instants $\\tau_k$. On each interval a deterministic equation is solved, $\\partial_t u = \\big(\\mathcal L^* - \\tfrac12 h^\\top S^{-1} h\\big) u$ (the Kolmogorov equation (2)–(4) of Yueh, Lin & Yau 2014, written there for $G = S = I$), and at each $\\tau_k$ the density is multiplied by the observation factor $\\exp\\!\\big(h^\\top S^{-1}\\,(y(\\tau_k) - y(\\tau_{k-1}))\\big)$. The equation on each interval does not involve the observations, so it can be prepared off-line; the observations enter only through the multiplication, and nothing is assumed Gaussian. Yueh, Lin & Yau (2014) give fast schemes for it (lesson 5).',
      'Here: the cubic sensor $f = 0$, $G = S = 1$, $h = x^3$ (Shi, Chen & Yau 2021, Example 1), solved on a grid of 399 points by QIEM.',
    ],
    lookFor: [
      'The heat strip under the plot is $\\sigma(t,\\cdot)$ over time: bright where $x(t)$ is likely. Its width is the filter\'s uncertainty.',
      'Near $x = 0$ the observation $x^3$ is flat, so it says little. The truth crosses 0 at $t \\approx 1.1$; the strip widens (the posterior standard deviation grows from 0.32 at the start to about 0.9 at $t \\approx 1.9$), and from $t = 1.5$ to $1.85$ the estimate stays within 0.35 of 0 while the truth is already below $-1$; only then does it follow the truth down. Once $|x|$ is large the strip narrows again (standard deviation about 0.25 around $t = 3$).',
    ],
    tryThis: [
      {
        label: 'less observation noise: S = 0.1',
        change: (c) => { c.model.noise = { kind: 'continuous', cov: [[0.1]] }; },
        expect: 'a tenth of the noise variance is a third of its standard deviation ($1/\\sqrt{10}$): the strip is narrower all along (mean posterior standard deviation about 0.29 against 0.47).',
      },
      {
        label: 'observe linearly: h(x) = x',
        change: (c) => { c.model.observation = ['x']; },
        expect: 'the strip no longer swells where the truth crosses 0, but it stays wide everywhere: with $f = 0$ and $h = x$ the posterior is Gaussian with the Kalman–Bucy variance (lesson 2), which tends to $P_\\infty = G\\sqrt S = 1$; the grid\'s standard deviation stays between 0.85 and 1 after $t = 1$ (a little below 1 where the box $[-4, 4]$ cuts the tail). Away from 0 the cubic sensor, with slope $3x^2 = 12$ at $|x| = 2$, said far more than a sensor of slope 1.',
      },
    ],
  },
  {
    id: 'kalman-bucy',
    // Its text points to the timing table and notes in this panel: opened with the lesson.
    opens: ['diagnostics-panel'],
    title: '2. Kalman–Bucy: the linear case, solved exactly',
    preset: 'cubic-sensor-1d',
    seed: 1,
    scenario: (c, method) => {
      c.model.drift = ['-x'];
      c.model.observation = ['x'];
      c.model.noise = { kind: 'continuous', cov: [[0.01]] };
      c.methods = methodsOf(method, [['kalman'], ['ekf'], ['pf', { particles: 200 }], ['qiem', { points: [399], dt: 0.001 }]]);
      return c;
    },
    body: [
      'When the drift and the observation are linear, $f(x) = Ax$ and $h(x) = Hx$, and the prior is Gaussian, the conditional density stays Gaussian for ever. Its mean and covariance follow the Kalman–Bucy filter (Kalman & Bucy 1961):',
      '$$d\\hat x = A\\hat x\\,dt + P H^\\top S^{-1}\\big(dy - H\\hat x\\,dt\\big),$$',
      '$$\\dot P = AP + PA^\\top + GG^\\top - P H^\\top S^{-1} H P.$$',
      'The gain $K = P H^\\top S^{-1}$ weighs the innovation $dy - H\\hat x\\,dt$ — the part of the observation the filter did not expect. The mean follows a stochastic differential equation driven by the observations; the covariance follows a Riccati equation, an ordinary differential equation that does not involve them, so $P$ can be computed before any observation arrives. Together they replace the Zakai equation. This program\'s Kalman filter (KF) is the discrete Kalman filter of the sampled model: an exact prediction over each interval $\\Delta\\tau$, then a Bayes update with $\\Delta y \\sim N(H x\\,\\Delta\\tau,\\ S\\,\\Delta\\tau)$ (the observation integral $\\int h\\,dt$ approximated by $H x\\,\\Delta\\tau$). It converges to the Kalman–Bucy filter as $\\Delta\\tau \\to 0$, its variance after each update sitting $O(\\Delta\\tau)$ below $P_\\infty$, with a handful of arithmetic operations per step.',
      'Here $A = -1$, $G = 1$, $H = 1$ and $S = 0.01$: an Ornstein–Uhlenbeck signal, whose own variance settles at $G^2/(2|A|) = 0.5$, seen through an accurate sensor. Setting $\\dot P = 0$ gives $P_\\infty = S\\big(\\sqrt{1 + G^2/S} - 1\\big) \\approx 0.090$: a posterior standard deviation of 0.30 against the signal\'s 0.71, so the estimate tracks the signal. (Updating once every $\\Delta\\tau = 0.01$, the KF settles a little lower, at 0.29.)',
      'The grid filter (QIEM) solves the Zakai equation without knowing that the answer is Gaussian, so agreeing with the Kalman–Bucy filter is a test of the grid: on this run they agree to within $5\\cdot 10^{-3}$.',
    ],
    lookFor: [
      'KF, EKF and QIEM on top of each other in the main plot (the EKF is the Kalman–Bucy filter when the model is linear); the particle filter jitters around them.',
      'In the densities panel every curve is the same bell curve; the KF\'s standard deviation settles at 0.29, near $\\sqrt{P_\\infty} = 0.30$.',
      'The work per interval: the KF updates one mean and one variance, about a dozen arithmetic operations; QIEM takes $\\Delta\\tau/\\Delta t = 10$ steps, each transforming its 399 grid values to sines and back ($O(N\\log N)$: of order $2 \\times 399 \\times \\log_2 399 \\approx 7000$ operations a step) — thousands of times the KF\'s arithmetic, for the same answer. (Measured times per step are in Diagnostics for researchers. At these small sizes they differ by far less than the operation counts, because every step also pays a fixed cost — the driver, the estimate, the copies — that is the same for every method, and one run\'s times move with whatever else the computer is doing: the KF can come out slower than the particle filter on a single run. The operation counts, and the benchmarks, are the comparison to trust.)',
    ],
    tryThis: [
      {
        label: 'a less accurate sensor: S = 1',
        change: (c) => { c.model.noise = { kind: 'continuous', cov: [[1]] }; },
        expect: '$P_\\infty = \\sqrt 2 - 1 \\approx 0.41$ (standard deviation 0.64, near the signal\'s own 0.71): the estimate now follows the signal only loosely. The sensor is still linear, so the filter is still exact.',
      },
      {
        label: 'a noisier signal: G = 2',
        change: (c) => { c.model.diffusion = [[2]]; },
        expect: '$P_\\infty = 0.01(\\sqrt{401} - 1) \\approx 0.19$ (standard deviation 0.44; the KF, updating once per interval, settles at 0.42) while the signal\'s own variance grows to 2; KF, EKF and QIEM still agree.',
      },
    ],
  },
  {
    id: 'cubic-sensor',
    title: '3. The cubic sensor: why the EKF\'s gain vanishes',
    preset: 'cubic-sensor-1d',
    seed: 3,
    trackLoss: true,
    opens: ['diagnostics-panel'],
    scenario: (c, method) => {
      c.methods = methodsOf(method, [['ekf', { substeps: 4 }], ['ukf', { alpha: 0.05, beta: 2, kappa: 0, substeps: 4 }], ['pf', { particles: 200 }], ['qiem', { points: [399], dt: 0.001 }]]);
      return c;
    },
    body: [
      'The extended Kalman filter linearises $h$ at its own estimate and runs the Kalman–Bucy equations with $H = h\'(\\hat x)$. For the cubic sensor $h(x) = x^3$, with $f = 0$:',
      '$$\\begin{gathered}K = P\\,h\'(\\hat x)\\,S^{-1} = \\frac{3\\hat x^2 P}{S}, \\\\ \\dot P = GG^\\top - \\frac{\\big(3\\hat x^2\\big)^2 P^2}{S}\\end{gathered}$$',
      '(here $G = S = 1$). When $\\hat x$ nears 0 the gain vanishes: the EKF stops listening to the observations, keeps the sign it had, and its covariance grows only by $GG^\\top$ — it does not know it is lost. The true posterior near 0 is wide; the grid and particle filters carry it.',
      'The unscented filter (Julier & Uhlmann 2004), in its scaled form, evaluates $h$ at sigma points $\\hat x \\pm \\sqrt{(n + \\lambda) P}$ with $\\lambda = \\alpha^2 (n + \\kappa) - n$; in one dimension with $\\kappa = 0$ that is $\\hat x \\pm \\alpha \\sqrt P$. With $\\alpha = 0.05$, the setting of Shi, Chen & Yau (2021)\'s Example 1 (results in their Table 1), the points sit so close to $\\hat x$ that the UKF sees the same flat slope as the EKF, and on this path it is lost the same way.',
      'A method is marked failed when its error stays above 1 for one time unit (the failure rule, under Time in Explore mode, where it can be changed), or when its numbers stop being finite. A method marked failed by the rule still has its Gaussian: the page draws it on, dashed, from a ✕ at its failure: with this seed the EKF stays near 0, where it was lost, to the end.',
    ],
    lookFor: [
      'The truth crosses 0 at $t \\approx 1.1$; the EKF and the UKF stay on the old side, and once their error has stayed above 1 for a time unit they are marked failed (at $t \\approx 2.3$–$2.5$), while QIEM and PF(200) follow.',
      'The EKF\'s own self-checks stay quiet (the diagnostics list nothing for it): over an interval of 0.01 its innovations $dy - \\hat x^3 dt$ are mostly observation noise, so nothing in them tells the EKF it is lost. Only the truth, which real data does not have, or a filter that carries the whole density shows it.',
    ],
    tryThis: [
      {
        label: 'wider sigma points: UKF with α = 1',
        change: (c) => { for (const m of c.methods) if (m.method === 'ukf') m.alpha = 1; },
        expect: 'the sigma points spread to $\\hat x \\pm \\sqrt P$ and see the curve of $x^3$: on this path the UKF follows the truth across 0 and is not marked failed.',
      },
      {
        label: 'another path: seed 1',
        change: (c) => { c.seed = 1; },
        expect: 'the EKF is lost again (marked failed at $t \\approx 1.4$); the UKF with α = 0.05 is not marked failed this time — but on this path QIEM, the exact filter up to its grid, is also more than 1 from the truth for most of $[0.4, 1.4]$, so the UKF escapes the rule by luck, not by accuracy: the failure rule measures the error against the truth, not against the best any filter could do. One path proves little: the Monte Carlo panel says how often each fails.',
      },
    ],
  },
  {
    id: 'particles-grids',
    title: '4. Particles against grids: accuracy against cost',
    preset: 'cubic-sensor-1d',
    seed: 3,
    opens: ['diagnostics-panel'],
    scenario: (c, method) => {
      c.methods = methodsOf(method, [['pf', { particles: 50 }], ['pf', { particles: 500 }], ['pf', { particles: 5000 }], ['qiem', { points: [399], dt: 0.001 }]]);
      return c;
    },
    body: [
      'A particle filter carries $N$ samples $x_i$ with weights $w_i$ (Gordon, Salmond & Smith 1993): each interval moves every sample by the signal\'s own equation and reweights it by the likelihood of the new observation,',
      '$$\\begin{gathered}w_i \\leftarrow w_i \\exp\\!\\Big(h(x_i)^\\top S^{-1} \\Delta y - \\tfrac12\\, h(x_i)^\\top S^{-1} h(x_i)\\, \\Delta\\tau\\Big), \\\\ \\hat x \\approx \\frac{\\sum_i w_i x_i}{\\sum_i w_i},\\end{gathered}$$',
      'then resamples — at every step in Gordon, Salmond & Smith\'s bootstrap filter; here only when the effective sample size falls below half of $N$. The Monte Carlo error of its estimate of the conditional mean falls like $1/\\sqrt N$, at a rate that does not depend on the dimension (its constant does). A grid filter\'s schemes have local truncation error $O(\\Delta t + \\Delta s^2)$ (Yueh, Lin & Yau 2014, Theorem 2) and converge under their stability conditions (30)/(31) (Theorems 3–5), but their cost grows like $(1/\\Delta s)^n$ in $n$ dimensions.',
      'Which filter is more accurate cannot be read off the error against the truth: all four here are close to the optimal filter, and the optimal estimate\'s own distance to the truth (the posterior\'s spread, a standard deviation of about 0.5) dwarfs their differences. What ranks them is the distance to the exact conditional mean. None is known here, so the convergence check estimates it: it reruns each method at doubled resolution on the same observations and measures how far the estimate moves.',
    ],
    lookFor: [
      'The work per interval: the particle filter moves and weighs each particle once (here $f = 0$, so one Euler step suffices), so its work grows in proportion to $N$ — PF(5000) does a hundred times PF(50)\'s arithmetic. QIEM\'s is fixed by its grid: 10 steps, each a sine transform of 399 values and back, of order $7 \\cdot 10^4$ operations per interval in all. (Measured times per step are in Diagnostics for researchers. They grow more slowly than the operation counts, because every step also pays a fixed cost — the driver, the estimate, the copies — that is the same for every method, and at these sizes one run\'s times are as much the computer\'s other work as the method\'s: PF(50) can come out slower than PF(500) on a single run. The operation counts, and the benchmarks, are the comparison to trust.)',
      'The four estimates are hard to tell apart by their MSE on one run; the Monte Carlo and the convergence check below tell them apart, or show that they cannot.',
    ],
    tryThis: [
      {
        label: 'Monte Carlo: 20 runs',
        mc: 20,
        expect: 'over 20 runs the four mean MSEs lie within about one standard error of each other (all near 0.31, with standard errors near 0.05): the error against the truth cannot rank filters that are all near the optimum. The table\'s “paper” column is Table 1 of Shi, Chen & Yau (2021) for the same problem: its PF(50) had an MSE of 1.31, four times ours; 004 does not describe its particle filter, so where the difference comes from cannot be said (the reproduction notes, docs/reproduction.md, compare every row).',
      },
      {
        label: 'check convergence',
        check: true,
        expect: 'doubling the particles moves PF(50)\'s estimate by about 0.12 (RMS over time, a quarter of the posterior standard deviation): not converged. Doubling QIEM\'s grid and halving its step moves it by about $10^{-4}$: converged. That, not the MSE, says the grid filter is the more accurate here.',
      },
    ],
  },
  {
    id: 'yau-yau-grid',
    title: '5. The Yau–Yau method on a grid: nonnegativity and accuracy',
    preset: 'cubic-sensor-1d',
    seed: 3,
    opens: ['diagnostics-panel'],
    scenario: (c, method) => {
      c.methods = methodsOf(method, [
        ['qiem', { points: [399], dt: 0.001 }],
        ['iem', { points: [399], dt: 0.001, likelihood: 'in_operator' }],
      ]);
      return c;
    },
    body: [
      'On a grid with spacing $\\Delta s$ and time step $\\Delta t$, Yueh, Lin & Yau (2014) solve the Kolmogorov equation (2), $\\partial_t u = \\tfrac12 \\Delta u - f\\cdot\\nabla u + q\\,u$ with $q = -\\nabla\\!\\cdot f - \\tfrac12 h^\\top S^{-1} h$ (their (3)–(4), with $S = I$). The implicit Euler scheme IEM (14) treats the whole operator implicitly; the quasi-implicit scheme QIEM (18) keeps only the Laplacian implicit, solved by a sine transform, and the rest explicit:',
      '$$\\Big(I - \\tfrac{\\Delta t}{2}\\,\\Delta_h\\Big)\\, u^{k+1} = u^k + \\Delta t\\,\\big(q\\,u^k - f\\cdot\\nabla_h u^k\\big).$$',
      'Write $\\mathbb A$ for the grid\'s matrix of the whole operator $\\tfrac12 \\Delta - f\\cdot\\nabla + q$ and $p_d = -f_d$ for the drift\'s coefficient of $\\partial_d u$ (their (3)). Their Theorem 1 guarantees that IEM keeps the density nonnegative — its matrix $I - \\Delta t\\,\\mathbb A$ is an M-matrix — when condition (22), $|p_d|\\,\\Delta s < 1$ and $|q|\\,\\Delta t < 1$, holds at every node. The proof uses the second half only as $1 - \\Delta t\\, q > 0$ (the row sums (24)), so a negative $q$ never breaks it. In the IEM row here the observation term is inside the operator: $f = 0$ and $q = -\\tfrac12 x^6 \\le 0$, so IEM is nonnegative for every $\\Delta t$. The program checks the condition as the proof uses it, and has no warning here.',
      'What the time step costs here is accuracy. Each implicit step multiplies by $(1 - q\\,\\Delta t)^{-1}$ where the equation multiplies by $e^{q\\,\\Delta t}$. Near the box\'s edge ($x = \\pm 4$) $q \\approx -2000$, so the ten steps of one interval $\\Delta\\tau = 0.01$ damp by about $(1 + 2)^{-10} \\approx 2\\cdot 10^{-5}$ instead of $e^{-20} \\approx 2\\cdot 10^{-9}$: the tails stay far too heavy. Zakai\'s default, which the QIEM row uses, takes $-\\tfrac12 h^\\top S^{-1} h$ out of the operator and applies it at each observation as part of the factor $\\exp\\!\\big(h^\\top S^{-1}\\Delta y - \\tfrac12 h^\\top S^{-1} h\\,\\Delta\\tau\\big)$, integrating that term exactly over each interval, at the cost of a splitting error that vanishes as $\\Delta\\tau \\to 0$.',
    ],
    lookFor: [
      'The two estimates agree (within 0.04) until $t \\approx 1.8$ and part once the state is far from 0 ($|x| > 2$), where $q = -\\tfrac12 x^6$ is large: IEM\'s estimate lies further out, pulled by its heavy tails, by more than 0.3 at the worst (near $t \\approx 2.8$).',
      'IEM\'s self-check finds mass near the boundary — the heavy tails — and its advice says why a wider box would make it worse.',
      'No warning of condition (22): as stated, $|q|\\,\\Delta t < 1$, it fails near the edges ($|q|\\,\\Delta t \\approx 2$), but the condition its proof uses, $1 - \\Delta t\\, q > 0$, holds everywhere.',
    ],
    tryThis: [
      {
        label: 'check convergence',
        check: true,
        expect: 'QIEM moves by less than a thousandth of its posterior standard deviation when its grid is doubled and its step halved: converged. IEM with the likelihood in the operator moves by more than a twentieth: not converged at $\\Delta t = 10^{-3}$.',
      },
      {
        label: 'IEM with the likelihood in the update',
        change: (c) => { for (const m of c.methods) if (m.method === 'iem') m.likelihood = 'in_update'; },
        expect: 'with the same grid and step, IEM now equals QIEM to within $10^{-8}$ — not because the schemes agree in general: with $f = 0$ and the observation term in the update, only the Laplacian is left in the operator, and IEM\'s (14) and QIEM\'s (18) both solve $\\big(I - \\tfrac{\\Delta t}{2}\\Delta_h\\big)\\, u^{k+1} = u^k$. The first run\'s gap came from where the observation term went. If you checked convergence first, its table is now the first run\'s (dimmed); check convergence again and IEM converges as QIEM does.',
      },
      {
        label: 'shrink IEM\'s step: Δt = 10⁻⁴',
        change: (c) => { for (const m of c.methods) if (m.method === 'iem') m.dt = 0.0001; },
        expect: 'ten times the steps, and IEM is still more than 0.08 away from QIEM at the worst: with $q$ in the operator the step must resolve $|q| \\approx 2000$.',
      },
    ],
  },
  {
    id: 'two-d',
    // Its text points to the timing table and notes in this panel: opened with the lesson.
    opens: ['diagnostics-panel'],
    title: '6. A 2-D posterior and log-concavity',
    preset: 'yau-2d',
    seed: 1,
    scenario: (c) => c,
    body: [
      'In two dimensions the grid filter\'s density is an image: the heatmap shows the joint posterior of $(x_1, x_2)$ with the truth and every estimate marked. The example is (33) of Yueh, Lin & Yau (2014): the nonlinear drift $f(x) = (-\\cos x_1 - \\sin x_2,\\ \\cos x_1 + \\sin x_2)$ observed linearly, $h(x) = (x_1 - x_2,\\ x_1 + x_2)$. QIEM-4 in the legend is their Algorithm 4, “fourth-order QIEM”, on the same grid: the Laplacian by the 9-point stencil of their (20)–(21), which also uses the four diagonal neighbours, and fourth-order differences for the drift. On its own that stencil is second-order accurate (its error is $\\tfrac{\\Delta s^2}{12}\\Delta^2 u$); this program also applies the compact (Mehrstellen) operator $I + \\tfrac{\\Delta s^2}{12}\\Delta_h$, with $\\Delta_h$ the 5-point Laplacian, to the right-hand side, which makes the Laplacian part fourth order — an addition to the paper\'s algorithm.',
      'Gaussian filters (EKF, UKF) and the MAP filters of Kang, Salmon & Yau (2023) work best when the posterior is log-concave, that is when',
      '$$-\\nabla^2 \\log p(x) \\succeq 0$$',
      'everywhere: then its maximisers form a convex set (a single mode when it is strictly log-concave) and finding the MAP point is a convex problem (their §4, (4.5)); their §3 gives conditions under which the posterior is log-concave. Where the Hessian of $-\\log p$ has a negative eigenvalue the density can bend into a banana or split into modes. With a linear $h$ only the drift can bend the posterior, and here it does so little.',
    ],
    lookFor: [
      'The heatmap: one compact blob around the estimates; EKF, UKF, the particle filter and QIEM nearly agree (their MSEs within 10 % of each other) — also where they are all off the truth together: between $t \\approx 0.9$ and $2$ every one of them estimates $x_1$ about two thirds of a unit above it (0.65 on average). Agreeing methods are not the truth; the observations there say little.',
      'The note at the top of “Diagnostics for researchers” (opened, below the plots): the smallest curvature of $-\\log p$ (the smallest eigenvalue of $-\\nabla^2 \\log p$) where the density is above $10^{-3}$ of its maximum. On this run it stays positive — log-concave — until $t \\approx 1.3$, and then dips a little below 0 (never below $-0.5$) away from the mode: the drift bends the posterior\'s outer part slightly, one compact mode still.',
    ],
    tryThis: [
      { label: 'show the log-concavity layer', view: 'lc-layer', expect: 'the heatmap marks in red the cells, at the time shown, where $-\\nabla^2 \\log p$ has a negative eigenvalue.' },
    ],
  },
  {
    id: 'spectral',
    // Its text points to the timing table and notes in this panel: opened with the lesson.
    opens: ['diagnostics-panel'],
    title: '7. The spectral method: off-line and on-line',
    preset: 'cubic-sensor-1d',
    seed: 3,
    scenario: (c, method) => {
      c.methods = methodsOf(method, [['spectral', { offline_basis: 11, online_basis: 16 }], ['qiem', { points: [399], dt: 0.001 }]]);
      return c;
    },
    body: [
      'Shi, Chen & Yau (2021) hold the density in generalised Legendre functions on the box — on-line, between observations, in $N_{\\text{on}}$ functions $\\phi_j$,',
      '$$\\sigma(t, x) \\approx \\sum_{j=0}^{N_{\\text{on}}-1} c_j(t)\\, \\phi_j(x),$$',
      'and split the work. Off-line, before any observation, the Kolmogorov step over one interval is solved once for every on-line function $\\phi_j$, its result written in $N_{\\text{off}}$ off-line functions $\\psi_l$ (their Algorithm 1: column $j$ of a matrix $W$ solves their linear system (37), the normal equations of a least-squares fit, for $\\phi_j$), so that over one interval $c \\mapsto g = W c$, with $W$ an $N_{\\text{off}} \\times N_{\\text{on}}$ matrix. On-line, at each observation $\\tau_k$, the propagated density $\\sum_l g_l \\psi_l$ is multiplied by the observation factor and projected back onto the on-line basis:',
      '$$c(\\tau_k) = \\Pi\\Big[\\exp\\!\\big(h\\,\\Delta y_k - \\tfrac12 h^2\\, \\Delta\\tau\\big)\\, \\textstyle\\sum_l (W\\,c(\\tau_{k-1}))_l\\, \\psi_l\\Big],$$',
      'a few small matrix products per step and no partial differential equation solved on-line. (This is the program\'s default, likelihood = in_update: the off-line step solves the Fokker–Planck equation alone and the factor carries $-\\tfrac12 h^2 \\Delta\\tau$. In Shi, Chen & Yau\'s own scheme that term sits in the off-line operator, their (12), and the factor is $\\exp(h\\,\\Delta y_k)$, their (15).) The price: the basis must resolve the posterior everywhere on the box, and a narrow posterior on a wide box needs many functions. The filter checks the share of energy in its highest degrees after every step and warns when it exceeds $10^{-3}$.',
    ],
    lookFor: [
      'Its self-check: with 16 functions on $[-4, 4]$ it fires from $t = 0$ — already the prior, with standard deviation 0.32, is too narrow for them — and the estimate strays far from QIEM\'s (by more than 1 at the worst).',
      'The work per interval: the spectral filter evaluates $\\sum_l (W c)_l \\psi_l$ at its on-line Gauss–Legendre nodes — $N_{\\text{off}} + N_{\\text{on}} + 8 = 11 + 16 + 8 = 35$ of them, the program\'s default for $N_{\\text{off}} = 11$ functions off-line and $N_{\\text{on}} = 16$ on-line (35 Gauss–Legendre nodes integrate every polynomial of degree up to 69 exactly; a product of two basis functions has degree at most 25, and the margin is for the observation factor, which is not a polynomial) —, weighs them and projects back — two matrix products of $35 \\times 16$ entries each (the off-line functions at the 35 nodes times $W$, folded into one matrix off-line; then the projection back onto the 16 on-line functions), about 1100 multiply–adds — where QIEM\'s 10 steps of sine transforms on 399 nodes take of order $7 \\cdot 10^4$ operations: a small fraction. (Measured times per step are in Diagnostics for researchers.)',
    ],
    tryThis: [
      {
        label: 'enough functions: 64 on-line, 48 off-line',
        change: (c) => { for (const m of c.methods) if (m.method === 'spectral') { m.online_basis = 64; m.offline_basis = 48; } },
        expect: 'the self-check is (nearly) silent and the estimate stays within 0.15 of QIEM\'s, still at a fraction of QIEM\'s work (120 nodes and 64 functions: about $2 \\times 120 \\times 64 \\approx 15\\,000$ multiply–adds per interval): the off-line work bought a cheap on-line filter.',
      },
    ],
  },
  {
    id: 'likelihood',
    title: '8. The likelihood of the data: whose noise level to believe',
    preset: 'cubic-sensor-fit',
    seed: 3,
    scenario: (c) => c,
    body: [
      'Every lesson so far took the model as known. In practice its noise levels rarely are. Here the state moves by $dx = -x\\,dt + \\sqrt q\\,dv$, $v$ a standard Brownian motion (the signal noise, lesson 1\'s $v$), and is measured every $\\Delta\\tau = 0.2$ as $z_k = x_k^3 + \\varepsilon_k$, $\\varepsilon_k \\sim N(0, r)$, with the measurement noise variance $r$ unknown. The data say which values of $r$ are plausible, through their likelihood.',
      'The exact filter predicts each measurement before it sees it, with the density $p(z_k \\mid z_0, \\dots, z_{k-1}, r)$. The likelihood of all the data is the product of these predictive densities at the measured values (the prediction-error decomposition; the first against the prior):',
      '$$\\ln L(r) = \\ln p(z_0, \\dots, z_N \\mid r) = \\sum_{k=0}^{N} \\ln p(z_k \\mid z_0, \\dots, z_{k-1}, r).$$',
      'Each predictive density is the normalising constant of the Bayes update, the denominator of (3) of Šimandl & Švácha (2005):',
      '$$p(z_k \\mid z_{0:k-1}, r) = \\int p(z_k \\mid x_k, r)\\, p(x_k \\mid z_{0:k-1}, r)\\, dx_k.$$',
      'The separation approach (SA) computes it on its grid as $c_k\'$ of their (7), the normaliser of their update (6), divided by the predicted density\'s mass on the grid: correct up to its discretisation (200 cells of $[-4, 4]$, time step 0.01, first-order upwind for the drift). The EKF predicts instead with the Gaussian $N\\big(h(\\hat x_{k|k-1}),\\, H P_{k|k-1} H^\\top + r\\big)$, $H = h\'(\\hat x_{k|k-1}) = 3\\hat x_{k|k-1}^2$, and the UKF with $N(\\hat z, P_{zz} + r)$, the weighted mean and covariance of $h$ at its sigma points. Here the EKF starts at the prior mean 0, where $H = 0$: its gain is 0, so its estimate never leaves 0 (a fixed point of the predicted mean\'s equation $d\\hat x/dt = -\\hat x$) and every prediction is $N(0, r)$. Its likelihood $\\sum_k \\ln N(z_k; 0, r)$ is largest at $r = \\frac{1}{N+1}\\sum_k z_k^2$, the mean square of the data, about $r + \\overline{x_k^6}$: all of $x^3$ is taken for noise. Maximising an approximate likelihood gives the maximiser of the approximation, which can be biased however many data there are.',
      'The data here are simulated with $q = 0.49$ and $r = 0.5$ (seed 3, 301 measurements $z_0, \\dots, z_{300}$). The Likelihood view below draws $\\ln L(r)$ for each method with $q$ held at its true value 0.49: a slice of the likelihood, not the profile likelihood, which would maximise over $q$ at each $r$ and is wider. The command zakai fit cubic-sensor-fit --params r (and zakai.fit in Python) finds the maximiser and its standard error from the observed information; without --params r it fits $q$ and $r$ together.',
    ],
    lookFor: [
      'The EKF\'s estimate is 0 throughout: started at the prior mean, where $h\'(0) = 0$, it has no gain. Where the truth is far from 0 ($|x| > 1$) its RMS error is 1.23, against the SA\'s 0.51.',
    ],
    tryThis: [
      {
        label: 'draw the likelihood of r',
        likelihood: 'r',
        expect: 'SA\'s $\\ln L(r)$ peaks near $r = 0.46$, about one standard error from the true 0.5 (even with $x$ known the standard error would be about $r\\sqrt{2/301} \\approx 0.04$): sampling error, not bias. The EKF\'s maximiser is exactly the mean square of the measurements, 0.947; the view reports 0.954 because it puts a parabola through the three nearest values, 0.097 apart, of a curve that is not a parabola. The UKF\'s lies near 0.6, in between on this run. The EKF\'s maximum is 48 below the SA\'s: the joint predictive density the EKF assigns to these data is about $e^{48}$ times smaller than the one the SA computes. The table\'s last column is what each method says about its own likelihood at its maximum (one more run there): the SA raises nothing; the EKF\'s normalised innovation squared rises above its band, 2.1 — its innovations are larger than its own covariance says, the sign of a filter whose likelihood should not be trusted.',
      },
    ],
  },
  {
    id: 'smoothing',
    title: '9. Filtering, forecasting and smoothing',
    preset: 'double-well-outage',
    seed: 5,
    scenario: (c) => c,
    body: [
      'Three questions can be asked about the state $x(t)$ from observations $y(s)$ on $[0, T]$. Filtering: what do the observations up to $t$ say about $x(t)$, the density $p\\big(x(t) \\mid y(s), s \\le t\\big)$ — what every lesson so far computed. Forecasting: what do they say about a later $x(t + u)$, $p\\big(x(t+u) \\mid y(s), s \\le t\\big)$. Smoothing: what do all of them, before and after $t$, say about $x(t)$, $p\\big(x(t) \\mid y(s), s \\le T\\big)$ — the best estimate of the past.',
      'The forecast density evolves in $u$ by the Fokker–Planck (forward Kolmogorov) equation alone, lesson 1\'s operator without the observation term, starting from the filter at $t$:',
      '$$\\partial_u p = \\mathcal L^* p = \\tfrac12 \\sum_{i,j} \\partial_i \\partial_j \\big((GG^\\top)_{ij}\\, p\\big) - \\sum_i \\partial_i (f_i\\, p).$$',
      'When nothing is observed between $t$ and $t + u$, the filter is this forecast: a filter whose sensor is out only predicts.',
      'The smoothed density is the filtered one reweighted by what the later observations say about each starting point, $\\beta_t(x)$, the likelihood of the observations after $t$ given $x(t) = x$:',
      '$$p\\big(x(t) \\mid y_{[0,T]}\\big) \\propto p\\big(x(t) \\mid y_{[0,t]}\\big)\\, \\beta_t(x).$$',
      'With continuous observations $\\beta$ solves the backward Zakai equation, backward in time from $\\beta_T = 1$ (Pardoux 1982), with $\\mathcal L$ the adjoint of $\\mathcal L^*$ and $\\overleftarrow{dy}$ a backward Itô differential:',
      '$$\\begin{gathered}-d\\beta = \\mathcal L \\beta\\,dt + \\beta\\, h^\\top S^{-1}\\,\\overleftarrow{dy}, \\\\ \\mathcal L \\beta = \\sum_i f_i\\, \\partial_i \\beta + \\tfrac12 \\sum_{i,j} (GG^\\top)_{ij}\\, \\partial_i \\partial_j \\beta.\\end{gathered}$$',
      'Where nothing is observed, as in an outage, it is the backward Kolmogorov equation $-\\partial_t \\beta = \\mathcal L \\beta$.',
      'On the grid, a step of the scheme carries the density as $p^-_{k+1} = T_k\\, p_k$ and the update multiplies it by the observation\'s factor $\\ell_{k+1}$; the backward function then steps as $\\beta_k = T_k^\\top(\\ell_{k+1} \\odot \\beta_{k+1})$, the transposed matrix standing for the adjoint ($\\odot$, $\\oslash$: node by node). Since $p^s_{k+1} \\oslash p^-_{k+1}$ is proportional to $\\ell_{k+1} \\odot \\beta_{k+1}$, the smoothed densities of the discrete model the filter solves are $p^s_k \\propto p_k \\odot T_k^\\top\\big(p^s_{k+1} \\oslash p^-_{k+1}\\big)$, from $p^s_N = p_N$ (densities as long as the scheme keeps its values nonnegative; values the scheme\'s explicit part makes negative are set to 0, as in the filter). On a linear-Gaussian model the same recursion on means and covariances is the Rauch–Tung–Striebel smoother (Rauch, Tung & Striebel 1965): exact for the model the Kalman–Bucy filter samples at $\\Delta\\tau$ (tending to the continuous-time smoother as $\\Delta\\tau \\to 0$); run on the UKF\'s moments it is a Gaussian approximation, as the UKF is. The particle filter\'s smoother draws whole trajectories backward through its stored particle clouds (Godsill, Doucet & West 2004).',
      'Here: a double well $dx = (x - x^3)\\,dt + 0.8\\,dv$, whose state lingers near $x = \\pm 1$ and now and then crosses over, observed as $dy = x\\,dt + dw$ with $S = 0.3$, except from $t = 3$ to $5.5$, when the sensor is out. QIEM on 299 points, the UKF and a particle filter of 500 run as filters; "smooth the run" below runs each as its smoother.',
    ],
    lookFor: [
      'In the outage QIEM\'s forecast widens: its standard deviation is 0.70 at $t = 3$, 0.88 at $t = 4.25$ and 0.90 at $t = 5.5$, and its density spreads into both wells (at $t = 5.45$ its peaks are at $x \\approx -0.98$ and $1.01$, the lower one 0.68 times as high). Its estimate is 0.20 at $t = 4.25$, where the truth, which crossed from 0.50 at $t = 3$, is at $-0.74$.',
      'Smoothed, QIEM\'s estimate follows the crossing (mean $-0.58$, standard deviation 0.66 at $t = 4.25$): its squared error averaged over the outage falls from 1.13 to 0.10 in this run, and at $t = 5.5$ its standard deviation is 0.36 instead of 0.90. At $t = 8$, with no later data, the smoothed estimate of QIEM and of the UKF is the filtered one; the particle smoother\'s is the mean of its 100 trajectories\' end points, drawn from the filter\'s weights, so it differs a little.',
      'The UKF\'s smoothed estimate at $t = 4.25$ is $-1.16$ (standard deviation 0.91; filtered 0.02), further down than the grid smoother\'s $-0.58$ (the grid smoother converges to the exact smoother as its grid is refined); its squared error over the outage falls from 0.84 to 0.13. On this one path the UKF\'s filter has the smaller error over the outage (0.84 against QIEM\'s 1.13): the conditional mean is the best estimate on average over paths, not on each one.',
    ],
    tryThis: [
      {
        label: 'smooth the run',
        view: 'smoothed',
        expect: 'the estimates drawn are now the smoothed ones, the filters\' faint and dotted beside them, and the heat strip shows QIEM\'s smoothed density: at $t = 4.25$ a single peak, below 0.',
      },
    ],
  },
  {
    id: 'measurement-families',
    title: '10. Counts, volatility and outliers: measurements that are not Gaussian',
    preset: 'stochastic-volatility',
    seed: 1,
    scenario: (c) => c,
    body: [
      'Every lesson so far measured the state through Gaussian noise. Many data are not like that: counts of events (spikes, cases, photons), measurements with occasional gross errors, returns whose spread is what changes. All that Bayes\' rule needs from a measurement is its likelihood, the density (for counts, the probability) $p(z_k \\mid x)$ of the value measured given each possible state. The update multiplies the predicted density by it and normalises:',
      '$$p(x \\mid z_{0:k}) = \\frac{p(z_k \\mid x)\\, p(x \\mid z_{0:k-1})}{\\int p(z_k \\mid x\')\\, p(x\' \\mid z_{0:k-1})\\, dx\'},$$',
      'Bayes\' rule as the separation approach states it (Šimandl & Švácha 2005 [001], (3)); its grid form (6)–(7) is written there for additive noise, $p(z_k \\mid x) = p_{\\varepsilon}(z_k - h_k(x))$ (001 writes the measurement noise $v_k$; here $\\varepsilon$, $v$ being the signal\'s noise). On the SA\'s grid the product is taken cell by cell, on particles particle by particle, whatever the form of $p(z \\mid x)$: these filters are exact in the measurement, and approximate only in their discretisation (cells and time step) or their number of particles. Three measurement models are in this lesson:',
      '$$\\begin{gathered}z_k \\sim N\\big(0,\\, e^{x_k}\\big), \\\\ z_k \\sim \\mathrm{Poisson}\\big(e^{x_k}\\big), \\\\ z_k = x_k + \\sigma\\, e_k,\\ e_k \\sim t_\\nu .\\end{gathered}$$',
      '($\\sigma$ here is a scale, not lesson 1\'s unnormalised density.) A Kalman-type filter assumes $z = h(x) + \\varepsilon$ with Gaussian $\\varepsilon$. This program gives it each family\'s first two conditional moments: the mean $E[z \\mid x] = h(x)$, kept as a function of $x$, and the variance, frozen at the predicted mean: $R = \\mathrm{Var}[z \\mid x]$ at $x = \\hat x^-$. That is $R = e^{\\hat x^-}$ for the volatility (with $h = 0$) and for the counts (with $h = e^x$), and $R = \\sigma^2 \\nu / (\\nu - 2)$ for Student-t noise, which has a variance only when $\\nu > 2$. This is a moment match, and the run\'s warnings say so for each Gaussian filter.',
      'For the volatility it is fatal. Every sigma point of the UKF predicts $z = h(\\chi_i) = 0$, so the cross-covariance $P_{xz}$ and with it the gain $K = P_{xz} P_{zz}^{-1}$ are 0; the EKF\'s gain is 0 too, since $H = h\'(\\hat x) = 0$. The information about $x$ is in the size of $z$ ($E[z^2 \\mid x] = e^x$, while $\\mathrm{Cov}(x, z) = 0$), and an update linear in $z$ cannot use it.',
      'Here: $dx = -0.1\\,x\\,dt + 0.3\\,dv$, where $x$ is the log-variance of daily returns $z_k \\sim N(0, e^{x_k})$, every $\\Delta\\tau = 1$ for $T = 300$, $p(x_0) = N(0, 0.45)$ (the stationary law). The separation approach (SA) on 200 cells of $[-4, 4]$, a particle filter of 1000, the UKF and the EKF.',
    ],
    lookFor: [
      'The UKF\'s and EKF\'s estimates are 0 at every time, and their standard deviation stays at 0.67, the prior\'s $\\sqrt{0.45}$ (the prior is the stationary law, so prediction alone keeps it there): they never learn from the data (MSE 0.571, this path\'s mean of $x_t^2$, whose expectation is 0.45). The SA follows the swings of the log-variance (MSE 0.306), as does the particle filter (0.305).',
      'The SA\'s density (the heat strip, and the densities plot when you look back) leans to the right: its skewness is positive at each of the 61 times the page keeps for looking back (every 5 time units), between 0.01 and 0.21. Each measurement\'s log-likelihood in $x$ is $-x/2 - z^2 e^{-x}/2$ up to a constant: it falls exponentially towards low volatility and only linearly towards high (so the likelihood itself falls double-exponentially towards low volatility), so the data rule out low volatilities more sharply than high ones.',
      'The warnings above the plots name the moment match for the UKF and the EKF, and for neither the SA nor the particle filter.',
    ],
    tryThis: [
      {
        label: 'counts: Poisson(eˣ)',
        preset: 'poisson-counts',
        expect: 'the poisson-counts preset, $dx = -0.5\\,x\\,dt + 0.6\\,dv$ and $z_k \\sim \\mathrm{Poisson}(e^{x_k})$ every 0.5: here the estimates are close (MSE SA 0.170, UKF 0.169, EKF 0.154; one run cannot rank them, and it is the exact posterior mean, which the SA approximates, that minimises the expected squared error), but the log-likelihoods are not: −171.8 for the SA, −195.0 for the UKF (comparable: the counts are one apart, so the UKF\'s density there is close to a probability). A model fitted by maximising a Gaussian filter\'s likelihood would be fitted to the wrong density (lesson 8).',
      },
      {
        label: 'outliers: Student-t noise',
        preset: 'student-t-outliers',
        expect: 'the student-t-outliers preset, $dx = -x\\,dt + dv$ and $z_k = x_k + 0.2\\,e_k$, $e_k \\sim t_\\nu$ with $\\nu = 2.5$, every 0.25. The t log-likelihood\'s slope in $x$ is $(\\nu + 1)\\,r / (\\nu\\sigma^2 + r^2)$ with $r = z - x$: it tends to 0 as $|r|$ grows, so a measurement far from every plausible state barely moves the posterior, while a Gaussian update moves the mean by $K(z - \\hat x^-)$, in proportion to the innovation. At $t = 23.5$ the measurement is −6.12 while the state is −0.53: the UKF jumps to −3.52, the SA stays at −0.31. Over the run the MSE is 0.111 for the SA and 0.205 for the UKF.',
      },
    ],
  },
  {
    id: 'state-dependent-noise',
    title: '11. Noise that grows with the state',
    preset: 'interest-rate',
    seed: 1,
    scenario: (c) => c,
    body: [
      'Every model so far had a constant noise gain $G$. In many systems the noise scales with the state: a population fluctuates more when it is large, an interest rate moves less when it is low. Cox, Ingersoll & Ross (1985) model a short rate as',
      '$$dx = \\kappa(\\theta - x)\\,dt + \\sigma\\sqrt{x}\\,dv,$$',
      'pulled towards the level $\\theta$ at the rate $\\kappa$, with a noise that vanishes as $x \\to 0$; when $2\\kappa\\theta \\ge \\sigma^2$ (Feller\'s condition) a rate started above 0 almost surely never reaches 0. Its stationary law is a gamma density, $p_\\infty(x) \\propto x^{2\\kappa\\theta/\\sigma^2 - 1} e^{-2\\kappa x/\\sigma^2}$.',
      'Here $\\kappa = 0.5$, $\\theta = 0.25$, $\\sigma = 0.35$ ($2\\kappa\\theta = 0.25 \\ge \\sigma^2 = 0.1225$), so $p_\\infty(x) \\propto x^{1.04} e^{-8.16\\,x}$, which is this run\'s prior. The rate is measured every $\\Delta\\tau = 0.25$ with noise, $z_k = x_k + 0.3\\,e_k$, for $T = 50$. The program\'s $G(x) = 0.35\\sqrt{|x|}$ is the same while $x > 0$, and is defined on the whole grid and wherever an Euler step of the simulation or of a particle lands below 0. The exact solution stays positive with either $G$; only Euler steps and the grid put anything below 0.',
      'Between measurements the density solves lesson 1\'s Fokker–Planck equation, with $a(x) = G(x)^2 = \\sigma^2 |x|$ inside the second derivative:',
      '$$\\partial_t p = -\\partial_x\\big(f\\,p\\big) + \\tfrac12\\,\\partial_x^2\\big(a\\,p\\big).$$',
      'Šimandl & Švácha (2005) [001] write it, (4), for a $Q$ that does not depend on $x$, where the last term is $\\tfrac12 Q\\,\\partial_x^2 p$. The separation approach\'s implicit step for the parabolic part (10) (their (17)) then differences $a\\,p$ instead of $p$:',
      '$$\\begin{aligned}\\frac{p_{j+1}[i] - p^*[i]}{\\Delta t} &= -f\'(x_i)\\,p_{j+1}[i] \\\\ &\\quad + \\frac{1}{2\\,\\Delta x^2}\\big(a_{i+1}p_{j+1}[i+1] - 2a_i p_{j+1}[i] \\\\ &\\qquad\\quad + a_{i-1}p_{j+1}[i-1]\\big),\\end{aligned}$$',
      'where $p_{j+1}[i]$ is the density in cell $i$ after the step and $p^*[i]$ the density the step\'s advection part (9) left there, with $a_i = a(x_i)$; for a constant $a = Q$ this is (17). The matrix of this system has the off-diagonal entries $-\\Delta t\\,a_{i\\pm1}/(2\\Delta x^2) \\le 0$, and column $i$ holds $1 + \\Delta t\\,f\'(x_i) + \\Delta t\\,a_i/\\Delta x^2$ on the diagonal against $\\Delta t\\,a_i/\\Delta x^2$ off it in all. When $1 + \\Delta t\\,f\'(x_i) > 0$ it is strictly diagonally dominant by columns, an M-matrix, so the step keeps the density nonnegative; and the diffusion\'s entries in each column sum to 0, so that part of the step only moves mass between cells (away from the grid\'s edges). The particle filter moves each particle with its own noise, $x \\leftarrow x + f(x)\\,\\delta + G(x)\\sqrt{\\delta}\\,\\xi$ over each substep $\\delta$, with $\\xi \\sim N(0, 1)$ (Euler–Maruyama).',
      'A Gaussian filter carries a mean $m$ and a variance $P$. For this model the exact prediction\'s mean and variance obey $\\dot m = \\kappa(\\theta - m)$ and $\\dot P = -2\\kappa P + \\sigma^2 m$ (the expectations of $dx$ and, by Itô\'s formula, of $d(x - m)^2$, with $\\mathbb E\\,a(x) = \\sigma^2\\,\\mathbb E\\,x$ while $x > 0$). The UKF here takes $a$ at its mean, $\\dot P = -2\\kappa P + a(m)$, as the run\'s warning says, and its sigma points follow the linear drift exactly: while $m > 0$ these are exactly the moment equations above, so between measurements it carries its own mean and variance as the exact dynamics would. They still differ from the conditional ones, because its update treats the skewed prediction as Gaussian. What it cannot carry is the shape.',
    ],
    lookFor: [
      'The SA\'s density (the heat strip, and the densities plot at the time shown) is skewed to the right at each of the 41 times the page keeps for looking back (every 1.25 time units): its skewness is between 0.27 and 1.09, largest at the time where its mean is lowest ($t = 45$) and smallest where its mean is highest ($t = 3.75$). Below the mean the noise $\\sigma\\sqrt x$ is smaller than above it, and the drift pushes up from 0, so the density is squeezed between 0 and its mode and spreads upwards, the more so the closer its mean is to 0. It never puts more than 0.5 % of its mass below 0 (0.46 % at $t = 45$; the exact density has none there: this is the discretisation\'s error).',
      'The UKF\'s Gaussian gives a negative rate a probability above 5 % at 16 of those 41 times, and 20.5 % at $t = 41.25$ (mean 0.087, standard deviation 0.106), where the SA\'s density has 0.39 % below 0.',
      'The estimates are close all the same: MSE 0.0111 for the SA, 0.0110 for the particle filter and 0.0105 for the UKF on this path (one run cannot rank them). The measurement noise\'s standard deviation, 0.3, is 1.7 to 4 times the SA\'s posterior one (0.075 to 0.18 at the kept times), and between updates the UKF propagates its own mean and variance exactly (see above).',
      'The warnings above the plots name the UKF\'s approximation (the process noise taken at the mean), and say nothing of the SA or the particle filter. The warning is the general one, $E[Q(x)] \\ne Q(E[x])$ where $Q$ is not affine: here $a(x) = \\sigma^2 |x|$ is affine for $x > 0$, so it matters only through the mass the UKF\'s Gaussian puts below 0, where $|x|$ bends.',
    ],
    tryThis: [
      {
        label: 'a constant noise instead',
        change: (c) => { c.model.diffusion = [[0.175]]; },
        expect: '$G = 0.175 = \\sigma\\sqrt\\theta$, the same noise at every level as the square-root model has at $\\theta$ (Vasicek 1977\'s model). The density is then nearly symmetric once the prior is forgotten: its skewness is between −0.03 and 0.03 at every kept time from $t = 1.25$ on (at $t = 0$, after the first measurement, it is 0.73; the gamma prior\'s is $2/\\sqrt{2.04} = 1.40$). And the model itself allows negative rates: the truth dips to −0.05, and the SA\'s density has 22.8 % of its mass below 0 at $t = 45$. The Gaussian is now close to the right shape (MSE SA 0.0112, UKF 0.0111).',
      },
    ],
  },
  {
    id: 'growth-model',
    title: '12. A map, not an SDE: the growth model\'s two modes',
    preset: 'ungm',
    seed: 1,
    speed: 1,
    scenario: (c) => c,
    body: [
      'Every lesson so far wrote the signal as a stochastic differential equation, which each method discretises in time. Many models are given instead as a map from one observation time to the next — an autoregression, a sampled tracking model — and that is how FilterPy, statsmodels and the Python package particles write their models. A standard benchmark of the particle-filter literature is such a map, the univariate non-stationary growth model (Kitagawa 1996; Gordon, Salmond & Smith 1993), here in the form of Arulampalam, Maskell, Gordon & Clapp (2002):',
      '$$\\begin{gathered}x_k = F(x_{k-1}, k) + w_k, \\\\ F(x, k) = \\tfrac12 x + \\frac{25\\,x}{1 + x^2} + 8\\cos(1.2k), \\\\ z_k = \\frac{x_k^2}{20} + v_k,\\end{gathered}$$',
      'with $w_k \\sim N(0, 10)$, $v_k \\sim N(0, 1)$ and $x_0 \\sim N(0, 5)$ (here $w$ is the signal\'s noise and $v$ the measurement\'s, as the particle-filter literature and the model form write a map; lessons 1–11 had the letters the other way round) (the second argument of $N$ is the variance: $w_k$ has standard deviation $\\sqrt{10} \\approx 3.16$), one transition per unit of time, so that $t = k$, and a measurement at each of $t = 0, 1, \\dots, 50$ ("signal in time: discrete" in the model form).',
      'Write $p_{k-1}$ for the filtering density after the measurement at $k - 1$ and $p^-_k$ for the prediction to time $k$. Between measurements the density moves by the Chapman–Kolmogorov equation, the discrete-time counterpart of lesson 1\'s Fokker–Planck equation, and the measurement multiplies it in by Bayes\' rule:',
      '$$\\begin{gathered}p^-_k(x) = \\int N\\big(x;\\ F(\\xi, k),\\ 10\\big)\\, p_{k-1}(\\xi)\\, d\\xi, \\\\ p_k(x) \\propto p(z_k \\mid x)\\, p^-_k(x).\\end{gathered}$$',
      'The point-mass filter (PMF) computes both on a grid — the method of Bucy & Senne (1971), in the form of Šimandl, Královec & Söderström (2006). The density is held at the centres $\\xi_j$ of 800 cells of width $\\Delta = 0.1$ covering $[-40, 40]$, $p[j] = p(\\xi_j)$, and the predicted value in cell $i$ is $\\sum_j T_{ij}\\, p[j]$, where $T_{ij}$ is the probability that $N\\big(F(\\xi_j, k), 10\\big)$ falls in cell $i$ — a difference of two normal distribution functions at the cell\'s edges, close to $N\\big(x_i; F(\\xi_j, k), 10\\big)\\,\\Delta$, so that the sum is the integral\'s Riemann sum; the kernel is cut at 6 standard deviations and renormalised there. Bayes\' rule then multiplies in $p(z_k \\mid x)$ cell by cell, as the separation approach of Šimandl & Švácha (2005) [001] does in its (6). The particle filter draws each particle from the transition itself, $x \\leftarrow F(x, k) + \\sqrt{10}\\,\\varepsilon$ with $\\varepsilon \\sim N(0, 1)$ (no Euler steps), then weighs it by $p(z_k \\mid x)$ and resamples. The methods that solve continuous-time equations (Yau–Yau, spectral, direct, Fokker–Planck) do not apply to a map and say so.',
      'The measurement sees $x^2$ only: $p(z \\mid x) = p(z \\mid -x)$, largest at $x = \\pm\\sqrt{20 z_k}$ when $z_k > 0$. Whether the posterior has one mode or two depends on the prediction: where it puts mass near both $+\\sqrt{20 z_k}$ and $-\\sqrt{20 z_k}$, both survive the update, and only a later prediction — through the cosine, which shifts both modes the same way — can tell them apart. A Gaussian filter carries one mode. The EKF linearises $h$ at its predicted mean $\\hat x$, with $H = \\hat x / 10$: near $\\hat x = 0$ its gain vanishes (lesson 3\'s cubic sensor again); elsewhere it reads the measurement as $x \\approx \\hat x / 2 + 10 z_k / \\hat x$, a Newton step towards the root $\\pm\\sqrt{20 z_k}$ on $\\hat x$\'s side that overshoots outwards when $\\hat x$ is far from it. For $z_k > 0$ an update never takes it across 0; only its prediction can.',
    ],
    lookFor: [
      'The point-mass filter\'s density (the heat strip; the densities plot at the time shown) has two peaks, one on each side of 0, at 16 of the 51 times (counting the peaks above a tenth of its maximum on the plot\'s 200 points): at $t = 17$ they are at $x = \\pm 13.5$, with 58 % of the mass below 0, and the truth is at $-13.13$. The prediction barely favours a sign there (58 : 42).',
      'There the point-mass filter\'s mean is $-2.16$ with standard deviation 13.25: the conditional mean sits between the modes, where the state almost never is, yet it is still the estimate with the least mean squared error, and its standard deviation, mostly the distance between the modes, says how far off it may be. The EKF is at $14.68$ with standard deviation 1.14, on the wrong mode and sure of it: 27.8 from the truth, 24 times its own standard deviation. The UKF is at $0.24$ with standard deviation 15.31, uncertain but blind to the two modes.',
      'The next prediction tells the modes apart: $F(\\pm 13.5, 18) \\approx 1.2$ and $-16.0$ (the cosine term, $8\\cos(21.6) \\approx -7.4$, shifts both down), and the truth moves to $-18.50$. At $t = 18$ the point-mass filter is at $-18.91$ with standard deviation 0.52, and so is the particle filter, while the EKF stays on the positive side from $t = 17$ to $t = 25$ (25.17 at $t = 18$ down to 7.74 at $t = 25$) with the truth below 0 throughout.',
      'The particle filter (1000 particles drawn from the transition) has its mean within 0.53 point-mass standard deviations of the point-mass filter\'s mean at every time. Mean squared errors on this run: point mass 34.19, particle filter 35.78, UKF 65.69, EKF 218.53. Agreement in the mean does not vouch for every step: the particle filter\'s own self-check (the ⚠ in its row of the metrics) flags two steps, the first at $t = 42$, where its effective sample size after weighting fell below 1 % of its particles — the weights collapsed onto a few of them.',
    ],
    tryThis: [
      {
        label: 'an odd map: drop 8 cos(1.2k)',
        change: (c) => { c.model.drift = ['x/2 + 25*x/(1 + x^2)']; },
        expect: 'without the cosine $F(-x) = -F(x)$: an even density through an odd map with noise symmetric about 0 stays even, the likelihood $p(z \\mid x)$ is even in $x$, and the prior is even, so by induction the posterior is even at every step and its mean is exactly 0. The point-mass filter\'s mean stays within $10^{-11}$ of 0, and on this run from $t = 1$ on its density has two mirrored peaks, one on each side of 0, at every time (at $t = 0$, after the first measurement, one peak, at 0), while the truth is within 3 of the map\'s stable fixed points $\\pm 7$ at 31 of the 51 times ($x = F(x)$ gives $x = 0$ or $x^2 = 49$; $F\'(x) = \\tfrac12 + 25(1 - x^2)/(1 + x^2)^2$ is 25.5 at 0 and 0.02 at $\\pm 7$). The point-mass filter\'s MSE, 65.51, is the mean square of the truth. The EKF and UKF are at 0 too: the EKF because its gain is 0 at $\\hat x = 0$ and $F(0) = 0$ (its variance meanwhile grows about 650-fold per step, $F\'(0)^2$), the UKF because $F$ is odd and $h$ even, so that over its symmetric sigma points the covariance of $x$ and $z$ is 0 and so is its gain: the same MSE. The particle filter\'s MSE is 92.95: its finite cloud does not keep the two modes equal, and its mean wanders off 0.',
      },
    ],
  },
  {
    id: 'posterior',
    title: '13. From a best fit to a posterior',
    preset: 'cubic-sensor-fit',
    seed: 3,
    opens: ['post-panel'],
    // A particle filter beside the preset's methods, for the last two tries.
    scenario: (c, method) => ({ ...c, methods: [...c.methods, method('pf', { particles: 200 })] }),
    body: [
      'Lesson 8 drew the likelihood $L(q, r) = p(z_0, \\dots, z_N \\mid q, r)$ of the cubic sensor\'s data along one noise level. A maximum-likelihood fit reports its highest point and a standard error from its curvature there. Bayes\' rule reports instead a distribution over the unknowns, the posterior:',
      '$$p(q, r \\mid z_{0:N}) = \\frac{L(q, r)\\, p(q, r)}{\\iint L(q\', r\')\\, p(q\', r\')\\, dq\'\\, dr\'},$$',
      'where $p(q, r)$ is the prior. Here it is uniform on the parameters\' bounds, $q \\in [0.01, 4]$ and $r \\in [0.05, 4]$, so the posterior is the likelihood restricted to that box and normalised: its shape — skewed, bounded, with the two unknowns traded against each other — is the likelihood\'s own, which a point and a standard error summarise only when it is close to a Gaussian.',
      'Each value of $L$ is a whole filter run, so the posterior is explored by a Markov chain that needs only ratios of $L\\,p$ (Metropolis, Rosenbluth, Rosenbluth, Teller & Teller 1953; Hastings 1970). From its current point $\\theta = (q, r)$ the chain proposes $\\theta\' = \\theta + \\varepsilon$, a Gaussian step, and moves there with probability',
      '$$\\alpha = \\min\\Big(1,\\ \\frac{L(\\theta\')\\, p(\\theta\')}{L(\\theta)\\, p(\\theta)}\\Big),$$',
      'else stays. The chain\'s states are then draws from the posterior, correlated ones. The steps are taken on an unbounded scale, $u = \\ln\\frac{\\theta - a}{b - \\theta}$ for $\\theta \\in [a, b]$, with the factor $|d\\theta/du|$ in the ratio so that the target stays $p(\\theta \\mid z)$; their covariance adapts during a warm-up to the chain\'s own (Haario, Saksman & Tamminen 2001), and their size so that about 23 % of proposals are accepted (Andrieu & Thoms 2008); both are then fixed.',
      'Four chains from different starting points: if they have forgotten where they started, they describe the same distribution and the rank-normalised split $\\hat R$, a ratio of the spread between chains to the spread within them, is near 1 — below 1.01 (Vehtari, Gelman, Simpson, Carpenter & Bürkner 2021). The effective sample size (ESS) is the number of independent draws the correlated ones are worth, for the bulk and for the 5 % and 95 % quantiles; below 400 (100 a chain) Vehtari et al. do not trust even the $\\hat R$ and ESS estimates; a mean\'s Monte Carlo error is about its sd over $\\sqrt{\\text{ESS}}$.',
      'The same data as lesson 8 (seed 3, 301 measurements, simulated with $q = 0.49$ and $r = 0.5$). The command zakai sample cubic-sensor-fit --observations obs.csv --method separation (and zakai.sample in Python) draws the same posterior, starting from the maximum-likelihood estimate.',
    ],
    lookFor: [
      'The Posterior panel below the plots: each parameter\'s traces (one line per chain, drawn as the chains go), its histogram with the prior dashed, the two parameters\' joint draws over the likelihood\'s regions, and the table of means, intervals, $\\hat R$ and ESS with the notes under it.',
    ],
    tryThis: [
      {
        label: 'sample the SA\'s posterior of q and r',
        posterior: { method: 'separation', draws: 600, warmup: 400, chains: 4 },
        expect: 'after 4 004 runs of the separation approach (4 chains × 1 000 iterations, and 4 starts): $r$\'s 90 % interval [0.35, 0.51] around its mean 0.43; $q$\'s [0.49, 0.91], its mean 0.69 above its median 0.68 (a longer tail to the right), and the true 0.49 at its lower end. The joint draws lean — a larger $q$ goes with a smaller $r$ (correlation −0.34): more signal noise and less measurement noise explain the same spread of the data. With 600 kept draws a chain the notes warn: the ESS of both parameters is below 400 (242 to 391) and $\\hat R$ of $r$ is 1.018; the intervals\' ends are uncertain in their second digit, and longer chains would settle them.',
      },
      {
        label: 'the same with the EKF\'s likelihood',
        posterior: { method: 'ekf', draws: 600, warmup: 400, chains: 4 },
        expect: 'the draws of $q$ spread over its whole box — mean 2.00 and sd 1.17, against the uniform prior\'s 2.005 and 1.15: the EKF\'s likelihood does not depend on $q$ at all (its gain is 0, lesson 8, and every prediction is $N(0, r)$), so its posterior of $q$ is its prior. Its posterior of $r$ is narrow and wrong: 90 % in [0.83, 1.09], around the mean square of the measurements 0.947, nowhere near the true 0.5. A posterior is only as good as the likelihood it is made of.',
      },
      {
        label: 'the particle filter\'s posterior, fresh random numbers',
        posterior: { method: 'pf', draws: 600, warmup: 400, chains: 4 },
        expect: 'a particle filter gives only an estimate $\\hat L(\\theta)$ of the likelihood: unbiased, and noisy. Particle marginal Metropolis–Hastings (Andrieu, Doucet & Holenstein 2010) puts it in $\\alpha$ in place of $L$, a fresh estimate at each proposal, the current point keeping its own. The chain is then a Metropolis–Hastings chain on $\\theta$ and the filter\'s random numbers $U$, whose target $p(\\theta)\\,\\hat L(\\theta, U)\\,\\varphi(U)$ has, because $\\hat L$ is unbiased, the exact posterior as its $\\theta$-marginal (re-estimating $L$ at the current point too would lose this). But where an estimate came out well above $L(\\theta)$ the chain sticks: each proposal is accepted with probability $\\min(1, \\hat L\\, p / \\hat L_{\\text{current}}\\, p_{\\text{current}})$, small until one comes out comparably high. What matters is the spread of $\\ln \\hat L$: for a fixed number of particles its variance grows in proportion to the number of measurements, and the chain mixes well only when its standard deviation is about 1 to 1.7 (Doucet, Pitt, Deligiannidis & Kohn 2015). With 200 particles on these 301 measurements the chains accept 17 % of their proposals on average after the warm-up (the warm-up shrinks the steps towards an acceptance of about 23 %, so the rate hides the noise), and they still disagree after 400 warm-up iterations and 600 kept draws: $\\hat R$ is 2.2 for $q$ and 1.7 for $r$, and the bulk and tail ESS are between 5 and 22 of 2 400 draws — these means and intervals are not yet the posterior\'s.',

      },
      {
        label: 'the same with correlated random numbers',
        posterior: { method: 'pf', sampler: 'correlated', rho: 0.99, draws: 600, warmup: 400, chains: 4 },
        expect: 'the filter\'s random numbers $U$ (every random number a run uses: the normals of its prior draws and of its moves between measurements, and, through $\\Phi$, each resampling\'s uniform) become part of the chain\'s state and move with each proposal, $U\' = \\rho U + \\sqrt{1 - \\rho^2}\\,\\varepsilon$ with $\\varepsilon \\sim N(0, I)$ and $\\rho = 0.99$ (Deligiannidis, Doucet & Pitt 2018). This step is reversible with respect to $N(0, I)$ (the pair $(U, U\')$ has the same law as $(U\', U)$), so in the acceptance ratio the proposal\'s density cancels against $U$\'s and $\\alpha$ is the PMMH one with the estimates at $(\\theta\', U\')$ and $(\\theta, U)$; $\\theta\'$ and $U\'$ are accepted or rejected together, and the chain\'s stationary distribution is still the exact posterior. For the estimate to change little when $\\theta$ or $U$ does, the filter sorts its particles before each resampling (by value, the state being one-dimensional; along a Hilbert curve in more), so that a small change moves which particles are copied only a little instead of reshuffling them; the two estimates in each ratio then share most of their noise. Same particles, same iterations: acceptance 22 % on average, $\\hat R$ 1.06 for $q$ and 1.03 for $r$, the means 0.73 and 0.44 beside the SA\'s 0.69 and 0.43. Both $\\hat R$ are still above 1.01 and the ESS runs from 63 to 359, so the notes ask for longer chains; a mean\'s Monte Carlo error is about its sd over $\\sqrt{\\text{ESS}}$, and the gap in $q$ is not yet a difference between the two likelihoods (the particles move by the Ornstein–Uhlenbeck transition exactly, so this chain\'s target is the model\'s own posterior, the SA\'s a grid approximation of it).',

      },
    ],
  },
  {
    id: 'tensor-train',
    // Its text points to the density column of the timing table in this panel: opened with the lesson.
    opens: ['diagnostics-panel'],
    title: '14. The curse of dimensionality and how low rank breaks it',
    preset: 'cubic-sensor-4d',
    seed: 1,
    scenario: (c) => c,
    body: [
      'Every grid filter so far held the density at every node of a grid. With $n$ points along each of $d$ axes that is $n^d$ numbers, and the count multiplies by $n$ with every dimension — the curse of dimensionality (Bellman 1961). The preset takes the cubic sensors of Shi, Chen & Yau\'s (2021) Example 2 to four dimensions, with the drift $-0.4\\, x_i$ in every component and without the example\'s coupling: four independent cubic sensors,',
      '$$dx_i = -0.4\\, x_i\\, dt + dv_i, \\qquad dy_i = x_i^3\\, dt + dw_i, \\qquad i = 1, \\dots, 4,$$',
      'from $x_0 = (1, 1, 1, 1)$ with prior $N(x_0, 0.1\\, I)$ on the box $[-4, 4]^4$. The tensor-train filter below takes 160 points an axis, the most its default takes beyond one dimension (10 points per prior standard deviation would be 253; 160 interior points space the nodes $8/161 \\approx 0.05$ apart, 6.4 per prior standard deviation): a full grid would hold $160^4 \\approx 6.55 \\cdot 10^8$ values, 5.2 GB in double precision, and in ten dimensions $160^{10} \\approx 1.1 \\cdot 10^{22}$.',
      'The tensor-train (TT) format (Oseledets 2011) writes the value at node $(i_1, \\dots, i_d)$ as a product of matrices, one from each dimension:',
      '$$p(i_1, \\dots, i_d) = G_1[i_1]\\, G_2[i_2] \\cdots G_d[i_d], \\qquad G_k[i_k] \\in \\mathbb{R}^{r_{k-1} \\times r_k},\\ r_0 = r_d = 1,$$',
      'which takes $\\sum_k r_{k-1}\\, n_k\\, r_k$ numbers: linear in $d$ and quadratic in the ranks $r_k$ ($r_0 = r_d = 1$ always, so $d$ dimensions have $d + 1$ ranks, $d - 1$ of them free). The smallest $r_k$ that represents a tensor exactly is the rank of its unfolding, the matrix whose rows are indexed by $(i_1, \\dots, i_k)$ and columns by $(i_{k+1}, \\dots, i_d)$ (Oseledets 2011, Theorem 2.1, and its easy converse): how far the tensor is from a sum of few products of a function of the first $k$ coordinates and one of the rest. A product $p_1(x_1) \\cdots p_d(x_d)$ has every rank 1.',
      'Li, Wang, Yau & Zhang (2023) run the Yau–Yau filter in this format, and so does this program\'s TT filter. Between observations the Kolmogorov equation is split into flows along one dimension each: for dimension $k$, the exponential of the one-dimensional difference operator of its diffusion and of the drift $f_k$ when $f_k$ reads $x_k$ alone, an $n \\times n$ matrix applied to the one core $G_k$ (a drift that reads other coordinates gets a flow of its own on a block of adjacent cores, by Runge–Kutta steps, placed symmetrically around the one-dimensional ones: Strang splitting). At each observation the density is multiplied by the robust-DMZ factor $\\exp(h\\, \\Delta y)$ of Yueh, Lin & Yau (2014), their (15), with the $-\\tfrac12 h^2$ of the potential in their (4) moved from the Kolmogorov step into the update (as lesson 7 explains for the spectral filter),',
      '$$p \\leftarrow p \\cdot \\prod_{i=1}^{4} \\exp\\!\\big(h_i(x)\\, \\Delta y_i - \\tfrac12 h_i(x)^2\\, \\Delta\\tau\\big),$$',
      'factor by factor on the cores each factor reads. A one-dimensional flow or a factor that reads one coordinate changes one core and no rank. A block flow or a factor that reads several coordinates multiplies the cores of its block out and splits the block back into cores by truncated singular value decompositions (Oseledets 2011, TT-SVD), cutting singular values while the relative error of the node values (in the Frobenius norm) stays below $\\varepsilon = 10^{-7}$ — unless a rank would exceed the cap of 30: then the cap wins, and the self-check reports a step\'s error above $10^{-3}$.',
      'Here nothing couples the components: the Kolmogorov operator is a sum of one-dimensional operators, one per $x_i$, which commute, so that applying their exponentials one after another is exact in time for the gridded operator (the central differences and the box remain); each factor of the update reads one $x_i$, and the prior is a product. A product stays a product under each of these steps, so the filter\'s posterior is $p_1(x_1, t) \\cdots p_4(x_4, t)$, four 1-D Yau–Yau posteriors, at every time: rank 1 throughout. (Zakai\'s test suite compares it with products of four, six and ten fine 1-D filters.)',
    ],
    lookFor: [
      'Diagnostics for researchers (opened, below the plots), the column “density held”: the TT filter holds 640 numbers, $4 \\times 160$, for the $6.55 \\cdot 10^8$ points of its grid, with ranks 1-1-1-1-1 at $t = 5$ and no larger at any time before.',
      'The heatmap (its caption chooses any pair of components): the joint density of $x_1, x_2$ is a product of its two marginals, its correlation 0 to rounding ($|\\rho| < 10^{-10}$ on the raster at $t = 5$).',
      'MSEs on this run (summed over the four components, Shi, Chen & Yau\'s (43)): TT 1.5223, PF(10 000) 1.5564, PF(1000) 1.5112, EKF 1.8552, UKF 2.5935. The mean of the particle filter with 10 000 particles stays within 0.52 of the TT filter\'s posterior standard deviations of the TT mean, in every component at every time (the largest gap, 0.51, in $x_1$). That PF(1000) has the smallest MSE here is one run\'s luck: the conditional mean has the least mean squared error on average over runs (the Monte Carlo panel), not on each run.',
    ],
    tryThis: [
      {
        label: 'a sensor of the sum: h₁ = (x₁ + x₂)³',
        change: (c) => { c.model.observation[0] = '(x1 + x2)^3'; },
        expect: 'the first factor of the update now reads $x_1 + x_2$ and is no longer a product of a function of $x_1$ and one of $x_2$: the posterior of $(x_1, x_2)$ leans, its correlation on the heatmap $-0.56$ at $t = 5$. Rank $r_1$, between $x_1$ and $x_2$, rises — to the cap of 30 at its largest, 19 at $t = 5$ (6 400 numbers) — while $r_2$ and $r_3$ stay 1: $(x_1, x_2)$ is still independent of $x_3$ and of $x_4$, and the TT filter\'s MSEs of $x_3$ and $x_4$ alone are those of the first run to all the digits shown (0.6480 and 0.3160), their sensors and data unchanged. Correlation costs rank: for a Gaussian with correlation $\\rho$ the singular values of the unfolding (in the plain $L^2$ norm: Mehler\'s formula written in Hermite functions) fall geometrically, by the factor $|\\rho| / (1 + \\sqrt{1 - \\rho^2})$ from one to the next, so $\\rho = -0.56$ needs 14 of them for a relative error of $10^{-7}$; this posterior, not a Gaussian, takes 19. The rounding\'s self-check stays silent (its error below $10^{-3}$), and two others warn: mass within two nodes of the box\'s edge above $10^{-4}$ from $t = 0.92$, and mass carried out of the box — the box $[-4, 4]^4$ cuts the density off there, and a wider one would hold it.',
      },
      {
        label: 'six sensors instead of four',
        change: (c) => {
          const d = 6;
          const each = (f) => Array.from({ length: d }, (_, i) => f(i));
          c.model.drift = each((i) => `-0.4*x${i + 1}`);
          c.model.observation = each((i) => `x${i + 1}^3`);
          c.prior.mean = each(() => 1);
          c.prior.cov = each((i) => each((j) => (i === j ? 0.1 : 0)));
          c.initial_state = each(() => 1);
          c.domain = each(() => [-4, 4]);
        },
        expect: 'a fresh run in six dimensions (the same seed draws a different path): the TT filter holds 960 numbers, $6 \\times 160$, for $160^6 \\approx 1.68 \\cdot 10^{13}$ grid points (134 TB as a full grid), every rank 1 throughout — each dimension adds 160 numbers where a full grid multiplies by 160. MSEs: TT 2.1316, PF(10 000) 2.2937, PF(1000) 2.1024, EKF 5.3858, UKF 5.8585; the EKF and UKF lose $x_1$ (their MSEs of $x_1$ alone 3.55 and 3.50, the TT filter\'s 0.33), and their self-checks warn from $t = 2.15$ that their innovations are larger than their covariances say.',
      },
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
  ['', 'J. C. Cox, J. E. Ingersoll and S. A. Ross, “A theory of the term structure of interest rates”, Econometrica 53(2), 1985.'],
  ['', 'O. Vasicek, “An equilibrium characterization of the term structure”, Journal of Financial Economics 5(2), 1977.'],
  ['', 'M. Zakai, “On the optimal filtering of diffusion processes”, Zeitschrift für Wahrscheinlichkeitstheorie und verwandte Gebiete 11, 1969.'],
  ['', 'R. E. Kalman and R. S. Bucy, “New results in linear filtering and prediction theory”, Journal of Basic Engineering 83, 1961.'],
  ['', 'S. J. Julier and J. K. Uhlmann, “Unscented filtering and nonlinear estimation”, Proceedings of the IEEE 92(3), 2004.'],
  ['', 'N. J. Gordon, D. J. Salmond and A. F. M. Smith, “Novel approach to nonlinear/non-Gaussian Bayesian state estimation”, IEE Proceedings F 140(2), 1993.'],
  ['', 'H. E. Rauch, F. Tung and C. T. Striebel, “Maximum likelihood estimates of linear dynamic systems”, AIAA Journal 3(8), 1965.'],
  ['', 'É. Pardoux, “Équations du filtrage non linéaire, de la prédiction et du lissage”, Stochastics 6(3–4), 1982.'],
  ['', 'S. J. Godsill, A. Doucet and M. West, “Monte Carlo smoothing for nonlinear time series”, Journal of the American Statistical Association 99(465), 2004.'],
  ['', 'G. Kitagawa, “Monte Carlo filter and smoother for non-Gaussian nonlinear state space models”, Journal of Computational and Graphical Statistics 5(1), 1996.'],
  ['', 'M. Šimandl, J. Královec and T. Söderström, “Advanced point-mass method for nonlinear state estimation”, Automatica 42(7), 2006.'],
  ['', 'R. S. Bucy and K. D. Senne, “Digital synthesis of non-linear filters”, Automatica 7(3), 1971.'],
  ['', 'M. S. Arulampalam, S. Maskell, N. Gordon and T. Clapp, “A tutorial on particle filters for online nonlinear/non-Gaussian Bayesian tracking”, IEEE Transactions on Signal Processing 50(2), 2002.'],
  ['', 'N. Metropolis, A. W. Rosenbluth, M. N. Rosenbluth, A. H. Teller and E. Teller, “Equation of state calculations by fast computing machines”, Journal of Chemical Physics 21(6), 1953.'],
  ['', 'W. K. Hastings, “Monte Carlo sampling methods using Markov chains and their applications”, Biometrika 57(1), 1970.'],
  ['', 'H. Haario, E. Saksman and J. Tamminen, “An adaptive Metropolis algorithm”, Bernoulli 7(2), 2001.'],
  ['', 'C. Andrieu and J. Thoms, “A tutorial on adaptive MCMC”, Statistics and Computing 18(4), 2008.'],
  ['', 'C. Andrieu, A. Doucet and R. Holenstein, “Particle Markov chain Monte Carlo methods”, Journal of the Royal Statistical Society B 72(3), 2010.'],
  ['', 'A. Doucet, M. K. Pitt, G. Deligiannidis and R. Kohn, “Efficient implementation of Markov chain Monte Carlo when using an unbiased likelihood estimator”, Biometrika 102(2), 2015.'],
  ['', 'G. Deligiannidis, A. Doucet and M. K. Pitt, “The correlated pseudomarginal method”, Journal of the Royal Statistical Society B 80(5), 2018.'],
  ['', 'A. Vehtari, A. Gelman, D. Simpson, B. Carpenter and P.-C. Bürkner, “Rank-normalization, folding, and localization: an improved R̂ for assessing convergence of MCMC”, Bayesian Analysis 16(2), 2021.'],
  ['', 'R. Bellman, “Adaptive Control Processes: A Guided Tour”, Princeton University Press, 1961.'],
  ['', 'I. V. Oseledets, “Tensor-train decomposition”, SIAM Journal on Scientific Computing 33(5), 2011.'],
  ['', 'S. Li, Z. Wang, S. S.-T. Yau and Z. Zhang, “Solving high-dimensional nonlinear filtering problems using a tensor train decomposition method”, IEEE Transactions on Automatic Control 68, 2023.'],
];
