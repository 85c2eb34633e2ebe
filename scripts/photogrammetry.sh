#!/usr/bin/env bash
# What correcting the rolling shutter buys in a reconstruction (docs/photogrammetry.md): one
# survey with exact truth (`shutterlab survey`), reconstructed by COLMAP (Debian's, CPU SIFT, its
# own command line) five ways, each scored against the truth (`shutterlab score`):
#   global shutter   the survey's references (every row from the middle row's pose)
#   rolling shutter  the photos as recorded
#   corrected        `shutterlab correct --photos` with the log and the true camera
#   readout +20 %    the same with the readout 20 % too long (the sensitivity)
#   ODM's treatment  OpenSfM's rs_correct as ODM runs it, reproduced (scripts/odm_rs_correct.py):
#                    the rolling-shutter reconstruction's observations moved by each photo's
#                    recorded speed (translation only), then matched and mapped again
# COLMAP gets the known camera (`shutterlab export --to colmap`) and keeps it fixed; a corrected
# folder's masks (pixels with no source) go to its feature extractor.
#
#   scripts/photogrammetry.sh OUT [survey options...]    e.g. --readout 10ms --speed 8m/s
#
# SHUTTERLAB_BIN: the shutterlab binary (default build/bin/shutterlab). Writes OUT/survey, OUT/corrected and OUT/wrong (the corrections), OUT/colmap_<variant>/ (COLMAP's
# database, sparse model, text model, score.json) and
# prints a Markdown table, also in OUT/table.md; OUT/centres.svg plots each photo's camera-centre
# error along the flight (scripts/photogrammetry_plot.py). COLMAP's mapper draws at random: a second run
# differs in the last digits.
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:?usage: scripts/photogrammetry.sh OUT [survey options...]}"
shift
bin="${SHUTTERLAB_BIN:-build/bin/shutterlab}"  # the tests give their build's
export QT_QPA_PLATFORM=offscreen  # COLMAP's command line without a display
mkdir -p "$out"
export GLOG_log_dir="$out"  # COLMAP's and Ceres' log files (glog) in OUT, not left in /tmp
threads=$(nproc)
"$bin" survey --out "$out/survey" "$@" >"$out/survey.txt"
cat "$out/survey.txt"
readout_s=$(/usr/bin/python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['rolling_shutter']['readout_s'])" "$out/survey/truth/camera.json")
readout_ms=$(/usr/bin/python3 -c "print('%g' % round(float('$readout_s') * 1e3, 4))")
wrong_ms=$(/usr/bin/python3 -c "print('%g' % round(float('$readout_s') * 1.2e3, 4))")
"$bin" correct --photos "$out/survey/images" "$out/survey/flight.ulg" \
  --camera "$out/survey/truth/camera.json" --out "$out/corrected" >/dev/null 2>&1
"$bin" correct --photos "$out/survey/images" "$out/survey/flight.ulg" \
  --camera "$out/survey/truth/camera.json" --readout "${wrong_ms}ms" --out "$out/wrong" \
  >/dev/null 2>&1
"$bin" export "$out/survey/truth/camera.json" --to colmap --out "$out/colmap_camera" >/dev/null 2>&1
read -r -a camera <"$out/colmap_camera/colmap_args.txt"

extract() {  # extract NAME IMAGES [MASKS]: COLMAP's features with the known camera
  local dir="$out/colmap_$1" images="$2" masks="${3:-}"
  rm -rf "$dir" && mkdir -p "$dir"
  local mask_args=()
  [ -n "$masks" ] && mask_args=(--ImageReader.mask_path "$masks")
  colmap feature_extractor --database_path "$dir/db.db" --image_path "$images" "${camera[@]}" \
    "${mask_args[@]}" --SiftExtraction.use_gpu 0 --SiftExtraction.num_threads "$threads" \
    >"$dir/log.txt" 2>&1
}

