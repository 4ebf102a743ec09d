#!/usr/bin/env bash
# Install what the test suite needs on a fresh Debian machine, then run every test.
# Tests are compiled with optimisation (profile.test opt-level = 3): they render images.
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v cargo >/dev/null 2>&1; then
  echo "error: cargo is not installed (https://rustup.rs)" >&2
  exit 1
fi
SUDO=""
if [ "$(id -u)" -ne 0 ] && command -v sudo >/dev/null 2>&1; then SUDO="sudo"; fi
# A C compiler for crates with C parts. Installed only when missing.
if ! command -v cc >/dev/null 2>&1; then
  $SUDO apt-get update -qq && $SUDO apt-get install -y -qq build-essential
fi
# Vulkan for the previewer's tests: the loader, lavapipe (Mesa's software Vulkan) and the
# validation layer; Xvfb (with xauth, which xvfb-run needs) for the windowed mode. Installed
# only when missing; the tests fail without them.
PREVIEW_PACKAGES="libvulkan1 mesa-vulkan-drivers vulkan-validationlayers xvfb xauth"
if ! dpkg -s $PREVIEW_PACKAGES >/dev/null 2>&1; then
  $SUDO apt-get update -qq && $SUDO apt-get install -y -qq $PREVIEW_PACKAGES
fi
# Python 3 for the plugin's ctypes example (plugin/python). Installed only when missing.
if ! command -v python3 >/dev/null 2>&1; then
  $SUDO apt-get update -qq && $SUDO apt-get install -y -qq python3
fi
# A Python virtual environment at $1 under target/ (python3-venv installed if missing).
make_venv() {
  [ -x "$1/bin/python" ] && return
  python3 -m venv "$1" >/dev/null 2>&1 ||
    { $SUDO apt-get install -y -qq python3-venv >/dev/null 2>&1 && python3 -m venv "$1"; }
}
# The farm tests (tests/farm.rs): the Open Job Description CLI (openjd-cli, from PyPI) in a
# virtual environment under target/, and a single-node Slurm (the Debian packages slurm-wlm and
# munge; the test starts and stops its daemons, as root). Without them (no network, not root)
# those tests say so and are skipped; everything else runs.
FARM_PACKAGES="slurm-wlm munge"
if [ "$(id -u)" -eq 0 ] && ! dpkg -s $FARM_PACKAGES >/dev/null 2>&1; then
  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $FARM_PACKAGES; } \
    >/dev/null 2>&1 || echo "note: slurm-wlm and munge could not be installed; the Slurm test is skipped" >&2
fi
openjd_cli() {
  local venv=target/farm-venv
  make_venv "$venv" || return
  if [ -x "$venv/bin/openjd" ] || "$venv/bin/python" -m pip install -q openjd-cli >/dev/null 2>&1; then
    echo "$PWD/$venv/bin/openjd"
  fi
}
WPBGI_OPENJD="$(openjd_cli || true)"
if [ -n "$WPBGI_OPENJD" ]; then
  export WPBGI_OPENJD
else
  unset WPBGI_OPENJD
  echo "note: openjd-cli could not be installed; the Open Job Description test is skipped" >&2
fi
# Intel Open Image Denoise for `render --denoise` (tests/denoise.rs): the library that PyPI's
# pyoidn wheel ships, in a virtual environment under target/, named by WPBGI_OIDN_LIBRARY.
# Without it (no network) that test says so and is skipped.
oidn_library() {
  local venv=target/oidn-venv
  make_venv "$venv" || return
  local lib
  lib=$(ls "$venv"/lib/python3*/site-packages/pyoidn/oidn/lib/libOpenImageDenoise.so.2 2>/dev/null | head -1)
  if [ -z "$lib" ] && "$venv/bin/python" -m pip install -q pyoidn >/dev/null 2>&1; then
    lib=$(ls "$venv"/lib/python3*/site-packages/pyoidn/oidn/lib/libOpenImageDenoise.so.2 2>/dev/null | head -1)
  fi
  [ -n "$lib" ] && echo "$PWD/$lib"
}
if [ -z "${WPBGI_OIDN_LIBRARY:-}" ]; then
  WPBGI_OIDN_LIBRARY="$(oidn_library || true)"
fi
if [ -n "$WPBGI_OIDN_LIBRARY" ]; then
  export WPBGI_OIDN_LIBRARY
else
  unset WPBGI_OIDN_LIBRARY
  echo "note: pyoidn could not be installed; the denoiser's test is skipped" >&2
fi
# The Python package (python/: pyo3, built by maturin) as a user installs it: `pip install
# ./python` in a fresh virtual environment (tests/python_package.rs), with Pixar's usd-core
# beside it for the USD pipeline example. maturin, numpy and usd-core come from PyPI: without
# network those tests say so and are skipped. A build that fails stops here.
wheel_python() {
  local venv=target/wheel-venv
  rm -rf "$venv"
  make_venv "$venv" || return
  "$venv/bin/python" -m pip install -q "maturin>=1.5,<2" numpy >/dev/null 2>&1 || return
  # The package's Rust build shares target/ with the tests (same release profile).
  # maturin's build backend runs the `maturin` the venv installed, so its bin goes on PATH.
  PATH="$PWD/$venv/bin:$PATH" CARGO_TARGET_DIR="$PWD/target" \
    "$venv/bin/python" -m pip install -q --no-build-isolation ./python >&2 ||
    { echo "error: pip install ./python failed" >&2; return 1; }
  "$venv/bin/python" -m pip install -q usd-core >/dev/null 2>&1 ||
    echo "note: usd-core could not be installed; the USD pipeline example's test is skipped" >&2
  echo "$PWD/$venv/bin/python"
}
if WPBGI_WHEEL_PYTHON="$(wheel_python)" && [ -n "$WPBGI_WHEEL_PYTHON" ]; then
  export WPBGI_WHEEL_PYTHON
else
  [ -x target/wheel-venv/bin/maturin ] && exit 1
  unset WPBGI_WHEEL_PYTHON
  echo "note: maturin and numpy could not be installed; the Python package's test is skipped" >&2
fi
cargo test --release --workspace --all-targets "$@"
# The crate documentation's examples (the front door's bake-and-render), which --all-targets
# leaves out.
cargo test --release -p wpbgi --doc "$@"
