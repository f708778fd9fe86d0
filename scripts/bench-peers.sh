#!/usr/bin/env bash
# Zakai's baselines against their Python peers, the same work in one run:
# a bootstrap PF with 10^4 particles (NumPy), a 1-D UKF (FilterPy) and a 1-D QIEM step on 2001
# nodes (SciPy's DST), each timed per step; Zakai through `zakai run` (the driver included) and
# from Python (the `zakai` package, per step() call and per run() call).
# Then the same PF in JAX (jit + lax.scan, scripts/peers/jax_pf.py) and the EKF and UKF beside
# dynamax's and cd-dynamax's (scripts/peers/dynamax_kf.py), both in target/jax-venv, and
# the particle filter beside `particles` (Chopin & Papaspiliopoulos 2020) on its growth model
# and its own stochastic-volatility model (scripts/peers/growth_pf.py, sv_pf.py).
# Installs NumPy, SciPy, FilterPy, particles and this checkout's wheel into target/peers-venv.
# Prints tables.
set -euo pipefail
cd "$(dirname "$0")/.."

venv=target/peers-venv
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
fi
# particles needs numpy < 2; pip resolves the four together.
"$venv/bin/python" -c 'import numpy, scipy, filterpy, particles' 2>/dev/null \
  || "$venv/bin/pip" install -q numpy scipy filterpy particles
# Zakai's Python package into the same environment, built from this checkout.
"$venv/bin/pip" install -q maturin
rm -f target/wheels/zakai-*.whl
"$venv/bin/maturin" build -q --release -m python/Cargo.toml -o target/wheels
"$venv/bin/pip" install -q --no-deps --force-reinstall target/wheels/zakai-*.whl
cargo build -q --release -p zakai-cli
# Where cargo put it (CARGO_TARGET_DIR, as the test command sets it, or ./target).
zakai="${CARGO_TARGET_DIR:-target}/release/zakai"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# The scenarios: the cubic-sensor preset changed to the peers' work.
"$zakai" show cubic-sensor-1d > "$work/preset.json"
"$venv/bin/python" - "$work" <<'PY'
import json, sys
work = sys.argv[1]
base = json.load(open(f"{work}/preset.json"))
def scenario(name, change):
    s = json.loads(json.dumps(base))
    s["failure"]["track_loss"] = None
    change(s)
    json.dump(s, open(f"{work}/{name}.json", "w"))
def pf(s):
    s["methods"] = [{"method": "pf", "particles": 10000, "ess_threshold": 1.0, "substeps": 1}]
def ukf(s):
    s["model"]["noise"] = {"kind": "discrete",
                           "mixture": [{"weight": 1.0, "mean": [0.0], "cov": [[0.1]]}]}
    s["methods"] = [{"method": "ukf", "alpha": 0.5, "beta": 2.0, "kappa": 0.0, "substeps": 1}]
def qiem(s):
    s["time"].update(t_final=0.2, dt_obs=1e-4)
    s["methods"] = [{"method": "qiem", "points": [2001], "dt": 1e-4}]
def qiem2d(s):
    # Two independent cubic sensors: dx_i = dv_i, dy_i = x_i^3 dt + dw_i on [-4, 4]^2.
    s["model"].update(drift=["0", "0"], observation=["x1^3", "x2^3"])
    s["prior"].update(mean=[1.0, 1.0], cov=[[0.1, 0.0], [0.0, 0.1]])
    s["initial_state"] = [1.0, 1.0]
    s["domain"] = [[-4.0, 4.0], [-4.0, 4.0]]
    s["time"].update(t_final=0.02, dt_obs=1e-4)
    s["methods"] = [{"method": "qiem", "points": [256, 256], "dt": 1e-4}]
for name, change in [("pf", pf), ("ukf", ukf), ("qiem", qiem), ("qiem2d", qiem2d)]:
    scenario(name, change)
PY

# Zakai: the least seconds per step of three runs (as for the peers).
zakai_step() {
  for _ in 1 2 3; do
    "$zakai" run "$work/$1.json" --format json | "$venv/bin/python" -c \
      'import json,sys; print(json.load(sys.stdin)["methods"][0]["seconds_per_step"])'
  done | sort -g | head -n 1
}
declare -A ours
for w in pf ukf qiem qiem2d; do ours[$w]=$(zakai_step "$w"); done
peers=$("$venv/bin/python" scripts/peers/peers.py)
from_python=$(cd scripts/peers && "../../$venv/bin/python" from_python.py)

