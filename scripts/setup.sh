#!/usr/bin/env bash
# Installs everything hubtrack needs on a fresh Debian 12 machine, skipping what is already there:
#   - apt: OpenCV (dev headers), clang/libclang (opencv-rust binding generator), libudev (v4l),
#          libturbojpeg (JPEG frames), nasm (OpenH264's assembly, built from source by the openh264 crate),
#          pkg-config, util-linux (taskset for the 2-core benchmark; unshare and nsenter for the
#          private network ArduCopter SITL flies in), iproute2 (ip, to bring its loopback up)
#   - a Python virtualenv in .venv with the independent test peers (mcap reader, protobuf, pymavlink)
# Safe to run repeatedly. Needs root (or sudo) only when an apt package is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

APT_PACKAGES=(libopencv-dev clang libclang-dev libudev-dev pkg-config util-linux iproute2 python3-venv libturbojpeg0-dev nasm)

missing=()
for p in "${APT_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "[setup] installing apt packages: ${missing[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "[setup] apt packages present"
fi

if [ "${HUBTRACK_SKIP_PYTHON:-0}" != "1" ]; then
  if [ ! -x .venv/bin/python ]; then
    echo "[setup] creating Python virtualenv .venv"
    python3 -m venv .venv
  fi
  if ! .venv/bin/python -c "import mcap, mcap_protobuf, google.protobuf, pymavlink, pytest, cv2, foxglove_schemas_protobuf, websockets" 2>/dev/null; then
    echo "[setup] installing Python test peers into .venv"
    .venv/bin/pip install -q --disable-pip-version-check -r tests/requirements.txt
  fi
fi
echo "[setup] done"
