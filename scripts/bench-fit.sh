#!/usr/bin/env bash
# The speed target of a maximum-likelihood fit (BENCHMARKS.md, "Maximum-likelihood fits"): both
# noise levels q and r of the cubic-sensor-fit preset, fitted on 1001 measurements (T = 200)
# with the separation filter at its size (200 cells, Δt = 0.01), the EKF and the UKF, by the
# release CLI; and one `zakai filter` run of the same filter on the same data, the cost of one
# likelihood evaluation.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build -q --release -p zakai-cli
zakai="${CARGO_TARGET_DIR:-target}/release/zakai"
dir=target/bench-fit
mkdir -p "$dir"
"$zakai" show cubic-sensor-fit | python3 -c '
import json, sys
c = json.load(sys.stdin)
c["time"]["t_final"] = 200.0
json.dump(c, sys.stdout)' > "$dir/scenario.json"
"$zakai" simulate "$dir/scenario.json" --seed 3 --format csv --out "$dir/obs.csv"
for method in separation ekf ukf; do
  start=$(date +%s.%N)
  "$zakai" fit "$dir/scenario.json" --observations "$dir/obs.csv" --method "$method" --format csv > "$dir/$method.csv"
  end=$(date +%s.%N)
  printf '%-11s %6.2f s   %s\n' "$method" "$(echo "$end - $start" | bc)" "$(tail -n +2 "$dir/$method.csv" | cut -d, -f1-3 | tr '\n' ' ')"
done
start=$(date +%s.%N)
"$zakai" filter "$dir/scenario.json" --observations "$dir/obs.csv" --methods separation --format json > /dev/null
end=$(date +%s.%N)
printf 'one zakai filter run of the separation filter: %.3f s\n' "$(echo "$end - $start" | bc)"

# Issue 61, item 4: the three parameters μ, ρ, σ of the AR(1) stochastic-volatility model
# (the sv-ar1 preset with them unknown, started at −1, 0.9, 0.3) fitted to 750 returns
# simulated from particles' values (seed 11) by the point-mass filter at its 400 cells — by
# L-BFGS on its score (the default) and by Nelder–Mead.
. scripts/lib/sv-ar1.sh
sv_ar1 "$zakai" "$dir"
for optimiser in lbfgs nelder-mead; do
  start=$(date +%s.%N)
  "$zakai" fit "$dir/sv-fit.json" --observations "$dir/sv.csv" --optimiser "$optimiser" > "$dir/sv-$optimiser.txt"
  end=$(date +%s.%N)
  printf 'SV, point-mass, %-11s %6.2f s   %s\n' "$optimiser" "$(echo "$end - $start" | bc)" "$(grep "^ln L" "$dir/sv-$optimiser.txt")"
  sed -n '3,5p' "$dir/sv-$optimiser.txt"
done

# The same returns, the model written as the SDE dx = −κ(x − μ) dt + s dv whose daily
# transition the AR(1) is, fitted by the separation filter at its size (κ, μ, s).
python3 -c '
import json, sys
c = json.load(open(sys.argv[1]))
c["model"].pop("dynamics", None)
c["parameters"] = {"kappa": {"value": 0.1, "bounds": [0.001, 2.0]},
                   "mu": {"value": -1.0, "bounds": [-3, 1]},
                   "s": {"value": 0.3, "bounds": [0.01, 2.0]}}
c["model"]["drift"] = ["-kappa*(x - mu)"]
c["model"]["diffusion"] = [["s"]]
c["prior"] = {"kind": "gaussian", "mean": ["mu"], "cov": [["s^2/(2*kappa)"]]}
c["methods"] = [{"method": "separation"}]
json.dump(c, sys.stdout)' "$dir/sv-fit.json" > "$dir/sv-sde-fit.json"
for optimiser in lbfgs nelder-mead; do
  start=$(date +%s.%N)
  "$zakai" fit "$dir/sv-sde-fit.json" --observations "$dir/sv.csv" --optimiser "$optimiser" > "$dir/sv-sde-$optimiser.txt" 2>/dev/null
  end=$(date +%s.%N)
  printf 'SV as an SDE, separation, %-11s %6.2f s   %s\n' "$optimiser" "$(echo "$end - $start" | bc)" "$(grep "^ln L" "$dir/sv-sde-$optimiser.txt")"
  sed -n '3,5p' "$dir/sv-sde-$optimiser.txt"
done
