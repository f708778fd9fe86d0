// The `zakai` CLI the browser and determinism tests compare with: ZAKAI_CLI, else the one the
// test command's `cargo test` builds into the shared cache (scripts/cache.sh).
const cache = process.env.ZAKAI_CACHE ?? `${process.env.XDG_CACHE_HOME ?? `${process.env.HOME}/.cache`}/zakai`;
export const cli = process.env.ZAKAI_CLI ?? `${process.env.CARGO_TARGET_DIR ?? `${cache}/target`}/debug/zakai`;
