#!/usr/bin/env bash
# Closing the loop on video, through the command line only: renders one VIDEO rig dataset
# per effect (`render --video`: 16 consecutive rolling-shutter frames of 640x480 at 30 fps over a
# real aerial scene, f 550 px, 30 ms readout, 50 m, a perfect multirotor-like gyro; no reference
# images) with the effect in the truth but not in camera.json, runs `shutterlab validate` on it and
# prints what the rotation-only and the pair-translation loops found, and the halves.
# With CLUTTER="--camera-fixed-patch 0.25 --moving-patch 10m/s" every clip also shows a dashboard over
# its bottom quarter and a car driving across the ground (render/clutter.h): the same effects must
# come out within the same tolerances.
#   scripts/validate_video_effects.sh [OUT_DIR]   (default /tmp/shutterlab_video_effects; ~4 min)
set -euo pipefail
cd "$(dirname "$0")/.."
shutterlab=${SHUTTERLAB:-build/bin/shutterlab}
out=${1:-/tmp/shutterlab_video_effects}
mkdir -p "$out"
# The scene: a real nadir photo from the shared data folder (not in the repository), or SCENE=FILE
# (e.g. one written by `shutterlab scene`).
data=${SHUTTERLAB_DATA_DIR:-../shared/data}
scene=${SCENE:-$data/images/siyi_zr10/IMG_0150.jpg}
[ -f "$scene" ] || { echo "$0: scene $scene not found (set SHUTTERLAB_DATA_DIR or SCENE)" >&2; exit 2; }

cat >"$out/camera.json" <<'EOF'
{"format": "rig/1", "image": {"width": 640, "height": 480},
 "intrinsics": {"fx": 550.0, "fy": 550.0, "cx": 319.5, "cy": 239.5},
 "rolling_shutter": {"readout_s": 0.030, "direction": "top_to_bottom"},
 "gyro_to_camera": [[1,0,0],[0,1,0],[0,0,1]], "time_offset_s": 0.0,
 "scene": {"altitude_m": 50.0}}
EOF
# frames FILE COUNT FIRST_S FPS
frames() {
  awk -v n="$2" -v a="$3" -v fps="$4" \
    'BEGIN { print "frame,t_first_row"; for (i = 0; i < n; i++) printf "%d,%.9f\n", i, a + i / fps }' >"$1"
}
"$shutterlab" synth flight --ideal --rate 1000Hz --duration 20s --seed 3 --out "$out/gyro.csv" >/dev/null
frames "$out/frames.csv" 16 12.6 30        # the flight's liveliest half second (up to 0.8 rad/s)
frames "$out/frames_yaw.csv" 16 11.4 30    # twice the yaw of 12.6 s: for the per-axis scale
frames "$out/frames_long.csv" 50 8 5       # 10 s at 5 fps: the clock's drift grows by 3 ms

# A 4 degree misalignment about the tilted axis (1, 2, -1.5): R = exp([w]x), written out.
misaligned=$(awk 'BEGIN {
  x = 1; y = 2; z = -1.5; n = sqrt(x*x + y*y + z*z); x /= n; y /= n; z /= n
  a = 4 * atan2(0, -1) / 180; c = cos(a); s = sin(a); t = 1 - c
  printf "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g",
    t*x*x + c, t*x*y - s*z, t*x*z + s*y, t*x*y + s*z, t*y*y + c, t*y*z - s*x,
    t*x*z - s*y, t*y*z + s*x, t*z*z + c }')

cases=("none" "time_offset=4ms" "readout_time=36ms" "gyro_to_camera=$misaligned"
       "gyro_to_camera=0,1,0,1,0,0,0,0,-1" "gyro_scale=1.05,0.95,1.04" "gyro_bias=0.01rad/s,0,0"
       "lens_distortion=-0.05,0.01" "readout_direction=bottom_to_top" "clock_rate=300ppm"
       "velocity=2m/s,1m/s,3m/s")
for injection in "${cases[@]}"; do
  name=${injection%%=*}
  [ "$injection" = "gyro_to_camera=0,1,0,1,0,0,0,0,-1" ] && name=gyro_axes
  times="$out/frames.csv"
  [ "$name" = clock_rate ] && times="$out/frames_long.csv"
  [ "$name" = gyro_scale ] && times="$out/frames_yaw.csv"
  inject=()
  [ "$injection" != none ] && inject=(--inject "$injection")
  # shellcheck disable=SC2086  # CLUTTER is a list of flags
  "$shutterlab" render --video --scene "$scene" \
    --camera "$out/camera.json" --gyro "$out/gyro.csv" --frames "$times" --out "$out/$name" \
    --no-pictures "${inject[@]}" ${CLUTTER:-} >/dev/null
  echo "== injected: ${injection:0:60}"
  "$shutterlab" validate "$out/$name" --report "$out/$name.json" |
    sed -n '/^left out before/,/^time:/p' | grep -v '^$' | grep -v '^time:' | tee "$out/$name.txt"
done

# The misalignment's error as an angle, from the report at full precision.
python3 scripts/rotation_error.py "$out/gyro_to_camera.json" "$misaligned"
python3 scripts/rotation_error.py "$out/gyro_axes.json" 0,1,0,1,0,0,0,0,-1
