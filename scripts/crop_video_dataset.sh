#!/usr/bin/env bash
# Cuts a video rig dataset (docs/FORMATS.md) to its top ROWS rows, to check that a verdict does not
# depend on the rows below (a car's dashboard, landing gear in view):
#  - every image frames.csv names, cut with oiiotool (openimageio-tools, installed by setup.sh);
#  - camera.json: height ROWS, readout_s times ROWS / height (each row keeps its time), the
#    principal point unchanged (the top-left pixel is the same); a mask is cut alike;
#  - import.json (when there is one): the readout_s claim scaled the same way.
# A readout fitted on the cut dataset is the cut rows' time: times height / ROWS for the full frame.
#   scripts/crop_video_dataset.sh DATASET ROWS OUT
set -euo pipefail
dataset=${1:?usage: scripts/crop_video_dataset.sh DATASET ROWS OUT}
rows=${2:?usage: scripts/crop_video_dataset.sh DATASET ROWS OUT}
out=${3:?usage: scripts/crop_video_dataset.sh DATASET ROWS OUT}
[ -f "$dataset/camera.json" ] || { echo "crop_video_dataset: $dataset: no camera.json" >&2; exit 2; }
[ -e "$out" ] && { echo "crop_video_dataset: $out exists" >&2; exit 2; }
command -v oiiotool >/dev/null || { echo "crop_video_dataset: oiiotool not found" >&2; exit 2; }
mkdir -p "$out"
cp "$dataset/gyro.csv" "$dataset/frames.csv" "$out/"
width=$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["image"]["width"])' \
  "$dataset/camera.json")
images=$(tail -n +2 "$dataset/frames.csv" | cut -d, -f4 | sort -u)
for image in $images $(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1])).get("mask", ""))' \
    "$dataset/camera.json"); do
  mkdir -p "$out/$(dirname "$image")"
  oiiotool "$dataset/$image" --cut "${width}x${rows}+0+0" -o "$out/$image"
done
/usr/bin/python3 - "$dataset" "$out" "$rows" <<'EOF'
import json, os, sys
dataset, out, rows = sys.argv[1], sys.argv[2], int(sys.argv[3])
camera = json.load(open(os.path.join(dataset, "camera.json")))
scale = rows / camera["image"]["height"]
if not 0 < scale <= 1:
    sys.exit(f"crop_video_dataset: ROWS must be 1..{camera['image']['height']}")
camera["image"]["height"] = rows
camera["rolling_shutter"]["readout_s"] *= scale
json.dump(camera, open(os.path.join(out, "camera.json"), "w"), indent=2)
record_path = os.path.join(dataset, "import.json")
if os.path.exists(record_path):
    record = json.load(open(record_path))
    for claim in record.get("claims", []):
        if claim.get("what") == "readout_s":
            claim["value"] *= scale
            claim["source"] = claim.get("source", "") + f" (scaled to the top {rows} rows)"
    json.dump(record, open(os.path.join(out, "import.json"), "w"), indent=2)
EOF
echo "crop_video_dataset: wrote $out (the top $rows rows)"
