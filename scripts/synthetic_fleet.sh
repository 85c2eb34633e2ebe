#!/usr/bin/env bash
# A synthetic fleet for `shutterlab batch`: COUNT multirotor flights (synth flight as PX4 ULogs,
# 1 kHz, a camera trigger every 2 s, 50 m above ground, gusts from calm to rough by seed) in four
# groups, and DIR/fleet.toml listing them.
#   scripts/synthetic_fleet.sh COUNT DIR [DURATION]   (DURATION of each flight, default 60s)
set -euo pipefail
count=$1
dir=$2
duration=${3:-60s}
shutterlab=${SHUTTERLAB:-$(cd "$(dirname "$0")/.." && pwd)/build/bin/shutterlab}
mkdir -p "$dir/logs"
seq 1 "$count" | xargs -P "$(nproc)" -I{} sh -c \
  "\"$shutterlab\" synth flight --format ulog --rate 1kHz --duration $duration --trigger-every 2s \
   --altitude 50m --seed {} --gust-max \$(( 10 + {} % 60 ))deg/s --out \"$dir/logs/f{}.ulg\" >/dev/null"
{
  echo '[defaults]'
  echo 'limit = ["5cm", "10cm"]'
  for i in $(seq 1 "$count"); do
    printf '\n[[item]]\nid = "f%s"\ngroup = "drone-%s"\nlog = "logs/f%s.ulg"\n' "$i" $((i % 4)) "$i"
  done
} >"$dir/fleet.toml"
echo "synthetic_fleet: $count flights in $dir/logs, manifest $dir/fleet.toml"
