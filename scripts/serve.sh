#!/usr/bin/env bash
# Builds the playground and serves the static site target/site on http://127.0.0.1:${PORT:-8080}/
# (the URL is printed).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build-web.sh
exec node web/serve.mjs "${PORT:-8080}" target/site
