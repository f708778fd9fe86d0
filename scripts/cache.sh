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

# One run at a time builds into and tests from the cache: a second run waits for the first
# (an flock on $ZAKAI_CACHE/lock, held until the script ends), so that no run tests binaries
# another run has just rebuilt. A script started by one that holds it (build-web.sh from
# test-all.sh) inherits the lock.
if [ -z "${ZAKAI_CACHE_LOCKED:-}" ] && command -v flock >/dev/null 2>&1; then
  exec 9>"$ZAKAI_CACHE/lock"
  if ! flock -n 9; then
    echo "waiting for another run that uses $ZAKAI_CACHE to finish …" >&2
    flock 9
  fi
  export ZAKAI_CACHE_LOCKED=1
fi

# Cargo decides that a crate of this workspace is up to date by its sources' modification
# times, and a crate's artifact does not depend on where the checkout is: an artifact built
# from another checkout, newer than this one's files, would pass for this checkout's. So the
# first script of a run marks every tracked file of this checkout as modified now: Zakai's own
# crates are always compiled from these sources (as a fresh clone's would be anyway), while
# the registry dependencies — never touched — are reused.
if [ -z "${ZAKAI_CACHE_TOUCHED:-}" ]; then
  git ls-files -z 2>/dev/null | xargs -0 -r touch -c
  export ZAKAI_CACHE_TOUCHED=1
fi
