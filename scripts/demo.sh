#!/usr/bin/env bash
# The demo: runs the greeting scene headless and writes what it recorded under out/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cargo run -q --release -- run scripts/examples/greeting.lua \
  --record out/greeting.trk --trace out/greeting.json "$@"
