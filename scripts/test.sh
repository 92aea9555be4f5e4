#!/usr/bin/env bash
# The README's test command: installs what is missing, builds everything, runs all tests
# (Rust unit tests, then the multi-process integration tests in tests/ with independent readers).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
echo "[test] building (release)"
cargo build --release --workspace --all-targets
echo "[test] Rust unit tests"
cargo test --release --workspace
echo "[test] integration tests (real processes, iceoryx2, MCAP read back by the Python mcap package)"
# Recordings are large: keep the temporary files of failed tests only.
.venv/bin/python -m pytest -q -o tmp_path_retention_policy=failed tests/
