#!/usr/bin/env bash
# The demo: runs the greeting scene headless and writes under out/ what it recorded
# (postures as .trk, the action timeline as Chrome trace JSON) and PNG frames of it.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cargo run -q --release -- run scripts/examples/greeting.lua \
  --record out/greeting.trk --trace out/greeting.json \
  --frames out/greeting-frames --every 10 "$@"
