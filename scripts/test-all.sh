#!/usr/bin/env bash
# The whole test suite of Zakai (the README's test command; .ci/run calls exactly this).
# Installs what a fresh machine lacks: rust targets, wasm-bindgen-cli, npm packages, and
# Debian's chromium for the browser tests.
set -euo pipefail
cd "$(dirname "$0")/.."
# Cargo builds into a cache outside the clone, shared with earlier runs (scripts/cache.sh).
source scripts/cache.sh
# The CLI binary `cargo test --workspace` builds (its test profile is optimised; a release
# build would compile the core a further time for the same results).
export ZAKAI_CLI="$CARGO_TARGET_DIR/debug/zakai"

# Each step prints its title and, when it ends, the seconds it took (the target: under 20 min
# from a fresh clone; BENCHMARKS.md, "The test command", has the measured steps).
last=$SECONDS
step() {
  [ -n "${title:-}" ] && printf '    (%s: %d s)\n' "$title" $((SECONDS - last))
  title=$*; last=$SECONDS
  printf '\n==> %s\n' "$*"
}

# `behind NAME COMMAND…` runs a command in the background, its output kept in
# target/NAME.log; `joined NAME` waits for it, prints that log, and fails like the command
# did. Work that leaves a core idle (one crate's type checking, one node or browser thread)
# runs beside other work this way; nothing is skipped when one side fails.
mkdir -p target
behind() { local name=$1; shift; ("$@") > "target/$name.log" 2>&1 & eval "behind_$name=\$!"; }
joined() {
  local pid_var="behind_$1" status=0
  wait "${!pid_var}" || status=$?
  cat "target/$1.log"
  return "$status"
}
# `timed COMMAND…` runs it and prints its seconds (inside a step of several commands).
timed() { local t=$SECONDS; "$@"; printf '    [%d s] %s\n' $((SECONDS - t)) "$*"; }

step "toolchain targets"
installed=$(rustup target list --installed)
for t in wasm32-unknown-unknown thumbv7em-none-eabihf; do
  grep -qx "$t" <<<"$installed" || rustup target add "$t"
done

step "packaging: rust-version covers the locked dependencies"
python3 scripts/check-rust-version.py

step "cargo fmt --check"
cargo fmt --all --check

step "clippy, docs, no_std, the core's unit tests, and the test build (two lanes)"
# Compiling leaves a core idle for long stretches (one crate's type checking runs on one
# thread), so the checks that share nothing with the test build run beside it, in a target
# directory of their own (two cargo processes on one directory wait for each other's lock);
# what one lane finds fails the step all the same. Each lane prints its own commands' times.
side="$CARGO_TARGET_DIR/side"
side_lane() {
  set -e
  timed cargo clippy -p zakai-wasm -p zakai -p zakai-tests --target wasm32-unknown-unknown \
    --all-targets --target-dir "$side" -- -D warnings
  # The benchmark that times a bare DST reaches it through `zakai::internals` (feature
  # `unstable-internals`, which no other build turns on).
  timed cargo clippy -p zakai --benches --features unstable-internals --target-dir "$side" -- -D warnings
  # No warning in the documentation (broken or private intra-doc links included).
  timed env RUSTDOCFLAGS="-D warnings" cargo doc -q --workspace --no-deps --target-dir "$side"
  # The core without the `std` feature for both targets, up to code generation (`cargo
  # check`: every name, type and borrow; generating its code took a minute here without
  # finding anything a check does not).
  timed cargo check -p zakai --no-default-features --target wasm32-unknown-unknown --target-dir "$side"
  timed cargo check -p zakai --no-default-features --target thumbv7em-none-eabihf --target-dir "$side"
  # The core's unit tests, at opt-level 0 (see core/Cargo.toml: the lib is `test = false` in
  # a workspace-wide run): a build of 25 s instead of the 100 s the second compilation of the
  # crate at opt-level 2 took, for 7 s of tests instead of 0.5.
  timed cargo test -p zakai --lib --features fit --target-dir "$side" \
    --config 'profile.test.package.zakai.opt-level=0'
}
behind side_lane side_lane
timed cargo clippy --workspace --all-targets -- -D warnings
timed cargo test --workspace --no-run
joined side_lane

step "cargo test --workspace"
cargo test --workspace

