#!/usr/bin/env bash
# Trains the learned hub heatmap (libs/detect/src/heat.rs) on the project's own renderer and
# writes libs/detect/models/hubnet.onnx. Rendered frames only: never ../shared/data (it is for
# evaluation).
#
# Data (`hubtrack dataset`): seeds 101, 103, 104 for training and 102 held out, each 1,500
# single frames per distance class with a quarter as many negatives and 20 rendered approach
# flights (every 5th frame): 6,825 frames; seeds 105, 106 with 3,000 frames each from
# 45–250 m (`--beyond`, photos show turbines that far) and 750 negatives. The evaluation seeds
# of `hubtrack eval` and the README (2026, 77, 500; flights 2026, 7, 100, 500, 3000, 4000) are
# not used.
# Training: `scripts/train-hubnet.py` (JAX on the CPU, in its own virtual environment under
# target/; 20 epochs). About 5 minutes of rendering and 17 of training on 2 cores; the held-out
# score is printed every 3 epochs (measured: the peak within one cell of the hub in 97.6 %).
#
# The still photos' heatmap (`detect.default.still_models`, libs/detect/models/hubnet-still.onnx):
#   scripts/train-hubnet.sh still [OUT.onnx] [-- train-hubnet.py options]
# The same data plus seeds 107, 108 with 3,000 photo-like views each (`--photo-like`: 12–250 m,
# from below and above, relative yaw to ±70°, the hub anywhere in the frame, shrubland, wind
# farms) and 750 negatives, 109 held out and scored on its own. About 10 minutes of rendering and
# 25–38 of training (measured: held out 98.4 % on seed 102, 90.1 % on the photo-like views of
# 109, where the video model gets 97.6 % and 66.9 %). Close photo-like views are included
# (`--photo-close`, 5–12 m: seeds 107, 108 with 1,500 each, 109 with 400 held out).
# Then `scripts/train-ranker.sh still`.
# Usage: scripts/train-hubnet.sh [OUT.onnx] [-- train-hubnet.py options]
# Then rebuild (the model is compiled in) and refit the ranker (scripts/train-ranker.sh): the
# ranker's `hub_heat` weight belongs to the model it was fitted with.
#
# The hub crop network (`HubCropNet`, libs/detect/models/hubcrop.onnx):
#   scripts/train-hubnet.sh crop [OUT.onnx] [-- train-hubnet.py options]
# Data: whole working levels (`hubtrack dataset --working`) of seeds 101 and 103 (1,000 frames
# per class, a quarter as many negatives, 10 flights), 105 (2,000 frames from 45–250 m) and 102
# held out; crops are cut at random offsets from the hub while training (15 epochs of 20,000
# crops). About 20 minutes of rendering and 10 of training on 2 cores. It only places the hub
# (no ranker feature), so the ranker needs no refit.
#
# The still photos' crop network (`detect.default.still_models`, libs/detect/models/hubcrop-still.onnx):
#   scripts/train-hubnet.sh crop-still [OUT.onnx] [-- train-hubnet.py options]
# The crop network's data plus whole working levels of photo-like views, seeds 107 (2,500) and
# 108 (3,000), each with a quarter as many negatives; 102 and 109 (800 photo-like views) held out
# (40 epochs of 20,000 crops). About 5 minutes of rendering and 15 of training on 2 cores.
#
# The yaw network (`HubYawNet`, libs/detect/models/hubyaw.onnx):
#   scripts/train-hubnet.sh yaw [OUT.onnx] [-- train-hubnet.py options]
# Data: whole working levels with the relative yaw (`hubtrack dataset --working`) of seeds 111
# and 113 (800 frames per class, 1,200 from 4–8 m with `--close-in`, 15 flights), each seed
# twice: with the thesis turbine and with a turbine of the training family per scene
# (`--turbines training`: the fleet's proportions with tower tops of 2.0–3.0 m and overhangs of
# 3–6 m, `processes/lab/src/turbine_family.rs`); held out, seed 112 (half as many frames) with
# turbines of the fleet outside that family (`--turbines held-out`: thinner or thicker towers,
# longer overhangs). Crops 8 m wide at the hub's distance around the hub, the hub and the
# distance jittered (frames within 3.5–46 m; 24 epochs of 20,000 crops). About 15 minutes of
# rendering and 12 of training on 2 cores. Measured, mean absolute error at 3.5–8 / 8–15 /
# 15–25 / 25–32 / 32–46 m: on the held-out family 5.6 / 4.4 / 3.1 / 3.5 / 4.1° (trained on the
# thesis turbine alone: 6.4 / 4.9 / 4.4 / 4.1 / 5.0°); on the thesis turbine (seed 112 as held
# out with `--turbines thesis`, scored by `train-hubnet.py --evaluate`) 4.9 / 3.9 / 2.5 / 2.6 /
# 2.9° (trained on it alone: 3.9 / 3.4 / 2.2 / 2.2 / 2.6°).
#
# The thesis turbine's yaw network (`detect.default.hub_yaw_thesis_tolerance`,
# libs/detect/models/hubyaw-thesis.onnx):
#   scripts/train-hubnet.sh yaw-thesis [OUT.onnx] [-- train-hubnet.py options]
# The same network trained on the thesis turbine alone (seeds 111 and 113 as above, 112 held out
# with as many frames): held out, mean error 3.9 / 3.4 / 2.2 / 2.2 / 2.6° on the thesis turbine,
# 6.4 / 4.9 / 4.4 / 4.1 / 5.0° on the held-out family. The detector uses it for the thesis
# turbine and the family's network for every other.
#
# The close-range yaw network (`detect.default.hub_yaw_close`, libs/detect/models/hubyaw-close.onnx):
#   scripts/train-hubnet.sh yaw-close [OUT.onnx] [-- train-hubnet.py options]
# The same network and window trained on the frames within 3.5–14 m only: the yaw network's
# seeds 111 and 113 plus seeds 114 and 115 with 4,000 hover views each (`--close-in`, 4–8 m,
# where the approach ends) and 1,000 negatives; 112 held out (24 epochs of 20,000 crops). About
# 5 minutes of rendering and 11 of training on 2 cores (measured: held out, mean error 3.3° at
# 3.5–8 m and 8–15 m, where the whole-range model gets 4.0° and 3.4°; a 12 m window 3.9°, a
# 16 m window 5.8° after 8 epochs: close in, the view is cropped by the frame and the spinner
# shrinks).
set -euo pipefail
cd "$(dirname "$0")/.."
model=frame
case "${1:-}" in crop | crop-still | yaw | yaw-thesis | yaw-close | still) model=$1; shift ;; esac
default_out=libs/detect/models/hubnet.onnx
[ "$model" = still ] && default_out=libs/detect/models/hubnet-still.onnx
[ "$model" = crop ] && default_out=libs/detect/models/hubcrop.onnx
[ "$model" = crop-still ] && default_out=libs/detect/models/hubcrop-still.onnx
[ "$model" = yaw ] && default_out=libs/detect/models/hubyaw.onnx
[ "$model" = yaw-thesis ] && default_out=libs/detect/models/hubyaw-thesis.onnx
[ "$model" = yaw-close ] && default_out=libs/detect/models/hubyaw-close.onnx
out=${1:-$default_out}
shift || true
[ "${1:-}" = "--" ] && shift
# Video frames and still photos have different first pyramid levels
# (`detect.default.box_first_level`): the still photos' models train on frames prepared as
# stills (`hubtrack dataset --stills`). Each kind of set has a folder of its own (named after
# the pyramid), so that sets of the other kind, or of an older pyramid, are not reused.
pyramid=box
stills=()
case "$model" in still | crop-still) pyramid=gauss; stills=(--stills) ;; esac
data=target/hubnet-data/$pyramid
venv=target/hubnet-venv
bin=target/release/hubtrack
[ -x "$bin" ] || cargo build --release -p hubtrack-lab -p hubtrack-supervisor
if [ ! -x "$venv/bin/python" ]; then
  echo "[train-hubnet] creating $venv (jax, optax, onnx, pillow)" >&2
  python3 -m venv "$venv"
  "$venv/bin/pip" install -q "jax[cpu]==0.10.2" "optax==0.2.8" "onnx==1.23.2" "pillow==13.0.0" "numpy==2.4.6"
