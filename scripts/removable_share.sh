#!/usr/bin/env bash
# The source paper's question, asked of the correction: what share of the rolling-shutter
# distortion can a MEMS gyro remove, given its noise, the readout and its sampling rate?
# Through the command line only:
#  - the truth: a multirotor-like flight (`synth flight --ideal`, 8 kHz: the motion itself,
#    vibration included), rendered over a real aerial photo by a 1280x960 camera (f 1100 px, 50 m)
#    with a 10 ms and a 30 ms readout, 10 frames each (8 .. 26 s);
#  - the gyro that corrects: the same flight logged by a calibrated MEMS gyro (no constant bias,
#    scale error or misalignment; `synth`'s white noise, bias instability, rate random walk and
#    250 deg/s quantisation) at 200 Hz, 1 kHz and 4 kHz, with the MPU-9250's noise density
#    (7e-5 rad/s/sqrt(Hz)) and ten times it, and a perfect gyro at 1 kHz (sampling alone);
#  - `correct --truth` with each, the rest of the model exact; D before and after against the
#    exact truth.
# Prints a markdown table: per readout, gyro and rate the median D before and after on the ground,
# the median share of D removed, how many frames exceed 5 cm at 50 m before and after, and what
# `correct` predicted.
#   scripts/removable_share.sh [OUT_DIR] [FRAMES]   (default /tmp/shutterlab_removable, 10 frames a
#                                                    readout; ~5 min)
set -euo pipefail
cd "$(dirname "$0")/.."
shutterlab=${SHUTTERLAB:-build/bin/shutterlab}
out=${1:-/tmp/shutterlab_removable}
frames=${2:-10}
# Frame i at 8 + 2i s: 10 fit in the 30 s flight.
[[ "$frames" =~ ^([1-9]|10)$ ]] ||
  { echo "$0: FRAMES must be a whole number from 1 to 10 (got '$frames')" >&2; exit 2; }
mkdir -p "$out"
data=${SHUTTERLAB_DATA_DIR:-../shared/data}
scene=${SCENE:-$data/images/siyi_zr10/IMG_0150.jpg}
[ -f "$scene" ] || { echo "$0: scene $scene not found (set SHUTTERLAB_DATA_DIR or SCENE)" >&2; exit 2; }

m_per_px=$(awk 'BEGIN { printf "%.6f", 50.0 / 1100.0 }')
"$shutterlab" synth flight --ideal --rate 8000Hz --duration 30s --seed 5 --out "$out/truth.csv" >/dev/null
awk -v n="$frames" 'BEGIN { print "frame,t_first_row"; for (i = 0; i < n; i++) printf "%d,%d\n", i, 8 + 2 * i }' \
  >"$out/times.csv"
# gyro NAME ARGS...: the flight logged by the gyro ARGS describe (calibrated: no constant errors).
gyro() {
  local name=$1
  shift
  [ -f "$out/$name.csv" ] || "$shutterlab" synth flight --duration 30s --seed 5 \
    --const-bias 0 0 0 --scale-error 0 0 0 --misalignment 0 0 0 0 0 0 "$@" \
    --out "$out/$name.csv" >/dev/null
}
gyro perfect_1k --ideal --rate 1000Hz
for rate in 200 1000 4000; do
  gyro "mpu9250_$rate" --rate "${rate}Hz" --noise-density 7e-5rad/s/rtHz
  gyro "mpu9250x10_$rate" --rate "${rate}Hz" --noise-density 7e-4rad/s/rtHz
done

# median FILE JQ_PATH: the median over frames of a per-frame number of correct.json.
median() { jq "[.frames[] | $2] | sort | .[length / 2 | floor]" "$1"; }
# over FILE JQ_PATH: frames whose D (px) exceeds 5 cm on the ground.
over() { jq "[.frames[] | select($2 * $m_per_px > 0.05)] | length" "$1"; }

printf '| readout | gyro | rate | D before cm (median) | D after cm (median) | removed (median) | frames > 5 cm before -> after | predicted D after cm |\n'
printf '| --- | --- | --- | --- | --- | --- | --- | --- |\n'
for readout in 0.010 0.030; do
  ds="$out/ds_$readout"
  cat >"$out/camera_$readout.json" <<JSON
{"format": "rig/1", "image": {"width": 1280, "height": 960},
 "intrinsics": {"fx": 1100.0, "fy": 1100.0, "cx": 639.5, "cy": 479.5},
 "rolling_shutter": {"readout_s": $readout, "direction": "top_to_bottom"},
 "scene": {"altitude_m": 50.0}}
JSON
  # A dataset of another FRAMES (an earlier run into the same OUT_DIR) is rendered again.
  cmp -s "$out/times.csv" "$ds/times.csv" || rm -rf "$ds"
  if [ ! -f "$ds/frames.csv" ]; then
    "$shutterlab" render --scene "$scene" --camera "$out/camera_$readout.json" \
      --gyro "$out/truth.csv" --frames "$out/times.csv" --out "$ds" --no-pictures >/dev/null
    cp "$out/times.csv" "$ds/times.csv"
  fi
  for logged in perfect_1k mpu9250_200 mpu9250_1000 mpu9250_4000 mpu9250x10_200 mpu9250x10_1000 \
      mpu9250x10_4000; do
    # The dataset as this gyro logged it: its gyro.csv, the same images and truth.
    variant="$out/ds_${readout}_$logged"
    mkdir -p "$variant"
    cp "$ds/camera.json" "$ds/frames.csv" "$variant/"
    cp "$out/$logged.csv" "$variant/gyro.csv"
    ln -sfn "$(cd "$ds" && pwd)/images" "$variant/images"
    ln -sfn "$(cd "$ds" && pwd)/truth" "$variant/truth"
    "$shutterlab" correct "$variant" --out "$variant.corrected" --truth --no-pictures --force \
      >/dev/null 2>"$variant.err"
    json="$variant.corrected/correct.json"
    case $logged in
      perfect_1k) words="perfect"; rate=1000 ;;
      mpu9250x10_*) words="10x MPU-9250"; rate=${logged#*_} ;;
      *) words="MPU-9250"; rate=${logged#*_} ;;
    esac
    printf '| %s ms | %s | %s Hz | %.2f | %.3f | %.1f %% | %s -> %s | %.3f |\n' \
      "$(awk -v r="$readout" 'BEGIN { print r * 1000 }')" "$words" "$rate" \
      "$(awk -v d="$(median "$json" .truth.D_before_px)" -v m="$m_per_px" 'BEGIN { print 100 * d * m }')" \
      "$(awk -v d="$(median "$json" .truth.D_px)" -v m="$m_per_px" 'BEGIN { print 100 * d * m }')" \
      "$(jq '[.frames[] | 100 * (1 - .truth.D_px / .truth.D_before_px)] | sort | .[length / 2 | floor]' "$json")" \
      "$(over "$json" .truth.D_before_px)" "$(over "$json" .truth.D_px)" \
      "$(awk -v d="$(median "$json" .D_after_px)" -v m="$m_per_px" 'BEGIN { print 100 * d * m }')"
  done
done
