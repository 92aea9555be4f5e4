#!/usr/bin/env bash
# The README's test command: installs what is missing, checks formatting and lints, builds
# everything, runs all tests (Rust unit tests, then the multi-process integration tests in tests/
# with independent readers). Fails on an unformatted file and on any clippy warning.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
echo "[test] formatting (cargo fmt --check)"
cargo fmt --all --check
# One build does both: clippy-driver compiles the workspace's own crates (lints, warnings are
# errors, then code generation as rustc would), dependencies are compiled once by rustc. A
# separate `cargo clippy` would compile every dependency a second time in check mode.
if ! command -v clippy-driver > /dev/null; then
  echo "[test] clippy is missing: installing it (rustup component add clippy)"
  rustup component add clippy
fi
export RUSTC_WORKSPACE_WRAPPER="$(command -v clippy-driver)"
export CLIPPY_ARGS="-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__"
echo "[test] building (release) with lints (clippy, warnings are errors)"
cargo build --release --workspace --all-targets
echo "[test] Rust unit tests"
cargo test --release --workspace
echo "[test] integration tests (real processes, iceoryx2, MCAP read back by the Python mcap package)"
# Recordings are large: keep the temporary files of failed tests only.
.venv/bin/python -m pytest -q -o tmp_path_retention_policy=failed tests/