fi
# Renders a `hubtrack dataset` folder unless it is there already: render DIR DATASET-OPTIONS...
render() {
  local dir=$1
  shift
  if [ ! -s "$dir/labels.jsonl" ]; then
    echo "[train-hubnet] rendering $dir" >&2
    "$bin" dataset -o "$dir" "${stills[@]}" "$@"
  fi
}
if [ "$model" = yaw ]; then
  data=target/hubyaw-data/$pyramid
  mkdir -p "$data"
  for seed in 111 113; do
    render "$data/s$seed" --working --seed "$seed" --per-class 800 --close-in 1200 --flights 15 --turbines thesis
    render "$data/t$seed" --working --seed "$seed" --per-class 800 --close-in 1200 --flights 15 --turbines training
  done
  render "$data/h112" --working --seed 112 --per-class 400 --close-in 600 --flights 8 --turbines held-out
  exec "$venv/bin/python" scripts/train-hubnet.py --model yaw --epochs 24 --out "$out" "$@" \
    "$data/s111" "$data/s113" "$data/t111" "$data/t113" "$data/h112"
fi
if [ "$model" = yaw-thesis ]; then
  data=target/hubyaw-data/$pyramid
  mkdir -p "$data"
  for seed in 111 113 112; do
    render "$data/s$seed" --working --seed "$seed" --per-class 800 --close-in 1200 --flights 15 --turbines thesis
  done
  exec "$venv/bin/python" scripts/train-hubnet.py --model yaw --epochs 24 --out "$out" "$@" \
    "$data/s111" "$data/s113" "$data/s112"
