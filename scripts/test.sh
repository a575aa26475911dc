#!/usr/bin/env bash
# The whole test suite: formatting, lints, Rust tests, then the Lua scenario tests on one
# and on two threads.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh --tests
cargo fmt --all -- --check
cargo clippy --workspace --all-targets -- -D warnings
# The default build has the zenoh feature (docs/distributed.md, "Build cost"): linted and
# tested above. The build without it must still compile and lint: a check build (some
# dependencies' features differ without zenoh, so a few are checked again).
cargo clippy -p troupe --no-default-features --all-targets -- -D warnings
cargo test --workspace
# Every Lua file of the repository, checked against the API's definitions (docs/editor.md).
cargo run -q -- lua-defs .tools/lua/troupe.d.lua
"${TROUPE_TOOLS:-$HOME/.cache/troupe-tools}/bin/emmylua_check" .
cargo run -q -- test
# Again with two threads stepping even the smallest scenes (one actor per chunk).
cargo run -q -- test --threads 2 --chunk 1
