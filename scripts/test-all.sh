#!/usr/bin/env bash
# The whole test suite of Zakai (README's test command; .ci/run calls exactly this).
set -euo pipefail
cd "$(dirname "$0")/.."

step() { printf '\n==> %s\n' "$*"; }

step "toolchain targets"
installed=$(rustup target list --installed)
for t in wasm32-unknown-unknown thumbv7em-none-eabihf; do
  grep -qx "$t" <<<"$installed" || rustup target add "$t"
done

step "cargo fmt --check"
cargo fmt --all --check

step "cargo clippy --all-targets -- -D warnings"
cargo clippy --workspace --all-targets -- -D warnings

step "cargo test --workspace"
cargo test --workspace

step "no_std builds of the core"
cargo build -p zakai --no-default-features --target wasm32-unknown-unknown
cargo build -p zakai --no-default-features --target thumbv7em-none-eabihf

step "wasm adapter builds for the browser"
cargo build -p zakai-wasm --target wasm32-unknown-unknown

step "all green"
