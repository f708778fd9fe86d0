#!/usr/bin/env bash
# The speed target of a maximum-likelihood fit (BENCHMARKS.md, "Maximum-likelihood fits"): both
# noise levels q and r of the cubic-sensor-fit preset, fitted on 1001 measurements (T = 200)
# with the separation filter at its size (200 cells, Δt = 0.01), the EKF and the UKF, by the
# release CLI; and one `zakai filter` run of the same filter on the same data, the cost of one
# likelihood evaluation.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build -q --release -p zakai-cli
zakai=target/release/zakai
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
