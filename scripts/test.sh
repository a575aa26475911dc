#!/usr/bin/env bash
# The whole test suite: formatting, lints, Rust tests, then the Lua scenario tests.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cargo fmt --all -- --check
cargo clippy --workspace --all-targets -- -D warnings
cargo test --workspace
cargo run -q -- test
