#!/usr/bin/env bash
# Installs what troupe needs, only when something is missing (idempotent).
# `scripts/setup.sh`: what running troupe needs (headless rendering uses Mesa's llvmpipe
# through EGL: libegl1, libegl-mesa0, libgl1-mesa-dri).
# `scripts/setup.sh --tests` (scripts/test.sh): also the tools the tests check troupe with.
set -euo pipefail
missing=()
for pkg in libegl1 libegl-mesa0 libgl1-mesa-dri; do
  dpkg -s "$pkg" >/dev/null 2>&1 || missing+=("$pkg")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}" >&2
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}"
fi
command -v cargo >/dev/null || { echo "setup: Rust (cargo) is required: https://rustup.rs" >&2; exit 1; }
[ "${1:-}" = "--tests" ] || exit 0
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
# Python tools from PyPI, into one venv in .tools/python, once, each for a test that checks
# troupe against an implementation it does not use (the test is skipped with a note when
# its package is missing): Pinocchio (`pin`), an independent RNEA on troupe's own URDF
# export (runtime/formats/tests/pinocchio_dynamics.rs); python-osc, the VMC compatibility
# check (scripts/vmc/compat.py, run by tests/vmc.rs); junitparser, a JUnit XML reader for
# `troupe test --junit` (tests/test_runner.rs); eclipse-zenoh, the independent Zenoh client
# that checks a published run's postures against its .trk (scripts/zenoh_check.py, run by
# tests/zenoh_cli.rs).
PYTHON_TOOLS=("pin==4.1.0" "python-osc==1.10.2" "junitparser==3.2.0" "eclipse-zenoh==1.10.2")
python_tools="$(cd "$(dirname "$0")/.." && pwd)/.tools/python"
if command -v python3 >/dev/null && ! "$python_tools/bin/python" -c "import pinocchio, pythonosc, junitparser, zenoh" >/dev/null 2>&1; then
  echo "setup: installing ${PYTHON_TOOLS[*]} into $python_tools" >&2
  { [ -x "$python_tools/bin/pip" ] || python3 -m venv "$python_tools"; } >&2 &&
    "$python_tools/bin/pip" install -q --disable-pip-version-check "${PYTHON_TOOLS[@]}" >&2 ||
    echo "setup: could not install the Python test tools; their tests will be skipped" >&2
fi
# emmylua_check (crates.io), the Lua checker scripts/test.sh runs over every Lua file with
# the API's definitions (`troupe lua-defs`). Built once, unoptimised and without debug
# information (about 2 minutes on 2 free cores; a release build took 43 on a busy machine, see
# docs/PERFORMANCE.md; it checks the repository in about a second either way), into a
# folder outside the clone, so that later clones and CI runs on the same machine reuse it:
# $TROUPE_TOOLS, default ~/.cache/troupe-tools.
EMMYLUA_CHECK=0.25.1
troupe_tools="${TROUPE_TOOLS:-$HOME/.cache/troupe-tools}"
if ! "$troupe_tools/bin/emmylua_check" --version 2>/dev/null | grep -q "$EMMYLUA_CHECK"; then
  echo "setup: installing emmylua_check $EMMYLUA_CHECK into $troupe_tools (once; long)" >&2
  CARGO_PROFILE_DEV_DEBUG=0 cargo install --locked --quiet --debug emmylua_check \
    --version "$EMMYLUA_CHECK" --root "$troupe_tools" >&2
fi
