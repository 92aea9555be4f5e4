#!/usr/bin/env bash
# The README's main command: installs what is missing, builds, and flies the mission in
# simulation through the real processes — sim (a simulated ArduCopter in GUIDED with a rendered
# GoPro camera) → detect → track → control → MAVLink → sim, recorder on — in real time, from a
# GPS-style start 25–40 m in front of the turbine to a hover 5 m in front of the hub. No camera,
# no autopilot needed. Prints the outcome (final distance, relative yaw, lateral offset, time,
# path length, closest approach to the rotor plane) and where the MCAP recording is.
#   DEMO_SEED=N scripts/demo.sh     another seeded scenario (turbine, start pose, wind)
#   scripts/demo.sh --seeds 3       extra arguments go to `hubtrack fly`
set -euo pipefail
cd "$(dirname "$0")/.."
HUBTRACK_SKIP_PYTHON=1 bash scripts/setup.sh
echo "[demo] building (release; the first build takes ~10 min)"
cargo build --release --workspace --bins
mkdir -p out
exec ./target/release/hubtrack fly --realtime --first-seed "${DEMO_SEED:-1}" --record out/demo-flight.mcap "$@"
