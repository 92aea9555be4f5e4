#!/usr/bin/env bash
# Regenerates recordings/demo.mcap: a small sample made by the project itself (synthetic camera,
# 640x480, 1.5 s at 10 fps, zstd). Run after `cargo build --release --workspace`.
set -euo pipefail
cd "$(dirname "$0")/.."
rm -f recordings/demo.mcap
./target/release/hubtrack run --config config/demo.toml \
  --set capture.synthetic.camera=usb --set capture.fps=10 --set capture.max_frames=15 \
  --set capture.synthetic.noise_sigma=0 --set capture.synthetic.path_duration_s=2 \
  --set capture.synthetic.start_distance_m=30 --set capture.synthetic.end_distance_m=20 \
  --record recordings/demo.mcap --duration 10
