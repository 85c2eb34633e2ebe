#!/usr/bin/env bash
# Closing the loop on every candidate effect, through the command line only: renders one rig dataset
# per effect (8 frames of 1280x960 over a real aerial photo, f 1100 px, 30 ms readout, 50 m, a
# perfect multirotor-like gyro) with the effect in the truth but not in camera.json, runs
# `shutterlab validate` on it and prints what was injected next to what the loop found.
#   scripts/validate_effects.sh [OUT_DIR]      (default /tmp/shutterlab_effects; about 2 minutes)
set -euo pipefail
cd "$(dirname "$0")/.."
shutterlab=${SHUTTERLAB:-build/bin/shutterlab}
out=${1:-/tmp/shutterlab_effects}
mkdir -p "$out"
# The scene: a real nadir photo from the shared data folder (not in the repository), or SCENE=FILE
# (e.g. one written by `shutterlab scene`).
data=${SHUTTERLAB_DATA_DIR:-../shared/data}
scene=${SCENE:-$data/images/siyi_zr10/IMG_0100.jpg}
[ -f "$scene" ] || { echo "$0: scene $scene not found (set SHUTTERLAB_DATA_DIR or SCENE)" >&2; exit 2; }

cat >"$out/camera.json" <<'EOF'
{"format": "rig/1", "image": {"width": 1280, "height": 960},
 "intrinsics": {"fx": 1100.0, "fy": 1100.0, "cx": 639.5, "cy": 479.5},
 "rolling_shutter": {"readout_s": 0.030, "direction": "top_to_bottom"},
 "gyro_to_camera": [[1,0,0],[0,1,0],[0,0,1]], "time_offset_s": 0.0,
 "scene": {"altitude_m": 50.0}}
EOF
# frames FILE FIRST_S LAST_S: 8 frame times spread evenly.
frames() {
  awk -v a="$2" -v b="$3" 'BEGIN { print "frame,t_first_row"; for (i = 0; i < 8; i++) printf "%d,%.6f\n", i, a + (b - a) * i / 7 }' >"$1"
}
"$shutterlab" synth flight --ideal --rate 1000Hz --duration 30s --seed 3 --out "$out/gyro.csv" >/dev/null
"$shutterlab" synth flight --ideal --rate 1000Hz --duration 120s --seed 3 --out "$out/gyro_long.csv" >/dev/null
frames "$out/frames.csv" 8 28
frames "$out/frames_long.csv" 10 110

# A 4 degree misalignment about the tilted axis (0.5, -0.3, 0.81): R = exp([w]x), written out.
misaligned=$(awk 'BEGIN {
  x = 0.5; y = -0.3; z = 0.81; n = sqrt(x*x + y*y + z*z); x /= n; y /= n; z /= n
  a = 4 * atan2(0, -1) / 180; c = cos(a); s = sin(a); t = 1 - c
  printf "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g",
    t*x*x + c, t*x*y - s*z, t*x*z + s*y, t*x*y + s*z, t*y*y + c, t*y*z - s*x,
    t*x*z - s*y, t*y*z + s*x, t*z*z + c }')

cases=("none" "time_offset=4ms" "readout_time=36ms" "gyro_to_camera=$misaligned"
       "gyro_scale=1.05,0.95,1.04" "gyro_bias=0.01rad/s,0,0" "velocity=4m/s,0,0" "lens_distortion=-0.05,0.01"
       "readout_direction=bottom_to_top" "clock_rate=300ppm")
for injection in "${cases[@]}"; do
  name=${injection%%=*}
  gyro="$out/gyro.csv" times="$out/frames.csv"
  if [ "$name" = clock_rate ]; then gyro="$out/gyro_long.csv" times="$out/frames_long.csv"; fi
  inject=()
  [ "$injection" != none ] && inject=(--inject "$injection")
  "$shutterlab" render --scene "$scene" --camera "$out/camera.json" \
    --gyro "$gyro" --frames "$times" --out "$out/$name" --no-pictures "${inject[@]}" >/dev/null
  echo "== injected: ${injection:0:60}"
  "$shutterlab" validate "$out/$name" --report "$out/$name.json" |
    sed -n '/^closing the loop/,/^  after:/p' | tee "$out/$name.txt"
done

# The misalignment's error as an angle, from the report at full precision.
python3 scripts/rotation_error.py "$out/gyro_to_camera.json" "$misaligned"
