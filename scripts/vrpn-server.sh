#!/usr/bin/env bash
# Builds the real VRPN server (vrpn_server) from the vendored source once, caches it under
# $CARGO_TARGET_DIR (or target/)/vrpn-07.38/, and prints the binary's path. The VRPN tests
# (drivers/tests/vrpn_server.rs) call this; run scripts/setup.sh --tests first for cmake and g++.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
tarball="${VRPN_TARBALL:-$root/../shared/vendor/vrpn-07.38.tar.gz}"
cache="${CARGO_TARGET_DIR:-$root/target}/vrpn-07.38"
server="$cache/vrpn/build/server_src/vrpn_server"
if [ ! -x "$server" ]; then
  [ -f "$tarball" ] || { echo "vrpn-server: no $tarball" >&2; exit 1; }
  command -v cmake >/dev/null || { echo "vrpn-server: cmake missing (run scripts/setup.sh --tests)" >&2; exit 1; }
  mkdir -p "$cache"
  # A lock, so that tests started at once build it once.
  exec 9>"$cache/.lock"
  flock 9
  if [ ! -x "$server" ]; then
    echo "vrpn-server: building vrpn_server into $cache (once)" >&2
    rm -rf "$cache/vrpn"
    tar xzf "$tarball" -C "$cache"
    cmake -S "$cache/vrpn" -B "$cache/vrpn/build" -DCMAKE_BUILD_TYPE=Release \
      -DVRPN_BUILD_CLIENTS=OFF -DVRPN_BUILD_JAVA=OFF -DVRPN_BUILD_PYTHON=OFF \
      -DVRPN_BUILD_PYTHON_HANDCODED_3X=OFF -DVRPN_USE_HID=OFF -DVRPN_USE_LIBUSB_1_0=OFF >&2
    make -C "$cache/vrpn/build" -j"${CARGO_BUILD_JOBS:-2}" vrpn_server >&2
  fi
fi
echo "$server"
