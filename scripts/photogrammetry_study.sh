#!/usr/bin/env bash
# docs/photogrammetry.md's table: scripts/photogrammetry.sh on four flights (calm at 5 m/s, gusty
# at 5 m/s, gusty at 10 m/s, and without rotation at 10 m/s) at two readouts (10 and 30 ms),
# 640x480 photos, 12 a flight; then one line per flight and readout. A flight whose
# OUT/NAME/table.md exists, flown with the same survey options, is not flown again (a rerun only
# prints). About 4 minutes a flight on
# 2 cores.
#
#   scripts/photogrammetry_study.sh OUT [NAME [survey options...]]
#
# NAME (e.g. gusty_5mps_30ms): only that flight and readout; the survey options go to each of its
# photogrammetry.sh runs (e.g. --width 320 --height 240 --focal-px 280 --photos-per-line 4).
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:?usage: scripts/photogrammetry_study.sh OUT [NAME [survey options...]]}"
only="${2:-}"
shift $(($# < 2 ? $# : 2))
case "$only" in
  "" | calm_5mps_10ms | calm_5mps_30ms | gusty_5mps_10ms | gusty_5mps_30ms | gusty_10mps_10ms | \
    gusty_10mps_30ms | none_10mps_10ms | none_10mps_30ms) ;;
  *) echo "$0: no flight '$only' (calm_5mps_10ms .. none_10mps_30ms: WIND_SPEEDmps_READOUTms)" >&2
     exit 2 ;;
esac
mkdir -p "$out"
for flight in "calm 5" "gusty 5" "gusty 10" "none 10"; do
  read -r wind speed <<<"$flight"
  for readout in 10 30; do
    name="${wind}_${speed}mps_${readout}ms"
    [ -z "$only" ] || [ "$name" = "$only" ] || continue
    # A flight flown with other survey options (an earlier run into the same OUT) is flown again.
    options="$*"
    flown_with=$(cat "$out/$name.options" 2>/dev/null || true)
    if [ ! -f "$out/$name/table.md" ] || [ "$flown_with" != "$options" ]; then
      echo "flying $name" >&2
      rm -rf "$out/$name"
      scripts/photogrammetry.sh "$out/$name" --wind "$wind" --speed "${speed}m/s" \
        --readout "${readout}ms" "$@" >"$out/$name.log" 2>&1
      printf '%s\n' "$options" >"$out/$name.options"
    fi
  done
done
/usr/bin/python3 - "$out" <<'PY'
import json, os, re, sys
out = sys.argv[1]
print("| flight | readout | D median px | centre horizontal cm: global / rolling / corrected / readout +20 % / ODM's | points median cm: the same |")
print("| --- | --- | --- | --- | --- |")
def order(name):  # calm, gusty, none; then by speed and readout
    wind, speed, readout = name.split("_")
    return (["calm", "gusty", "none"].index(wind), float(speed[:-3]), float(readout[:-2]))
names = [n for n in os.listdir(out) if os.path.isfile(os.path.join(out, n, "table.md"))]
for name in sorted(names, key=order):
    wind, speed, readout = name.split("_")
    survey = open(os.path.join(out, name, "survey.txt")).read()
    d_median = re.search(r"D median ([0-9.]+) px", survey).group(1)
    scores = [json.load(open(os.path.join(out, name, "colmap_%s" % v, "score.json")))
              for v in ("global", "rolling", "corrected", "wrong", "odm")]
    def row(key):
        return " / ".join("%.2f" % (100 * s[key]) if s["registered"] == s["photos"]
                          else "%.2f (%d of %d)" % (100 * s[key], s["registered"], s["photos"])
                          for s in scores)
    print("| %s, %s m/s | %s ms | %s | %s | %s |" % (
        "no rotation" if wind == "none" else wind, speed.replace("mps", ""), readout.replace("ms", ""), d_median,
        row("horizontal_rms_m"), row("point_median_m")))
PY
