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
# python-osc, an OSC implementation troupe does not use, for the VMC compatibility check
# (scripts/vmc/compat.py, run by tests/vmc.rs, which is skipped with a note without it).
# Installed from PyPI only, into .tools/python, once.
PYTHON_OSC=1.10.2
pytools="$(cd "$(dirname "$0")/.." && pwd)/.tools/python"
if command -v python3 >/dev/null && [ ! -d "$pytools/pythonosc" ]; then
  echo "setup: installing python-osc==$PYTHON_OSC into $pytools" >&2
  python3 -m pip install --quiet --disable-pip-version-check --target "$pytools" "python-osc==$PYTHON_OSC" >&2 ||
    echo "setup: could not install python-osc; the VMC compatibility test will be skipped" >&2
fi
