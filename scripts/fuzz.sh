#!/usr/bin/env bash
# Runs the cargo-fuzz targets of fuzz/ (nightly toolchain), each for SECONDS (default 600),
# then minimises its corpus in place (fuzz/corpus/<target>, committed). Crashes land in
# fuzz/artifacts/<target>/ and the script exits non-zero; turn each into a regression test.
# Usage: bash scripts/fuzz.sh [SECONDS] [TARGET...]   (targets: expression config_json session)
set -euo pipefail
cd "$(dirname "$0")/../fuzz"
seconds=${1:-600}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(expression config_json session)
command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz
mkdir -p logs
for t in "${targets[@]}"; do
  echo "==> fuzzing $t for ${seconds}s"
  cargo +nightly fuzz run "$t" "corpus/$t" -- \
    -max_total_time="$seconds" -timeout=30 -rss_limit_mb=4096 -print_final_stats=1 \
    >"logs/$t.log" 2>&1 || { tail -40 "logs/$t.log"; exit 1; }
  grep -E "DONE|stat::number_of_executed_units|stat::peak_rss_mb" "logs/$t.log" || true
  cargo +nightly fuzz cmin "$t" "corpus/$t" >"logs/$t-cmin.log" 2>&1
  echo "    corpus: $(ls "corpus/$t" | wc -l) inputs after cmin"
done
