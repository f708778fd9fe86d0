"""What the particle-filter comparisons with `particles` share (growth_pf.py, sv_pf.py): run
each filter `repeats` times on the same data, keep the least time per step and the spread of the
log-likelihood estimates, and print them with the ratio of the times."""

import numpy as np


def compare(title, z, runs, repeats):
    """`runs` is [(name, run)], `run(z, seed)` returning (seconds, log-likelihood); the first
    is the peer, the others Zakai's forms of the same filter."""
    steps = len(z)
    rows = []
    for name, run in runs:
        results = [run(z, seed) for seed in range(repeats)]
        best = min(r[0] for r in results)
        lls = [r[1] for r in results]
        rows.append((name, best / steps * 1e6, np.mean(lls), np.std(lls)))
    print(f"{title}, least of {repeats} runs")
    for name, per_step, ll, sd in rows:
        print(f"{name:<28} {per_step:10.1f} µs/step   ln L {ll:9.3f} (sd over runs {sd:.3f})")
    for name, per_step, _, _ in rows[1:]:
        print(f"ratio particles / {name}: {rows[0][1] / per_step:.2f}")