fi
if [ "$model" = yaw-close ]; then
  data=target/hubyaw-data/$pyramid
  mkdir -p "$data"
  for seed in 111 113 112; do
    render "$data/s$seed" --working --seed "$seed" --per-class 800 --close-in 1200 --flights 15
  done
  for seed in 114 115; do
    render "$data/c$seed" --working --seed "$seed" --per-class 0 --close-in 4000 --flights 0
  done
  exec "$venv/bin/python" scripts/train-hubnet.py --model yaw --yaw-window-m 8 --yaw-range-m 3.5 14 --epochs 24 \
    --out "$out" "$@" "$data/s111" "$data/s113" "$data/c114" "$data/c115" "$data/s112"
fi
if [ "$model" = crop ] || [ "$model" = crop-still ]; then
  data=target/hubcrop-data/$pyramid
  mkdir -p "$data"
  for seed in 101 103 102; do
    render "$data/s$seed" --working --seed "$seed" --per-class 1000 --flights 10
  done
  render "$data/b105" --working --seed 105 --per-class 0 --flights 0 --beyond 2000
  if [ "$model" = crop-still ]; then
    render "$data/p107" --working --seed 107 --per-class 0 --flights 0 --photo-like 2500
    render "$data/p108" --working --seed 108 --per-class 0 --flights 0 --photo-like 3000
    render "$data/p109" --working --seed 109 --per-class 0 --flights 0 --photo-like 800
    exec "$venv/bin/python" scripts/train-hubnet.py --model crop --epochs 40 --out "$out" "$@" \
      "$data/s101" "$data/s103" "$data/b105" "$data/p107" "$data/p108" "$data/s102" --held-out "$data/p109"
  fi
  exec "$venv/bin/python" scripts/train-hubnet.py --model crop --epochs 15 --out "$out" "$@" \
    "$data/s101" "$data/s103" "$data/b105" "$data/s102"
fi
mkdir -p "$data"
for seed in 101 103 104 102; do
  render "$data/s$seed" --seed "$seed" --per-class 1500 --flights 20
done
for seed in 105 106; do
  render "$data/b$seed" --seed "$seed" --per-class 0 --flights 0 --beyond 3000
done
photo=()
if [ "$model" = still ]; then
  for seed in 107 108 109; do
    render "$data/p$seed" --seed "$seed" --per-class 0 --flights 0 --photo-like 3000
  done
  # Close photo-like views (5–12 m): inspection photos next to the hub.
  for seed in 107 108; do
    render "$data/q$seed" --seed "$seed" --per-class 0 --flights 0 --photo-close 1500
  done
  render "$data/q109" --seed 109 --per-class 0 --flights 0 --photo-close 400
  photo=("$data/p107" "$data/p108" "$data/q107" "$data/q108")
  set -- --held-out "$data/p109" --held-out "$data/q109" "$@"
fi
# The last folder is held out (and with `still`, p109: photo-like views, scored on their own).
"$venv/bin/python" scripts/train-hubnet.py --out "$out" "$@" \
  "$data/s101" "$data/s103" "$data/s104" "$data/b105" "$data/b106" "${photo[@]}" "$data/s102"
