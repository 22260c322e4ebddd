#!/usr/bin/env bash
# The LeRobot virtualenv that tests/learn/test_lerobot_export.py loads exports with, and in
# which examples/lerobot_round_trip.py trains LeRobot's DiffusionPolicy and evaluates it with
# this package (docs/lerobot.md):
#   bash tests/learn/lerobot_venv.sh [VENV]   (default .ci-lerobot-venv), then
#   IMPACT_LEROBOT_PYTHON=VENV/bin/python python -m pytest tests/learn/test_lerobot_export.py \
#       tests/learn/test_lerobot_round_trip.py
# lerobot 0.4.4 is the newest release for Python 3.11 (0.5+ needs 3.12); it pins torch < 2.11,
# and only torch 2.13 (CPU) installs here, so lerobot goes in without its pins (--no-deps)
# beside torch 2.13 with what its dataset code imports. torchvision 0.28.0 (torch 2.13's) is
# PyPI's CUDA build, whose C ops cannot load on CPU torch (tests/learn/lerobot_load.py declares
# the two op schemas its import needs); torchcodec 0.13.0 decodes the MP4s with the system's
# FFmpeg libraries, installed here with apt when missing.
set -euo pipefail
VENV=${1:-.ci-lerobot-venv}
if ! ldconfig -p | grep 'libavcodec\.so' >/dev/null; then
  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq \
    --no-install-recommends ffmpeg >/dev/null
fi
python3 -m venv "$VENV"
"$VENV/bin/pip" install -q torch==2.13.0
"$VENV/bin/pip" install -q --no-deps lerobot==0.4.4 torchvision==0.28.0 torchcodec==0.13.0
"$VENV/bin/pip" install -q "datasets>=4,<5" "huggingface-hub>=0.34.2,<0.36" "av>=15,<16" \
  "accelerate>=1.10,<2" jsonlines "packaging<26" draccus==0.10.0 einops termcolor deepdiff \
  "imageio[ffmpeg]" pandas pyarrow
# lerobot.policies (the round trip) also imports diffusers and pyserial; then this package
"$VENV/bin/pip" install -q "diffusers>=0.30,<0.50" pyserial
"$VENV/bin/pip" install -q -e "$(cd "$(dirname "$0")/../.." && pwd)[bench]"
# LeRobot's commands (lerobot-eval with the impact_lerobot plugin) import torchvision before
# any plugin loads: a startup hook declares the two op schemas at that import
# (tests/learn/lerobot_torchvision_hook.py; docs/lerobot.md)
SITE=$("$VENV/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
cp "$(dirname "$0")/lerobot_torchvision_hook.py" "$SITE/impact_torchvision_hook.py"
echo "import impact_torchvision_hook" > "$SITE/impact_torchvision_hook.pth"
