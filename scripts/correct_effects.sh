#!/usr/bin/env bash
# How well `correct` removes the rolling shutter for every effect of docs/FORMATS.md's table,
# measured against the renderer's exact truth, through the command line only: renders one rig
# dataset per effect (6 frames of 1280x960 over a real aerial photo, f 1100 px, 30 ms readout, 50 m,
# a perfect multirotor-like gyro) with the effect in the truth but not in camera.json, then
#  - corrects with camera.json alone (what ignoring the effect leaves),
#  - corrects with the true model (camera.json plus the effect: `correct --effect`),
#  - runs `validate --report` and corrects with what it fitted (`correct --report`),
# each with `--truth`, and prints per effect the median over frames of D before, D after and the
# rms of what is left, and the residual `correct` predicted from the report.
#   scripts/correct_effects.sh [OUT_DIR] [EFFECTS]   (default /tmp/shutterlab_correct_effects;
#                                                       ~3 min)
# EFFECTS: only these effects' rows, names separated by commas (time_offset,velocity; default all).
set -euo pipefail
cd "$(dirname "$0")/.."
shutterlab=${SHUTTERLAB:-build/bin/shutterlab}
out=${1:-/tmp/shutterlab_correct_effects}
only=${2:-}
effects="time_offset readout_time gyro_to_camera gyro_scale gyro_bias velocity lens_distortion"
effects+=" readout_direction clock_rate"
if [ -n "$only" ]; then
  IFS=, read -ra names <<<"$only"
  [ "${#names[@]}" -gt 0 ] || names=("")
  for name in "${names[@]}"; do
    [[ -n "$name" && " $effects " == *" $name "* ]] ||
      { echo "$0: no effect '$name' in '$only' (names separated by commas, of:" \
          "${effects// /, })" >&2; exit 2; }
  done
fi
mkdir -p "$out"
data=${SHUTTERLAB_DATA_DIR:-../shared/data}
scene=${SCENE:-$data/images/siyi_zr10/IMG_0100.jpg}
[ -f "$scene" ] || { echo "$0: scene $scene not found (set SHUTTERLAB_DATA_DIR or SCENE)" >&2; exit 2; }

cat >"$out/camera.json" <<'JSON'
{"format": "rig/1", "image": {"width": 1280, "height": 960},
 "intrinsics": {"fx": 1100.0, "fy": 1100.0, "cx": 639.5, "cy": 479.5},
 "rolling_shutter": {"readout_s": 0.030, "direction": "top_to_bottom"},
 "scene": {"altitude_m": 50.0}}
JSON
"$shutterlab" synth flight --ideal --rate 1000Hz --duration 30s --seed 3 --out "$out/gyro.csv" >/dev/null
"$shutterlab" synth flight --ideal --rate 1000Hz --duration 120s --seed 3 --out "$out/gyro_long.csv" >/dev/null
printf 'frame,t_first_row\n0,8\n1,12\n2,16\n3,20\n4,24\n5,28\n' >"$out/frames.csv"
printf 'frame,t_first_row\n0,10\n1,30\n2,50\n3,70\n4,90\n5,110\n' >"$out/frames_long.csv"

# median FILE JQ_PATH: the median over frames of a per-frame number of correct.json.
median() { jq "[.frames[] | $2] | sort | .[length / 2 | floor]" "$1"; }

printf '| effect (in the truth, not in camera.json) | D before px | camera.json alone: D / rms px | true model: D / rms px | validate found | fitted: D / rms px | predicted D px (90 %%) |\n'
printf '| --- | --- | --- | --- | --- | --- | --- |\n'
for injection in "time_offset=4ms" "readout_time=36ms" \
    "gyro_to_camera=0.99756405,-0.06975647,0,0.06975647,0.99756405,0,0,0,1" \
    "gyro_scale=1.05,0.95,1.04" "gyro_bias=0.01rad/s,0,0" "velocity=4m/s,0,0" \
    "lens_distortion=-0.05,0.01" "readout_direction=bottom_to_top" "clock_rate=300ppm"; do
  name=${injection%%=*}
  [ -z "$only" ] || [[ ",$only," == *",$name,"* ]] || continue
  gyro="$out/gyro.csv" times="$out/frames.csv"
  if [ "$name" = clock_rate ]; then gyro="$out/gyro_long.csv" times="$out/frames_long.csv"; fi
  ds="$out/$name"
  "$shutterlab" render --scene "$scene" --camera "$out/camera.json" --gyro "$gyro" \
    --frames "$times" --out "$ds" --no-pictures --inject "$injection" >/dev/null
  "$shutterlab" correct "$ds" --out "$ds.declared" --truth --no-pictures --force >/dev/null
  "$shutterlab" correct "$ds" --out "$ds.true" --truth --no-pictures --force \
    --effect "$injection" >/dev/null
  "$shutterlab" validate "$ds" --report "$ds.report.json" >/dev/null
  "$shutterlab" correct "$ds" --out "$ds.fitted" --truth --no-pictures --force \
    --report "$ds.report.json" >/dev/null
  found=$(jq -r '[.effects[] | .name] | join(", ") | if . == "" then "nothing" else . end' \
    "$ds.report.json")
  printf '| `%s` | %.2f | %.3f / %.3f | %.4f / %.4f | %s | %.4f / %.4f | %.4f (%.4f) |\n' \
    "${injection:0:40}" "$(median "$ds.true/correct.json" .truth.D_before_px)" \
    "$(median "$ds.declared/correct.json" .truth.D_px)" \
    "$(median "$ds.declared/correct.json" .truth.rms_px)" \
    "$(median "$ds.true/correct.json" .truth.D_px)" "$(median "$ds.true/correct.json" .truth.rms_px)" \
    "$found" \
    "$(median "$ds.fitted/correct.json" .truth.D_px)" "$(median "$ds.fitted/correct.json" .truth.rms_px)" \
    "$(median "$ds.fitted/correct.json" .D_after_px)" "$(median "$ds.fitted/correct.json" .D_after_p90_px)"
done
