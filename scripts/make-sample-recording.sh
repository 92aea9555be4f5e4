#!/usr/bin/env bash
# Regenerates the sample recordings made by the project itself. Run after
# `cargo build --release --workspace`.
#  - recordings/demo.mcap: the camera alone (synthetic camera, 640x480, 1.5 s at 10 fps, JPEG
#    frames), as `config/demo.toml` records it;
#  - recordings/flight.mcap: a simulated flight with every channel (JPEG frames with the
#    detector's overlay, frame headers with the truth, detections, track, setpoints, vehicle
#    states, stage status, recorder counters): sim -> detect -> track -> control over MAVLink,
#    lock-step, 960x540 at 15 fps, 6 s.
set -euo pipefail
cd "$(dirname "$0")/.."
export HUBTRACK_DOMAIN="sample-$$"
rm -f recordings/demo.mcap recordings/flight.mcap
./target/release/hubtrack run --config config/demo.toml \
  --set capture.synthetic.camera=usb --set capture.fps=10 --set capture.max_frames=15 \
  --set capture.synthetic.noise_sigma=0 --set capture.synthetic.path_duration_s=2 \
  --set capture.synthetic.start_distance_m=30 --set capture.synthetic.end_distance_m=20 \
  --record recordings/demo.mcap --duration 10
port=$(python3 -c 'import socket; s=socket.socket(socket.AF_INET, socket.SOCK_DGRAM); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
./target/release/hubtrack run --record recordings/flight.mcap --duration 120 \
  --set 'run.stages=["sim","detect","track","control","recorder"]' \
  --set 'sim.pace="lockstep"' --set 'control.clock="sim"' \
  --set "control.link=\"udpin:127.0.0.1:$port\"" --set "sim.link=\"udpout:127.0.0.1:$port\"" \
  --set sim.seed=5 --set sim.max_time_s=6
