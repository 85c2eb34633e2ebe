#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/*_fuzz.cc, clang, ASan + UBSan) and runs each one, seeded with
# small seeds made from the real logs and clips in the shared data folder (scripts/fuzz_seeds.py:
# a few KiB that hold each format's header and definitions) and with small files of every text
# format. Prints, per target, the executions, the wall and CPU time, the executions per CPU second
# and whether anything was found; the same table goes to DIR/fuzz.txt (DIR/campaign.txt).
#
#   scripts/fuzz.sh                      every target for 60 s
#   scripts/fuzz.sh --seconds 600 ulog   one target for 10 minutes
#   scripts/fuzz.sh --runs 10000000      every target until 10 million executions
#   nice scripts/fuzz.sh --campaign      the same, the table also in DIR/campaign.txt (hours: the
#                                        rate of each target is in the table of a short run)
#   scripts/fuzz.sh --smoke              every target for 3000 executions from seed 1 (what CI runs:
#                                        the same inputs on every machine, so it passes or fails alike)
#   scripts/fuzz.sh --build DIR ...      use (or make) the fuzz build in DIR (default build-fuzz)
#
# A crash, leak, hang (> 10 s on one input), an input needing over 2 GB, or a sanitizer report stops
# that target, leaves the input in DIR/artifacts/, and makes the script exit 1. Each such input
# belongs in a regression test. SHUTTERLAB_DATA_DIR overrides ../shared/data; without it the
# targets start from the small text seeds alone.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install_packages.sh fuzz clang libclang-rt-14-dev  # clang and its libFuzzer
limit=(-max_total_time=60)
targets=()
build=build-fuzz
table=
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) limit=(-max_total_time="$2"); shift 2 ;;
    --runs) limit=(-runs="$2"); shift 2 ;;
    --campaign) limit=(-runs=10000000); table=campaign.txt; shift ;;
    --smoke) limit=(-runs=3000 -seed=1); shift ;;
    --build) build="$2"; shift 2 ;;
    -*) echo "fuzz.sh: unknown option $1" >&2; exit 2 ;;
    *) targets+=("$1"); shift ;;
  esac
done
# Ninja for a new build folder, as scripts/setup.sh says.
command -v ninja >/dev/null && export CMAKE_GENERATOR="${CMAKE_GENERATOR:-Ninja}"
if [ ! -f "$build/CMakeCache.txt" ]; then
  CC=clang CXX=clang++ cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DSHUTTERLAB_FUZZ=ON -DSHUTTERLAB_BUILD_TESTS=OFF -DSHUTTERLAB_BUILD_BENCH=OFF \
    -DSHUTTERLAB_PCH=OFF >/dev/null  # no precompiled headers here: a missing #include still fails
else
  # picks up fuzz targets added since it was configured (and a build made before SHUTTERLAB_PCH)
  cmake -S . -B "$build" -DSHUTTERLAB_PCH=OFF >/dev/null