step "examples (core/examples: own data, models from text and closures)"
# The binaries `cargo test --workspace` above has built (same profile, same features; a
# `cargo run -p zakai` would rebuild the core with the package's own feature set).
for example in core/examples/*.rs; do
  "$CARGO_TARGET_DIR/debug/examples/$(basename "$example" .rs)"
done

step "playground build (wasm package, npm packages)"
bash scripts/build-web.sh

step "the tests in WebAssembly under node (wasm-pack test --node, as a user runs them)"
# The integration tests of tests/ (all but those that read files or start threads, and the
# Monte Carlo reproductions) and the wasm adapter's Session tests (suite/wasm_session.rs: in
# the same build, one compilation of the core for wasm32 instead of two), compiled to wasm32
# and run in node. The core's own unit tests run once, natively, above: compiling them for
# wasm32 took 2.5 minutes for 1.5 s of tests, whose code the integration tests run in wasm
# anyway.
command -v wasm-pack >/dev/null 2>&1 || cargo install wasm-pack --locked
# The integration tests in two halves at once (node runs one test binary at a time on one
# core): the counting-allocator binary and the suite's yau_yau, spectral and missing_data
# modules (about 55, 30, 28 and 20 s under node), beside the rest of the suite (about 120 s). The suite is one binary
# (tests/tests/suite): one link and one wasm-bindgen pass instead of thirty. Heavy checks run
# once, natively: the paper reproductions and point-mass comparisons are marked native-only
# in the suite (`#[cfg(not(target_arch = "wasm32"))]`); their numbers are the core's, which
# wasm computes as native does — the determinism step after this one holds every method of
# every preset to 1e-9 of the native CLI.
# The modules of the first half, one run each (the runner takes one filter); the second half
# skips them.
first_half_modules=(yau_yau spectral missing_data)
wasm_first_half() {
  cd tests
  wasm-pack test --node -- --test allocation
  for module in "${first_half_modules[@]}"; do
    wasm-pack test --node -- --test suite -- "$module::"
  done
}
behind wasm_first_half wasm_first_half
skips=()
for module in "${first_half_modules[@]}"; do skips+=(--skip "$module::"); done
(cd tests && wasm-pack test --node -- --lib --test suite -- "${skips[@]}")
joined wasm_first_half

step "same seed, same truth: native CLI vs wasm; the Python package (wheel, pytest, example)"
# Side by side: the determinism check is one node thread (about 30 s), the Python step
# mostly one Python thread.
behind determinism node tests/web/determinism.mjs
venv="$ZAKAI_CACHE/py-venv"
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/pip" install -q --disable-pip-version-check maturin numpy pytest filterpy pandas statsmodels "dask[distributed]" \
  matplotlib nbformat nbclient ipykernel arviz
rm -f target/wheels/zakai-*.whl
# The test profile (optimised, debug assertions on), whose dependencies the cache already
# holds from the Rust tests; a user's `pip install` builds the release profile.
# python/Cargo.toml asks for the features the workspace's build unified, so the wheel links the
# core that `cargo test --workspace` compiled instead of compiling it again.
"$venv/bin/maturin" build --profile dev -m python/Cargo.toml -o target/wheels 2>&1 | tee target/wheel.log
if grep -q "Compiling zakai v" target/wheel.log; then
  echo "warning: the wheel compiled the core again (about 70 s): the features in python/Cargo.toml no longer match the workspace's build" >&2
fi
"$venv/bin/pip" install -q --disable-pip-version-check --no-deps --force-reinstall target/wheels/zakai-*.whl
ZAKAI_NO_SKIPS=1 "$venv/bin/python" -m pytest -q python/tests
# The docstrings' examples, against the installed package.
"$venv/bin/python" -m pytest -q -p no:cacheprovider --doctest-modules --pyargs zakai
"$venv/bin/python" python/examples/tour.py > /dev/null
joined determinism

step "browser end-to-end tests and the lessons' claims against their own runs (headless chromium)"
if ! command -v chromium >/dev/null 2>&1; then
  if [ "$(id -u)" = 0 ]; then
    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null
  else
    sudo apt-get update -qq && sudo DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null
  fi
fi
node tests/web/imports.mjs
# Two browsers side by side (each keeps about one and a half cores busy: 245 s one after the
# other, 190 s together here).
behind lessons node tests/web/lessons.mjs
node tests/web/e2e.mjs
joined lessons

if [ "${ZAKAI_SOAK:-0}" = 1 ]; then
  step "soak: every 1-D method, 10^6 intervals of the cubic sensor (ZAKAI_SOAK=1)"
  cargo test --release -p zakai-tests --test soak -- --ignored --nocapture
fi

step "all green"