"$venv/bin/python" - "$peers" "$from_python" "${ours[pf]}" "${ours[ukf]}" "${ours[qiem]}" "${ours[qiem2d]}" <<'PY'
import json, sys
peers = json.loads(sys.argv[1])
from_python = json.loads(sys.argv[2])
ours = dict(zip(["pf", "ukf", "qiem", "qiem2d"], map(float, sys.argv[3:7])))
names = {
    "pf": ("bootstrap PF, 10^4 particles, resampling every step", "NumPy"),
    "ukf": ("UKF 1-D, z = x^3 + v, predict + update", "FilterPy"),
    "qiem": ("QIEM 1-D, 2001 nodes, dt = 1e-4", "SciPy DST"),
    "qiem2d": ("QIEM 2-D, 256^2 nodes, dt = 1e-4", "SciPy dstn"),
}
print(f"{'work':<54} {'peer':<10} {'peer/step':>12} {'Zakai/step':>12} {'ratio':>8}")
for k, (work, peer) in names.items():
    p, z = peers[k], ours[k]
    print(f"{work:<54} {peer:<10} {p * 1e6:>10.2f}µs {z * 1e6:>10.2f}µs {p / z:>7.1f}×")
print()
print("Zakai called from Python (zakai.Filter): a step() call per observation, or run() over all")
print(f"{'work':<54} {'peer':<10} {'peer/step':>12} {'step()':>10} {'ratio':>7} {'run()':>10} {'ratio':>7}")
for k, (work, peer) in names.items():
    if k not in from_python:
        continue
    p, s, r = peers[k], from_python[k]["step"], from_python[k]["run"]
    print(f"{work:<54} {peer:<10} {p * 1e6:>10.2f}µs {s * 1e6:>8.2f}µs {p / s:>6.1f}× {r * 1e6:>8.2f}µs {p / r:>6.1f}×")
PY

# The JAX PF (jit + lax.scan) in a venv of its own: JAX needs numpy >= 2, `particles` < 2.
jax_venv=target/jax-venv
if [ ! -x "$jax_venv/bin/python" ]; then
  python3 -m venv "$jax_venv"
fi
"$jax_venv/bin/python" -c 'import jax, dynamax, cd_dynamax, filterpy' 2>/dev/null \
  || "$jax_venv/bin/pip" install -q jax dynamax cd-dynamax filterpy
"$jax_venv/bin/pip" install -q --no-deps --force-reinstall target/wheels/zakai-*.whl
jax_pf=$("$jax_venv/bin/python" scripts/peers/jax_pf.py)
kf=$(cd scripts/peers && "../../$jax_venv/bin/python" dynamax_kf.py)
"$venv/bin/python" - "$jax_pf" "${ours[pf]}" <<'PY'
import json, sys
peer, z = json.loads(sys.argv[1])["pf_jax"], float(sys.argv[2])
print()
print(f"{'bootstrap PF, 10^4 particles, resampling every step':<54} {'JAX jit':<10} {peer * 1e6:>10.2f}µs {z * 1e6:>10.2f}µs {peer / z:>7.1f}×")
PY
"$venv/bin/python" - "$kf" <<'PY'
import json, sys
print()
print("EKF and UKF over 500 measurements: dynamax and cd-dynamax (jit, whole series), FilterPy (its Python loop) and Zakai's Filter.run")
print(f"{'work':<54} {'peer':<10} {'peer/step':>12} {'Zakai/step':>12} {'ratio':>8} {'|means gap|':>12}")
for title, rows in json.loads(sys.argv[1]):
    for method, r in rows.items():
        work = f"{method.upper()} {title}"
        for peer, (t, gap) in r["peers"].items():
            print(f"{work[:54]:<54} {peer:<10} {t * 1e6:>10.2f}µs {r['zakai'] * 1e6:>10.2f}µs {t / r['zakai']:>7.1f}× {gap:>12.1e}")
PY

echo
(cd scripts/peers && "../../$venv/bin/python" growth_pf.py)
echo
(cd scripts/peers && "../../$venv/bin/python" sv_pf.py)