fi
table="$build/${table:-fuzz.txt}"
if [ ${#targets[@]} -eq 0 ]; then
  for src in fuzz/*_fuzz.cc; do targets+=("$(basename "$src" _fuzz.cc)"); done
fi
cmake --build "$build" -j"$(nproc)" --target "${targets[@]/%/_fuzz}" >/dev/null

data="${SHUTTERLAB_DATA_DIR:-../shared/data}"
# Seeds stay small (libFuzzer's -max_len below): every execution reads the whole input.
max_len=8192
seed() {  # seed TARGET MODE FILE...: scripts/fuzz_seeds.py MODE of each file that exists
  local dir="$build/corpus/$1" mode="$2"; shift 2
  mkdir -p "$dir"
  for f in "$@"; do
    [ -f "$f" ] && python3 scripts/fuzz_seeds.py "$mode" "$f" "$dir/$(basename "$f")" "$max_len"
  done
  return 0
}
text_seeds() {  # text_seeds TARGET [PREFIX]: small files of every text format, after PREFIX
  # (the option bytes that some targets read first; printf escapes)
  local dir="$build/corpus/$1" p="${2:-}"
  mkdir -p "$dir"
  printf "${p}"'t,gx,gy,gz\n0,0.1,0.2,0.3\n0.001,0.1,0.2,0.3\n0.004,-1e-3,+2,3.5\n' >"$dir/gyro.csv"
  printf "${p}"'\xef\xbb\xbft,gx,gy,gz,extra\r\n1.5, 0.1 ,0.2,0.3,x\r\n\r\n1.5,0.1,0.2,0.3,y\r\n' >"$dir/gyro_crlf.csv"
  printf "${p}"'0,12,-5,3\n1000,13,-4,3\n2000,32767,-32768,0\n' >"$dir/raw.csv"
  printf "${p}"'time,x,y,z\n0,12,-5,3\n1,13,-4,3\n' >"$dir/raw_header.csv"
  printf "${p}"'GYROFLOW IMU LOG\nversion,1.3\nid,x\norientation,XYZ\ntscale,0.001\ngscale,1\nt,gx,gy,gz\n0,0.1,0.2,0.3\n1,0.1,0.2,0.3\n' >"$dir/log.gcsv"
  printf "${p}"'SOF  10246,  frameNum :1 exp time 0.005\nframeid:1 gyro:0 x 0.003973 y -0.038 z 1e-3 ts 10741\nframeid:2 gyro:0 x 0.003973 y -0.038 z 1e-3 ts 10741\nframeid:2 gyro:1 x 0 y 0 z 0 ts 13167.5\n' >"$dir/gyro_dump.txt"
  printf "${p}"'CAMERA IMU LOG\nversion,1.1\norientation,yXZ\ntscale,1e-6\ngscale,0.0174533\nascale,1\nt,gx,gy,gz,ax,ay,az\n0,1,2,3,0,0,1\n1000,1,2,3,0,0,1\n' >"$dir/camera.gcsv"
}
ulogs=("$data"/gyro/px4_ulog/*.ulg)
dataflash=("$data"/incoming/ardupilot_*/*.bin "$data"/incoming/ardupilot_*/*.BIN)
blackbox=("$data"/gyro/betaflight_blackbox/*)
mp4s=("$data"/rs/gopro_karma/*.mp4 "$data"/incoming_rs/gopro_max_heromode/*.mp4)
for t in "${targets[@]}"; do
  case "$t" in
    ulog) seed ulog ulog "${ulogs[@]}" ;;
    dataflash) seed dataflash dataflash "${dataflash[@]}" ;;
    blackbox) seed blackbox prefix "${blackbox[@]}" ;;
    flight_log)
      seed flight_log ulog "${ulogs[@]}"
      seed flight_log dataflash "${dataflash[@]}"
      seed flight_log prefix "${blackbox[@]}"
      seed flight_log mp4 "${mp4s[@]}"
      text_seeds flight_log ;;
    gyro_csv | gcsv) text_seeds "$t" '\x05' ;;  # blocks of 6 bytes
    gyro_dump)  # blocks of 9 bytes
      text_seeds "$t" '\x20'
      seed gyro_dump prefix "$data"/rs/phone_gyro_video_20200109_145447/gyro_dump.txt ;;
    raw_csv) text_seeds "$t" '\x10' ;;          # 250 deg/s, seconds, blocks of 5 bytes
    mp4) seed mp4 mp4 "${mp4s[@]}" ;;
    gpmf)
      seed gpmf gpmf "${mp4s[@]}"
      printf 'DEVC\x00\x00\x00\x00' >"$build/corpus/gpmf/empty" ;;
    camera_json)
      mkdir -p "$build/corpus/camera_json"
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
      ;;
    lens_profile) seed lens_profile prefix "$data"/incoming_rs/*/reference/*.json ;;
    column_csv)
      seed column_csv prefix "$data"/rs/phone_gyro_video_20200109_145447/gyro.txt
      for f in "$build/corpus/column_csv"/gyro.txt; do  # columns 4,1,2,3, auto delimiter
        [ -f "$f" ] && { printf '\x01\xff'; head -c 4000 "$f"; } >"$f.tmp" && mv "$f.tmp" "$f"
      done
      printf '\x01\x07t;gx;gy;gz\n0;1;2;3\n0.001;1;2;3\n' >"$build/corpus/column_csv/semicolon.csv"
      printf '\x00\x20"time_us","wx","wy","wz"\n1000,0.1,0.2,0.3\n2000,0.1,0.2,0.3\n' >"$build/corpus/column_csv/quoted.csv" ;;
    colmap_model)  # cameras.txt, images.txt, points3D.txt between NUL bytes
      mkdir -p "$build/corpus/colmap_model"
      printf '# Camera list\n1 PINHOLE 160 120 140 140 80 60\n\0# Image list\n1 1 0 0 0 0 0 0 1 images/a.jpg\n10.5 20.5 1 30 40 -1\n2 0.7071 0 0.7071 0 1 2 3 1 b.jpg\n\n\0# 3D points\n1 0.5 1.5 -2 128 128 128 0.4 1 0 2 1\n' >"$build/corpus/colmap_model/model" ;;
    frames_csv)
      mkdir -p "$build/corpus/frames_csv"
      printf 'frame,t,image,ref\n0,0.0,images/frame_000000.png,\n1,0.04,images/frame_000001.png,0\n' >"$build/corpus/frames_csv/frames.csv" ;;
    trigger_file)
      seed trigger_file prefix "$data"/incoming/autel_mrk_helenenschacht/*.mrk "$data"/images/siyi_zr10/image_metadata.csv
      printf 'image,t\nDJI_0001.JPG,12.5\nDJI_0002.JPG,14.25\n' >"$build/corpus/trigger_file/named.csv"
      printf '1\t396015.412566\t[2110]\t-17,N\t11,E\t196,V\t22.5685,Lat\t113.9428,Lon\t-1.473,Ellh\t0.01, 0.01, 0.02\t50,Q\n' >"$build/corpus/trigger_file/dji.MRK" ;;
    validation_report)
      mkdir -p "$build/corpus/validation_report"
      cat >"$build/corpus/validation_report/report.json" <<'JSON'
{"format": "validation/1", "frames": 2, "before": {"rms_px": 1.0, "max_px": 2.0},
 "effects": [{"name": "clock_rate", "value": 30.0, "stderr": 1.0, "unit": "ppm",
              "parameters": [30.0, 0.001], "covariance": [[1.0, null], [null, 1e-8]]}],
 "after": {"rms_px": 0.1, "max_px": 0.2}, "noise_px": 0.1, "unexplained": false,
 "fitted_model": {"camera": {"format": "rig/1", "image": {"width": 64, "height": 48},
   "intrinsics": {"fx": 50, "fy": 50, "cx": 31.5, "cy": 23.5},
   "rolling_shutter": {"readout_s": 0.03}}, "gyro_scale": [1, 1, 1],
   "gyro_bias_rad_s": [0, 0, 0], "clock_rate_ppm": 30.0}}
JSON
      ;;
  esac
done

mkdir -p "$build/artifacts"
failed=0
# The table goes to the terminal and to $table (a campaign's record). CPU time is the fuzzer's own
# (user + system): on a shared machine it, not wall time, says what a target costs.
: >"$table"
row() { printf '%-18s %12s %9s %9s %10s  %s\n' "$@" | tee -a "$table"; }
row target executions "wall s" "CPU s" "exec/CPU s" result
children_cpu() {  # cpu_now: user + system seconds of this shell's finished children (`times`,
  # run in this shell, not in a subshell, which would have children of its own)
  times >"$build/artifacts/times.$$.txt"  # per run: two campaigns may share DIR
  cpu_now=$(awk 'NR == 2 { split($0, f, /[ ms]+/); print f[1] * 60 + f[2] + f[3] * 60 + f[4] }' \
    "$build/artifacts/times.$$.txt")
}
for t in "${targets[@]}"; do
  log="$build/artifacts/$t.log"
  start=$(date +%s.%N)
  children_cpu
  cpu_start=$cpu_now
  if "$build/bin/${t}_fuzz" "${limit[@]}" -max_len=$max_len -timeout=10 -rss_limit_mb=2048 \
      -print_final_stats=1 -artifact_prefix="$build/artifacts/$t-" "$build/corpus/$t" \
      >"$log" 2>&1; then
    result=ok
  else
    result="FOUND (see $log)"
    failed=1
  fi
  seconds=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.0f", b - a }')
  children_cpu
  cpu=$(awk -v a="$cpu_start" -v b="$cpu_now" 'BEGIN { printf "%.2f", b - a }')
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(awk -v n="${execs:-0}" -v s="$cpu" 'BEGIN { printf "%.0f", (s > 0 ? n / s : 0) }')
  row "$t" "${execs:-?}" "$seconds" "$cpu" "$rate" "$result"
done
echo "table written to $table"
exit $failed
