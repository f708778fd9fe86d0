#!/usr/bin/env bash
# Issue 64, item 5: effective samples per second of the posterior samplers on the AR(1)
# stochastic-volatility model — μ, ρ, σ unknown (uniform priors on [−3, 1], [0, 0.999],
# [0.01, 1]), 750 returns simulated from `particles`' values (seed 11, as scripts/bench-fit.sh),
# the point-mass filter at its 400 cells — by the release CLI: random-walk Metropolis (4 chains
# × 4500 draws after 500 of warm-up), the same with delayed acceptance screened by the
# point-mass filter on 100 cells (4 × 6000 after 500), and Metropolis-adjusted Langevin steps
# on the filter's score (4 × 1000 after 500); then the particle filter's pseudo-marginal
# samplers, started at the point-mass filter's maximum-likelihood estimate (no fit): PMMH with
# fresh random numbers and correlated pseudo-marginal steps (ρ = 0.99) at 25, 50 and 100
# particles (4 × 5000 after 500). Prints each run's summary (ESS bulk and tail per parameter)
# and wall time (the starting fit included where there is one).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build -q --release -p zakai-cli
zakai="${CARGO_TARGET_DIR:-target}/release/zakai"
dir=target/bench-posterior
mkdir -p "$dir"
. scripts/lib/sv-ar1.sh
sv_ar1 "$zakai" "$dir"
run() {
  local name=$1
  shift
  start=$(date +%s.%N)
  "$zakai" sample "$dir/sv-fit.json" --observations "$dir/sv.csv" --warmup 500 --seed 1 \
    "$@" > "$dir/sv-$name.txt"
  end=$(date +%s.%N)
  printf 'SV posterior, %-18s %7.1f s\n' "$name" "$(echo "$end - $start" | bc)"
  sed -n '1,6p' "$dir/sv-$name.txt"
}
run metropolis --draws 4500
run delayed-acceptance --draws 6000 --surrogate '{"method":"point_mass","cells":[100]}'
run langevin --draws 1000 --sampler langevin
# The particle filter's samplers: the scenario with the PF alone, started at the 400-cell
# point-mass filter's estimate (zakai fit on sv-fit.json: μ = −1.248, ρ = 0.943, σ = 0.180).
for n in 25 50 100; do
  python3 -c '
import json, sys
c = json.load(open(sys.argv[1]))
for k, v in (("mu", -1.248), ("rho", 0.943), ("sigma", 0.180)):
    c["parameters"][k]["value"] = v
c["methods"] = [{"method": "pf", "particles": int(sys.argv[2])}]
json.dump(c, sys.stdout)' "$dir/sv-fit.json" "$n" > "$dir/sv-pf$n.json"
  run_pf() {
    local name=$1
    shift
    start=$(date +%s.%N)
    "$zakai" sample "$dir/sv-pf$n.json" --observations "$dir/sv.csv" --warmup 500 --seed 1 \
      --no-fit --draws 5000 "$@" > "$dir/sv-$name.txt"
    end=$(date +%s.%N)
    printf 'SV posterior, %-18s %7.1f s\n' "$name" "$(echo "$end - $start" | bc)"
    sed -n '1,6p' "$dir/sv-$name.txt"
  }
  run_pf "pmmh-pf$n"
  run_pf "correlated-pf$n" --correlation 0.99
done
