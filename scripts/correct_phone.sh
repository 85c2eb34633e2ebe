#!/usr/bin/env bash
# The loop closed on real footage: the phone clip (20 frames of 800x600 from a car, its own gyro)
# imported, validated, corrected with the fitted model, and the frame-to-frame residual of a
# global-shutter model measured on the frames before and after correction.
#  - before: the imported frames with the corrected dataset's camera.json and gyro.csv (the fitted
#    model, readout 0): what treating the raw frames as global shutter leaves;
#  - after: the corrected frames, the same camera.json and gyro.csv.
# Both through `validate` (video: each frame against the one before, rotation only and with each
# pair's translation); prints both reports' residuals and writes the side-by-side pictures.
#   scripts/correct_phone.sh [OUT_DIR] [FRAMES]   (default /tmp/shutterlab_phone, every frame;
#                                                  ~2 min)
set -euo pipefail
cd "$(dirname "$0")/.."
shutterlab=${SHUTTERLAB:-build/bin/shutterlab}
out=${1:-/tmp/shutterlab_phone}
max_frames=()
if [ -n "${2:-}" ]; then
  [[ "$2" =~ ^[1-9][0-9]*$ ]] || { echo "$0: FRAMES must be a whole number from 1 (got '$2')" >&2; exit 2; }
  max_frames=(--max-frames "$2")
fi
data=${SHUTTERLAB_DATA_DIR:-../shared/data}
clip=$data/rs/phone_gyro_video_20200109_145447
[ -d "$clip" ] || { echo "$0: $clip not found (set SHUTTERLAB_DATA_DIR)" >&2; exit 2; }
mkdir -p "$out"

"$shutterlab" import "$clip" --out "$out/phone" "${max_frames[@]}" >/dev/null
"$shutterlab" validate "$out/phone" --report "$out/phone.json" >"$out/phone_validate.txt"
"$shutterlab" correct "$out/phone" --report "$out/phone.json" --out "$out/corrected" --force \
  | tee "$out/correct.txt"
# The raw frames under the corrected dataset's global-shutter model.
rm -rf "$out/raw_global"
mkdir -p "$out/raw_global"
cp "$out/corrected/camera.json" "$out/corrected/gyro.csv" "$out/phone/frames.csv" "$out/raw_global/"
ln -sfn "$(cd "$out/phone" && pwd)/images" "$out/raw_global/images"
"$shutterlab" validate "$out/raw_global" --report "$out/raw_global.json" >"$out/raw_global.txt"
"$shutterlab" validate "$out/corrected" --report "$out/corrected.json" --out "$out/corrected_plots" \
  >"$out/corrected_validate.txt"

# row LABEL REPORT: the rotation-only and the pair-translation residuals of a report.
row() {
  jq -r --arg what "$1" '"| \($what) | \(.rotation_only.before.rms_px * 1000 | round / 1000) | \(.translation.before.rms_px * 1000 | round / 1000) | \(.translation.noise_px / (2 | sqrt) * 1000 | round / 1000) | \([.translation.effects[] | "\(.name) \(.value)"] | join(", ") | if . == "" then "nothing" else . end) | \(.translation.after.rms_px * 1000 | round / 1000) |"' "$2"
}
echo
echo "| frames, global-shutter model (readout 0) | rotation only: rms px | with pair translation: rms px across the epipolar lines | noise per component px | validate then adds | after px |"
echo "| --- | --- | --- | --- | --- | --- |"
row "as recorded (rolling shutter)" "$out/raw_global.json"
row "corrected" "$out/corrected.json"
jq -r '"fitted rolling-shutter model on the recorded frames (validate on the import): \(.model): rms \(.after.rms_px * 1000 | round / 1000) px, noise per component \(.noise_px / (2 | sqrt) * 1000 | round / 1000) px"' "$out/phone.json"
echo "pictures: $out/corrected/overview.png, residual plots: $out/corrected_plots/"
