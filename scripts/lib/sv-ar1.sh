# Sourced by scripts/bench-fit.sh and scripts/bench-posterior.sh: `sv_ar1 ZAKAI DIR` writes the
# AR(1) stochastic-volatility data and model the fit and posterior benchmarks share —
# DIR/sv.csv, 750 returns simulated from the sv-ar1 preset (particles' values, seed 11), and
# DIR/sv-fit.json, the preset with μ, ρ, σ as parameters (started at −1, 0.9, 0.3, bounded by
# [−3, 1], [0, 0.999], [0.01, 1]; uniform priors on them) and the point-mass filter alone.
sv_ar1() {
  local zakai=$1 dir=$2
  "$zakai" show sv-ar1 | python3 -c '
import json, sys
c = json.load(sys.stdin)
c["time"]["t_final"] = 749.0
json.dump(c, sys.stdout)' > "$dir/sv-truth.json"
  "$zakai" simulate "$dir/sv-truth.json" --seed 11 --format csv --out "$dir/sv.csv"
  python3 -c '
import json, sys
c = json.load(open(sys.argv[1]))
c["parameters"] = {"mu": {"value": -1.0, "bounds": [-3, 1]},
                   "rho": {"value": 0.9, "bounds": [0.0, 0.999]},
                   "sigma": {"value": 0.3, "bounds": [0.01, 1.0]}}
c["model"]["drift"] = ["mu + rho*(x - mu)"]
c["model"]["diffusion"] = [["sigma"]]
c["prior"] = {"kind": "gaussian", "mean": ["mu"], "cov": [["sigma^2/(1 - rho^2)"]]}
c["methods"] = [m for m in c["methods"] if m["method"] == "point_mass"]
json.dump(c, sys.stdout)' "$dir/sv-truth.json" > "$dir/sv-fit.json"
}
