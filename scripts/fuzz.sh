#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/*_fuzz.cc, clang, ASan + UBSan) and runs each one, seeded with
# prefixes of the real logs and clips in the shared data folder and with small files of every text
# format. Prints, per target, the executions, the time and whether anything was found.
#
#   scripts/fuzz.sh                      every target for 60 s
#   scripts/fuzz.sh --seconds 600 ulog   one target for 10 minutes
#   scripts/fuzz.sh --runs 10000000      every target until 10 million executions
#   scripts/fuzz.sh --smoke              every target for 10 s (what CI runs)
#
# A crash, leak, hang (> 10 s on one input) or sanitizer report stops that target, leaves the input
# in build-fuzz/artifacts/, and makes the script exit 1. Each such input belongs in a regression
# test. SHUTTERLAB_DATA_DIR overrides ../shared/data; without it the targets start from the small
# seeds alone.
set -euo pipefail
cd "$(dirname "$0")/.."
limit=(-max_total_time=60)
targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) limit=(-max_total_time="$2"); shift 2 ;;
    --runs) limit=(-runs="$2"); shift 2 ;;
    --smoke) limit=(-max_total_time=10); shift ;;
    -*) echo "fuzz.sh: unknown option $1" >&2; exit 2 ;;
    *) targets+=("$1"); shift ;;
  esac
done
build=build-fuzz
if [ ! -f "$build/CMakeCache.txt" ]; then
  CC=clang CXX=clang++ cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DSHUTTERLAB_FUZZ=ON -DSHUTTERLAB_BUILD_TESTS=OFF -DSHUTTERLAB_BUILD_BENCH=OFF >/dev/null
fi
if [ ${#targets[@]} -eq 0 ]; then
  for src in fuzz/*_fuzz.cc; do targets+=("$(basename "$src" _fuzz.cc)"); done
fi
cmake --build "$build" -j"$(nproc)" --target "${targets[@]/%/_fuzz}" >/dev/null

data="${SHUTTERLAB_DATA_DIR:-../shared/data}"
# Seeds: the first 64 KiB of each real file (headers, format definitions and some records; a
# whole 3 MB log would make every execution slow), and tiny files of the text formats.
seed() {  # seed TARGET FILE...
  local dir="$build/corpus/$1"; shift
  mkdir -p "$dir"
  for f in "$@"; do
    [ -f "$f" ] && head -c 65536 "$f" >"$dir/$(basename "$f")"
  done
  return 0
}
text_seeds() {  # small files of every text format the log reader detects
  local dir="$build/corpus/$1"
  mkdir -p "$dir"
  printf 't,gx,gy,gz\n0,0.1,0.2,0.3\n0.001,0.1,0.2,0.3\n' >"$dir/gyro.csv"
  printf '0,12,-5,3\n1000,13,-4,3\n' >"$dir/raw.csv"
  printf 'GYROFLOW IMU LOG\nversion,1.3\nid,x\norientation,XYZ\ntscale,0.001\ngscale,1\nt,gx,gy,gz\n0,0.1,0.2,0.3\n1,0.1,0.2,0.3\n' >"$dir/log.gcsv"
}
seed ulog "$data"/gyro/px4_ulog/*.ulg
seed dataflash "$data"/incoming/ardupilot_*/*.bin "$data"/incoming/ardupilot_*/*.BIN
seed blackbox "$data"/gyro/betaflight_blackbox/*
seed flight_log "$data"/gyro/px4_ulog/*.ulg "$data"/incoming/ardupilot_*/*.bin "$data"/gyro/betaflight_blackbox/*
text_seeds flight_log
seed mp4 "$data"/rs/gopro_karma/*.mp4 "$data"/incoming_rs/gopro_max_heromode/*.mp4
seed gpmf
printf 'DEVC\x00\x00\x00\x00' >"$build/corpus/gpmf/empty"
seed camera_json
cat >"$build/corpus/camera_json/camera.json" <<'JSON'
{"format": "rig/1", "image": {"width": 1280, "height": 960},
 "intrinsics": {"fx": 1100.0, "fy": 1100.0, "cx": 639.5, "cy": 479.5},
 "distortion": {"k1": 0.01, "k2": 0.0, "p1": 0.0, "p2": 0.0, "k3": 0.0},
 "rolling_shutter": {"readout_s": 0.030, "direction": "top_to_bottom"},
 "gyro_to_camera": [[1,0,0],[0,1,0],[0,0,1]], "time_offset_s": 0.0,
 "scene": {"altitude_m": 50.0}, "velocity_mps": [0.0, 0.0, 0.0]}
JSON
cat >"$build/corpus/camera_json/fisheye.json" <<'JSON'
{"format": "rig/1", "image": {"width": 848, "height": 480},
 "intrinsics": {"fx": 368.7, "fy": 370.8, "cx": 424.2, "cy": 238.8},
 "distortion": {"model": "fisheye", "k1": 0.0646, "k2": 0.0391, "k3": -0.0414, "k4": 0.0149},
 "rolling_shutter": {"readout_s": 0.0206, "direction": "top_to_bottom"}}
JSON
seed lens_profile "$data"/incoming_rs/*/reference/*.json
seed column_csv "$data"/rs/phone_gyro_video_20200109_145447/gyro.txt
printf '\x01t;gx;gy;gz\n0;1;2;3\n0.001;1;2;3\n' >"$build/corpus/column_csv/semicolon.csv"
seed frames_csv
printf 'frame,t,image,ref\n0,0.0,images/frame_000000.png,\n1,0.04,images/frame_000001.png,0\n' >"$build/corpus/frames_csv/frames.csv"

mkdir -p "$build/artifacts"
failed=0
printf '%-12s %14s %9s  %s\n' target executions seconds result
for t in "${targets[@]}"; do
  log="$build/artifacts/$t.log"
  start=$(date +%s.%N)
  if "$build/bin/${t}_fuzz" "${limit[@]}" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
      -artifact_prefix="$build/artifacts/$t-" "$build/corpus/$t" >"$log" 2>&1; then
    result=ok
  else
    result="FOUND (see $log)"
    failed=1
  fi
  seconds=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { print b - a }')
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  printf '%-12s %14s %9.0f  %s\n' "$t" "${execs:-?}" "$seconds" "$result"
done
exit $failed
