# Sourced by the set-up scripts (build-web.sh, test-all.sh): the cache outside the clone that
# every checkout on this machine shares, ZAKAI_CACHE (default ~/.cache/zakai).
#
# Cargo builds into $ZAKAI_CACHE/target (CARGO_TARGET_DIR overrides it): a fresh clone then
# compiles Zakai's own crates again — their sources are new to Cargo — but not the
# dependencies an earlier run compiled for the same profile, target and features. Cargo's own
# fingerprints decide what is reused, so a reused artifact is the one a clean build would make.
# Incremental compilation is off (CARGO_INCREMENTAL overrides it): a fresh clone gains nothing
# from it, and its files are gigabytes. The test command keeps its Python virtual environment
# there too ($ZAKAI_CACHE/py-venv).
export ZAKAI_CACHE="${ZAKAI_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/zakai}"
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$ZAKAI_CACHE/target}"
export CARGO_INCREMENTAL="${CARGO_INCREMENTAL:-0}"
mkdir -p "$CARGO_TARGET_DIR" target