match_and_map() {  # match_and_map NAME IMAGES: matches, maps, converts and scores
  local dir="$out/colmap_$1" images="$2"
  rm -rf "$dir/sparse" "$dir/text" && mkdir -p "$dir/sparse" "$dir/text"
  colmap exhaustive_matcher --database_path "$dir/db.db" --SiftMatching.use_gpu 0 \
    --SiftMatching.num_threads "$threads" >>"$dir/log.txt" 2>&1
  colmap mapper --database_path "$dir/db.db" --image_path "$images" --output_path "$dir/sparse" \
    --Mapper.ba_refine_focal_length 0 --Mapper.ba_refine_principal_point 0 \
    --Mapper.ba_refine_extra_params 0 --Mapper.num_threads "$threads" >>"$dir/log.txt" 2>&1
  # The largest model (the mapper numbers them 0, 1, ...: 0 is the first and usually the only).
  colmap model_converter --input_path "$dir/sparse/0" --output_path "$dir/text" \
    --output_type TXT >>"$dir/log.txt" 2>&1
  "$bin" score "$out/survey" "$dir/text" --json >"$dir/score.json"
}

reconstruct() {  # reconstruct NAME IMAGES [MASKS]
  extract "$@"
  match_and_map "$1" "$2"
}

# ODM's --rolling-shutter, reproduced (scripts/odm_rs_correct.py): the rolling-shutter
# reconstruction, aligned to the photos' positions as OpenSfM's is by their GPS; its observations
# moved by each photo's recorded speed (translation only), the rest dropped; matched and mapped again.
odm_reproduction() {
  local dir="$out/colmap_odm" first="$out/colmap_rolling"
  rm -rf "$dir" && mkdir -p "$dir/aligned" "$dir/aligned_text"
  awk -F, 'NR > 1 { print $1, $6, $7, $8 }' "$out/survey/truth/photos.csv" >"$dir/positions.txt"
  colmap model_aligner --input_path "$first/sparse/0" --output_path "$dir/aligned" \
    --ref_images_path "$dir/positions.txt" --ref_is_gps 0 --alignment_type custom \
    --robust_alignment 0 >"$dir/log.txt" 2>&1
  colmap model_converter --input_path "$dir/aligned" --output_path "$dir/aligned_text" \
    --output_type TXT >>"$dir/log.txt" 2>&1
  cp "$first/db.db" "$dir/db.db"
  /usr/bin/python3 scripts/odm_rs_correct.py "$dir/db.db" "$dir/aligned_text" \
    "$out/survey/images" "$readout_ms" >>"$dir/log.txt" 2>&1
  match_and_map odm "$out/survey/images"
}

reconstruct global "$out/survey/reference"
reconstruct rolling "$out/survey/images"
reconstruct corrected "$out/corrected/images" "$out/corrected/masks"
reconstruct wrong "$out/wrong/images" "$out/wrong/masks"
odm_reproduction

/usr/bin/python3 - "$out" "$wrong_ms" <<'PY' | tee "$out/table.md"
import json, sys
out, wrong_ms = sys.argv[1], sys.argv[2]
rows = [("global shutter (reference)", "global"), ("rolling shutter", "rolling"),
        ("corrected", "corrected"), ("corrected, readout %s ms (+20 %%)" % wrong_ms, "wrong"),
        ("ODM's --rolling-shutter (reproduced: translation only)", "odm")]
print("| photos | registered | reprojection px | centre horizontal cm | centre vertical cm | orientation deg | points: median cm | points: RMS cm |")
print("| --- | --- | --- | --- | --- | --- | --- | --- |")
for label, name in rows:
    s = json.load(open("%s/colmap_%s/score.json" % (out, name)))
    print("| %s | %d of %d | %.3f | %.2f | %.2f | %.4f | %.2f | %.2f |" % (
        label, s["registered"], s["photos"], s["mean_reprojection_error_px"],
        100 * s["horizontal_rms_m"], 100 * s["vertical_rms_m"], s["orientation_rms_deg"],
        100 * s["point_median_m"], 100 * s["point_rms_m"]))
PY
/usr/bin/python3 scripts/photogrammetry_plot.py "$out" "$*"  # OUT/centres.svg
