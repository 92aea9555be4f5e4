#!/usr/bin/env bash
# The README's test command: installs what is missing, checks formatting and lints, builds
# everything, runs all tests (Rust unit tests, then the multi-process integration tests in tests/
# with independent readers). Fails on an unformatted file and on any clippy warning.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
echo "[test] formatting (cargo fmt --check)"
cargo fmt --all --check
echo "[test] lints (cargo clippy, warnings are errors)"
cargo clippy --release --workspace --all-targets -- -D warnings
echo "[test] building (release)"
cargo build --release --workspace --all-targets
echo "[test] Rust unit tests"
cargo test --release --workspace
echo "[test] integration tests (real processes, iceoryx2, MCAP read back by the Python mcap package)"
# Recordings are large: keep the temporary files of failed tests only.
.venv/bin/python -m pytest -q -o tmp_path_retention_policy=failed tests/
