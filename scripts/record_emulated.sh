#!/usr/bin/env bash
# The recorder without hardware, through the command line only: an emulated MPU-9250 playing a
# synthetic 8 kHz flight in real time for 10 s with the writer stalled 300 ms every 2 s, then the
# same trace through the source paper's pause-while-writing scheme, two emulated sensors fused, and
# the recordings read back by `flight`, `noise` and `analyze` against the source traces.
#   scripts/record_emulated.sh [OUT_DIR]      (default /tmp/shutterlab_record; about 25 s)
set -euo pipefail
cd "$(dirname "$0")/.."
shutterlab=${SHUTTERLAB:-build/bin/shutterlab}
out=${1:-/tmp/shutterlab_record}
mkdir -p "$out"
s() { "$shutterlab" "$@"; }
# the first n+1 lines of a gyro.csv: the source's samples that a recording of n rows holds
head_rows() { head -n $(($2 + 1)) "$1"; }
rows() { awk '/^t,gx,gy,gz/ { f = 1; next } f { n++ } END { print n }' "$1"; }

s synth flight --rate 8000Hz --duration 12s --seed 4 --out "$out/flight.csv" >/dev/null
s synth still --rate 8000Hz --duration 12s --seed 5 --out "$out/still.csv" --out2 "$out/still_b.csv" >/dev/null
printf 'image,t\nIMG_0001,2\nIMG_0002,4\nIMG_0003,6\nIMG_0004,8\n' >"$out/triggers_truth.csv"

echo "== 1. real time, 10 s at 8 kHz, ppm 40, the writer stalled 300 ms every 2 s, triggers with bounce"
s record --device "emulate:$out/flight.csv,ppm=40" --duration 10s --stall-writer 300ms@2s \
  --trigger "emulate:$out/triggers_truth.csv,bounce=2" --out "$out/rec.gcsv" --status-every 2s

echo "== 2. the same trace with the source paper's scheme: reading stops 300 ms after every second"
s record --device "emulate:$out/flight.csv" --duration 10s --pause-while-writing 8000@300ms \
  --out "$out/paper.gcsv" | grep -E "samples|gaps|gap:"

echo "== 3. read back (virtual clock, ppm 0): flight and noise tables, recording against source"
s record --device "emulate:$out/flight.csv" --duration 10s --stall-writer 300ms@2s --clock virtual \
  --out "$out/flight_rec.gcsv" >/dev/null
head_rows "$out/flight.csv" "$(rows "$out/flight_rec.gcsv")" >"$out/flight_src.csv"
s flight "$out/flight_src.csv" --window 10.0625ms,20.0625ms >"$out/flight_src.txt"
s flight "$out/flight_rec.gcsv" --window 10.0625ms,20.0625ms >"$out/flight_rec.txt"
diff "$out/flight_src.txt" "$out/flight_rec.txt" && echo "flight tables: identical" || true
echo "the paper's 10 ms / 20 ms windows (whole numbers of periods), source then recording:"
s flight "$out/flight_src.csv" | sed -n 3p
s flight "$out/flight_rec.gcsv" | sed -n 3p
echo "the real-time recording of step 1 (ppm 40), source then recording, first row:"
head_rows "$out/flight.csv" "$(rows "$out/rec.gcsv")" >"$out/rt_src.csv"
s flight "$out/rt_src.csv" --window 10.0625ms,20.0625ms | sed -n 3p
s flight "$out/rec.gcsv" --window 10.0625ms,20.0625ms 2>/dev/null | sed -n 3p
s record --device "emulate:$out/still.csv" --duration 10s --stall-writer 300ms@2s --clock virtual \
  --out "$out/still_rec.gcsv" >/dev/null
head_rows "$out/still.csv" "$(rows "$out/still_rec.gcsv")" >"$out/still_src.csv"
s noise "$out/still_src.csv" >"$out/noise_src.txt"
s noise "$out/still_rec.gcsv" >"$out/noise_rec.txt"
diff "$out/noise_src.txt" "$out/noise_rec.txt" && echo "noise tables: identical" || true

echo "== 4. triggers: analyze on the recording with its trigger file, and on the source with the truth"
s analyze "$out/rec.gcsv" --triggers "$out/rec.triggers.csv" --json >"$out/analyze_rec.json" 2>/dev/null
s analyze "$out/flight.csv" --triggers "$out/triggers_truth.csv" --json >"$out/analyze_src.json" 2>/dev/null
for f in analyze_src analyze_rec; do
  printf '%s:' "$f"
  grep -o '"D_paper_m": [0-9.e-]*' "$out/$f.json" | awk '{ printf " %.5f", $2 }'
  echo
done

echo "== 5. two emulated still sensors (the Pi's two buses) fused: noise --second"
s record --device "emulate:$out/still.csv" --device "emulate:$out/still_b.csv,ppm=-25" --duration 10s \
  --clock virtual --out "$out/pair.gcsv" >/dev/null
s noise "$out/pair.gcsv" --second "$out/pair.2.gcsv" | sed -n '/Fused gain/,$p'

echo "== 6. two emulated sensors on a synthetic flight: the mounting fitted, the fused flight table"
s synth flight --rate 8000Hz --duration 12s --seed 7 --out "$out/fa.csv" --out2 "$out/fb.csv" >/dev/null
s record --device "emulate:$out/fa.csv" --device "emulate:$out/fb.csv,ppm=20" --duration 11s --clock virtual \
  --out "$out/fp.gcsv" >/dev/null
s flight "$out/fp.gcsv" --second "$out/fp.2.gcsv" | head -3
