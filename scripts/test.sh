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
cargo test --release --workspace --all-targets "$@"
