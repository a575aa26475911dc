#!/usr/bin/env bash
# What the `zenoh` feature costs to build, side by side in one run: a clean dev build of
# the troupe binary without the feature, then the same target folder with it, so the
# second row is what Zenoh adds (docs/distributed.md, "Build cost").
#
#   scripts/bench/build_cost.sh [EMPTY_TARGET_FOLDER]      (default: a new temporary folder)
#
# CPU seconds (user + system) are the figure to compare: wall time depends on what else
# the machine runs, so the load average is printed beside it.
set -euo pipefail
cd "$(dirname "$0")/../.."
target=${1:-$(mktemp -d)}
mkdir -p "$target"
if [ -n "$(ls -A "$target")" ]; then
    echo "build_cost.sh: $target is not empty; a clean build needs an empty target folder" >&2
    exit 1
fi
export CARGO_TARGET_DIR=$target CARGO_INCREMENTAL=0
echo "| build | CPU | wall (load average before → after) | peak memory | binary | stripped | crates |"
echo "|---|---:|---:|---:|---:|---:|---:|"
row() {
    local label=$1
    shift
    local load_before
    load_before=$(cut -d' ' -f1 /proc/loadavg)
    /usr/bin/time -f "%U %S %e %M" -o "$target/time.txt" cargo build -q --bin troupe "$@"
    local user sys wall rss
    read -r user sys wall rss <"$target/time.txt"
    local load="$load_before → $(cut -d' ' -f1 /proc/loadavg)"
    local binary=$target/debug/troupe
    strip -o "$target/troupe.stripped" "$binary"
    local crates
    # Each crate once: a repeated subtree is printed with a trailing "(*)".
    crates=$(cargo tree -q -e normal,build --prefix none "$@" | sed 's/ (\*)$//' | sort -u | wc -l)
    awk -v l="$label" -v u="$user" -v s="$sys" -v w="$wall" -v la="$load" -v m="$rss" \
        -v b="$(stat -c %s "$binary")" -v st="$(stat -c %s "$target/troupe.stripped")" \
        -v c="$crates" 'BEGIN {
            printf "| %s | %.0f s (%.0f user + %.0f system) | %.0f s (%s) | %.1f GB | %.0f MiB | %.0f MiB | %d |\n",
                l, u + s, u, s, w, la, m / 1048576, b / 1048576, st / 1048576, c }'
}
row "clean, \`--no-default-features\` (no Zenoh)" --no-default-features
row "then with \`zenoh\` (what it adds)"
