#!/usr/bin/env bash
# Installs the system packages troupe needs, only when something is missing (idempotent).
# Headless rendering uses Mesa's llvmpipe through EGL: libegl1, libegl-mesa0, libgl1-mesa-dri.
set -euo pipefail
missing=()
for pkg in libegl1 libegl-mesa0 libgl1-mesa-dri; do
  dpkg -s "$pkg" >/dev/null 2>&1 || missing+=("$pkg")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}" >&2
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  $SUDO DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}"
fi
command -v cargo >/dev/null || { echo "setup: Rust (cargo) is required: https://rustup.rs" >&2; exit 1; }
# The Khronos glTF validator, for the test that checks the glTF files troupe writes
# (runtime/formats/tests/khronos_validator.rs, which is skipped with a note without it).
# Installed from the npm registry only, into .tools/node, once.
GLTF_VALIDATOR=2.0.0-dev.3.10
tools="$(cd "$(dirname "$0")/.." && pwd)/.tools/node"
if command -v npm >/dev/null && [ ! -f "$tools/node_modules/gltf-validator/package.json" ]; then
  echo "setup: installing gltf-validator@$GLTF_VALIDATOR into $tools" >&2
  mkdir -p "$tools"
  npm install --prefix "$tools" --no-save --no-audit --no-fund "gltf-validator@$GLTF_VALIDATOR" >&2 ||
    echo "setup: could not install gltf-validator; its test will be skipped" >&2
fi
# VRPN: the tests in drivers/tests/vrpn_server.rs build the real VRPN server from
# ../shared/vendor/vrpn-07.38.tar.gz (scripts/vrpn-server.sh) and need cmake and g++.
vrpn_missing=()
for pkg in cmake g++; do
  dpkg -s "$pkg" >/dev/null 2>&1 || vrpn_missing+=("$pkg")
done
if ((${#vrpn_missing[@]})); then
  echo "setup: installing ${vrpn_missing[*]} (to build the VRPN server for its tests)" >&2
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${vrpn_missing[@]}"
fi
# Zenoh: tests/zenoh_cli.rs checks a published run with an independent client, the
# `eclipse-zenoh` Python package from PyPI (scripts/zenoh_check.py; the test is skipped
# with a note without it). Installed once, only when missing.
ZENOH_PY=1.10.2
if command -v python3 >/dev/null && ! python3 -c "import zenoh" >/dev/null 2>&1; then
  echo "setup: installing eclipse-zenoh==$ZENOH_PY (PyPI)" >&2
  python3 -m pip install --quiet "eclipse-zenoh==$ZENOH_PY" >&2 ||
    echo "setup: could not install eclipse-zenoh; the Python client test will be skipped" >&2
fi
