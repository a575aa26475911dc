#!/usr/bin/env bash
# The whole test suite: formatting, lints, Rust tests, then the Lua scenario tests on one
# and on two threads. How long each part takes, and why it is arranged so:
# docs/PERFORMANCE.md, "The clean CI run".
set -euo pipefail
cd "$(dirname "$0")/.."

# The logs of the runs in the background; removed however the script ends.
setup_log="$(mktemp)"
one="$(mktemp)"
two="$(mktemp)"
trap 'rm -f "$setup_log" "$one" "$two"' EXIT
# Waits for run PID, then prints TITLE and the run's log FILE; fails as the run did.
report() {
  local pid=$1 file=$2 title=$3 status=0
  wait "$pid" || status=1
  echo "$title:"
  cat "$file"
  return "$status"
}

# The set-up (system packages, and the tools the tests check troupe with) runs beside
# formatting and compiling, which need none of it: building emmylua_check fills the core
# that the workspace's chain of crates leaves idle. Its output is shown when it ends.
scripts/setup.sh --tests >"$setup_log" 2>&1 &
setup_pid=$!

cargo fmt --all -- --check

# Clippy lints our crates while they are compiled for the tests: clippy-driver is the
# compiler of the workspace's own crates, as under `cargo clippy`, with warnings denied.
# `cargo clippy` would check every dependency once more (a check does not reuse a
# build); here each is compiled once. The lints are the same: a lint or a warning fails
# the build, and so this script.
sysroot="$(rustc --print sysroot)"
clippy_driver="$sysroot/bin/clippy-driver"
[ -x "$clippy_driver" ] || { echo "test: clippy is required (rustup component add clippy)" >&2; exit 1; }
export RUSTC_WORKSPACE_WRAPPER="$clippy_driver"
export CLIPPY_ARGS="-Dwarnings"
# Every target of the default build (benches and examples too, as `cargo clippy
# --all-targets` lints them).
cargo test --workspace --all-targets --no-run
# The default build has the zenoh feature (docs/distributed.md, "Build cost"). The build
# without it must still compile and lint: `cargo clippy` of that package, a check build.
# Zenoh turns on features of dependencies that the rest shares (serde's, rustix's…), so
# without it most of them, wgpu and mlua among them, differ: building them took 17 min
# of a clean run, checking them 3 (docs/PERFORMANCE.md). Being a check, it also leaves
# the default build's binary in place for the tests.
cargo clippy -p troupe --no-default-features --all-targets -- -D warnings
# The API docs: every intra-doc link resolves and no public item's doc links to a private
# one. It reuses that check build of the dependencies: seconds.
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --workspace --no-default-features

report "$setup_pid" "$setup_log" "scripts/setup.sh --tests" ||
  { echo "test: scripts/setup.sh --tests failed" >&2; exit 1; }

# Every Rust test. cargo-nextest runs the tests of all the binaries side by side, each in
# its own process (`cargo test` runs one binary at a time, and many of its tests wait on
# sockets and child processes): 179 s instead of 246 s. It runs no doctests: `cargo test
# --doc` does. Where nextest is not installed, `cargo test` runs them all.
if cargo nextest --version >/dev/null 2>&1; then
  cargo nextest run --workspace
  cargo test --workspace --doc
else
  cargo test --workspace --no-fail-fast
fi
# The `troupe` binary the integration tests just ran (their CARGO_BIN_EXE_troupe), where
# scripts/vrpn-server.sh finds the target folder too. Not `cargo run`: without the other
# crates' dev-dependencies some dependencies resolve to other features (regex-syntax
# without Unicode, for one), and `cargo run` would compile them and every crate above
# them once more.
troupe="${CARGO_TARGET_DIR:-target}/debug/troupe"
[ -x "$troupe" ] || { echo "test: no troupe binary at $troupe" >&2; exit 1; }

# Every Lua file of the repository, checked against the API's definitions (docs/editor.md).
"$troupe" lua-defs .tools/lua/troupe.d.lua
"${TROUPE_TOOLS:-$HOME/.cache/troupe-tools}/bin/emmylua_check" .

# The scenario tests, on one thread and again on two stepping even the smallest scenes
# (one actor per chunk): both runs at once, since the one-thread run leaves a core free.
# Each run's report is printed whole when it ends, and either failing fails the script.
"$troupe" test >"$one" 2>&1 &
one_pid=$!
"$troupe" test --threads 2 --chunk 1 >"$two" 2>&1 &
two_pid=$!
status=0
report "$one_pid" "$one" "troupe test (1 thread)" || status=1
report "$two_pid" "$two" "troupe test --threads 2 --chunk 1" || status=1

# A release build records the postures the golden test pins, as the tests' build does:
# with the compiler's default sixteen codegen units a release build's walks depended on
# the directory it was built in (docs/navigation.md, "Determinism"). Without the zenoh
# feature, which no example needs: about 4 minutes of a clean run.
cargo build --release --no-default-features
release="$(realpath "${CARGO_TARGET_DIR:-target}/release/troupe")"
# `--workspace`, as the test build above: alone, the root package's dev-dependencies
# resolve some shared dependencies to other features (regex-syntax, zenoh's crates), and
# cargo compiled them and every crate above them again, 2 min 31 s of the clean run.
TROUPE_GOLDEN_BIN="$release" cargo test --workspace --test golden || status=1
exit "$status"
