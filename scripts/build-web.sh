#!/usr/bin/env bash
# Builds the playground: the wasm package (release) into web/pkg and web's npm packages,
# installing what a fresh machine lacks (the wasm target, wasm-bindgen-cli of the version in
# Cargo.lock, the npm packages).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/cache.sh

rustup target list --installed | grep -qx wasm32-unknown-unknown \
  || rustup target add wasm32-unknown-unknown

# The CLI must match the wasm-bindgen library version exactly.
want=$(awk '/^name = "wasm-bindgen"$/ { getline; gsub(/version = |"/, ""); print; exit }' Cargo.lock)
have=$(wasm-bindgen --version 2>/dev/null | awk '{print $2}' || true)
if [ "$have" != "$want" ]; then
  echo "installing wasm-bindgen-cli $want (found: ${have:-none})"
  cargo install wasm-bindgen-cli --version "$want"
fi

# The SIMD build (rustfft's wasm SIMD kernels, +simd128) and a scalar fallback for browsers
# without wasm SIMD; the page's worker picks one with WebAssembly.validate. The two compile
# side by side (their own target directories; one crate's type checking leaves a core idle).
mkdir -p target
RUSTFLAGS='--cfg getrandom_backend="wasm_js" -C link-arg=-zstack-size=8388608' cargo build -p zakai-wasm --profile wasm-release \
  --target wasm32-unknown-unknown --no-default-features --target-dir "$CARGO_TARGET_DIR/scalar" \
  > target/scalar-build.log 2>&1 &
scalar=$!
cargo build -p zakai-wasm --profile wasm-release --target wasm32-unknown-unknown
scalar_status=0
wait "$scalar" || scalar_status=$?
cat target/scalar-build.log
[ "$scalar_status" = 0 ]
wasm-bindgen --target web --out-dir web/pkg \
  "$CARGO_TARGET_DIR/wasm32-unknown-unknown/wasm-release/zakai_wasm.wasm"
wasm-bindgen --target web --out-dir web/pkg-scalar \
  "$CARGO_TARGET_DIR/scalar/wasm32-unknown-unknown/wasm-release/zakai_wasm.wasm"

if [ ! -d web/node_modules/uplot ] || [ ! -d web/node_modules/temml ] \
  || [ web/package-lock.json -nt web/node_modules/.package-lock.json ]; then
  (cd web && npm ci --no-audit --no-fund)
fi
# Vendored libraries: the page loads nothing from node_modules at run time.
mkdir -p web/vendor/uplot
cp web/node_modules/uplot/dist/uPlot.esm.js web/node_modules/uplot/dist/uPlot.min.css \
  web/node_modules/uplot/LICENSE web/vendor/uplot/
# Temml renders the lessons' equations to MathML (Learn mode loads it on first use).
mkdir -p web/vendor/temml
cp web/node_modules/temml/dist/temml.mjs web/node_modules/temml/dist/Temml-Local.css \
  web/node_modules/temml/dist/Temml.woff2 web/node_modules/temml/LICENSE web/vendor/temml/

# The static site: one self-contained folder for any static host.
rm -rf target/site
mkdir -p target/site
# Every module of the page (web/*.js: main.js boots the others) and its style.
cp web/index.html web/*.js web/style.css target/site/
cp -r web/vendor target/site/
for pkg in pkg pkg-scalar; do
  mkdir -p "target/site/$pkg"
  cp web/$pkg/zakai_wasm.js web/$pkg/zakai_wasm_bg.wasm "target/site/$pkg/"
done
echo "built web/pkg ($(du -h web/pkg/zakai_wasm_bg.wasm | cut -f1) of wasm) and the static site target/site ($(du -sh target/site | cut -f1))"
