#!/usr/bin/env bash
# The README's main command: installs what is missing, builds, and runs the demo pipeline on
# built-in data (synthetic camera; no camera, no autopilot needed) for a few seconds, recording
# every channel to an MCAP file whose path and summary it prints.
set -euo pipefail
cd "$(dirname "$0")/.."
HUBTRACK_SKIP_PYTHON=1 bash scripts/setup.sh
echo "[demo] building (release; the first build takes ~10 min)"
cargo build --release --workspace --bins
mkdir -p out
exec ./target/release/hubtrack run --config config/demo.toml --duration "${DEMO_SECONDS:-5}" "$@"
