#!/usr/bin/env bash
# scripts/odm_rs_correct.py (ODM's rolling-shutter treatment, reproduced) against a known answer:
# a pinhole camera (f 1000 px, 1000 x 800) at (1, 2, 5) m turned 90 degrees about its view
# (cam_from_world = Rz(90)), flying east at 10 m/s (its XMP: FlightYSpeed 10), readout 30 ms.
# The point (16, -3, 55) m, 50 m in front of it, projects to (600, 700); it is observed at
# (601, 699), 1 px off. Row 699 was read 11.2125 ms after the middle row, so the camera is moved
# back by 11.2125 cm east, which its turn shows along y: the point reprojects to (600, 702.2425),
# and the observation moves by that difference to (601, 701.2425). (A wrong centre, rotation or
# update each gives another answer.) An observation of no point is dropped with its descriptor; a
# photo outside the model keeps its features; the matches are cleared; a photo without a flight
# speed is refused (exit 2).
set -euo pipefail
fail() { echo "FAIL: $*" >&2; exit 1; }
script="$(cd "$(dirname "$0")/../.." && pwd)/scripts/odm_rs_correct.py"
work=$(mktemp -d "${TMPDIR:-/tmp}/odm_rs_correct_test.XXXXXX")
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/model" "$work/images"
xmp() {  # xmp FILE EAST_MPS: a stand-in photo whose bytes hold DJI's XMP speeds
  printf '<x:xmpmeta><rdf:Description drone-dji:FlightXSpeed="+0.00" drone-dji:FlightYSpeed="%s" drone-dji:FlightZSpeed="-0.00"/></x:xmpmeta>' "$2" >"$1"
}
xmp "$work/images/a.jpg" +10.00
xmp "$work/images/b.jpg" +10.00
cat >"$work/model/cameras.txt" <<'EOF'
# Camera list with one line of data per camera:
1 PINHOLE 1000 800 1000 1000 500 400
EOF
cat >"$work/model/images.txt" <<'EOF'
# Image list with two lines of data per image:
1 0.7071067811865476 0 0 0.7071067811865476 2 -1 -5 1 a.jpg
601 699 7 10 10 -1
EOF
cat >"$work/model/points3D.txt" <<'EOF'
7 16 -3 55 0 0 0 0.1 1 0
EOF
/usr/bin/python3 - "$work/db.db" <<'PY'
import array, sqlite3, sys
db = sqlite3.connect(sys.argv[1])
db.execute("CREATE TABLE keypoints (image_id INTEGER PRIMARY KEY, rows INTEGER, cols INTEGER, data BLOB)")
db.execute("CREATE TABLE descriptors (image_id INTEGER PRIMARY KEY, rows INTEGER, cols INTEGER, data BLOB)")
db.execute("CREATE TABLE matches (pair_id INTEGER PRIMARY KEY, rows INTEGER, cols INTEGER, data BLOB)")
db.execute("CREATE TABLE two_view_geometries (pair_id INTEGER PRIMARY KEY, rows INTEGER, cols INTEGER, data BLOB)")
for image_id in (1, 2):  # affine keypoints (6 columns), 4-byte descriptors
    keypoints = array.array("f", [601, 699, 1, 0, 0, 1, 10, 10, 2, 0, 0, 2])
    descriptors = array.array("B", [1, 1, 1, 1, 2, 2, 2, 2])
    db.execute("INSERT INTO keypoints VALUES (?, 2, 6, ?)", (image_id, keypoints.tobytes()))
    db.execute("INSERT INTO descriptors VALUES (?, 2, 4, ?)", (image_id, descriptors.tobytes()))
db.execute("INSERT INTO matches VALUES (1, 1, 2, ?)", (b"\0" * 8,))
db.execute("INSERT INTO two_view_geometries VALUES (1, 1, 2, ?)", (b"\0" * 8,))
db.commit()
PY
"$script" "$work/db.db" "$work/model" "$work/images" 30 >"$work/out.txt" ||
  fail "exit $?: $(cat "$work/out.txt")"
grep -q "1 photos, 1 observations moved" "$work/out.txt" || fail "summary: $(cat "$work/out.txt")"
/usr/bin/python3 - "$work/db.db" <<'PY' || fail "the database holds the wrong features"
import array, sqlite3, sys
db = sqlite3.connect(sys.argv[1])
def table(name, image_id, kind):
    rows, cols, data = db.execute("SELECT rows, cols, data FROM %s WHERE image_id = ?" % name,
                                  (image_id,)).fetchone()
    return rows, cols, list(array.array(kind, data))
rows, cols, k = table("keypoints", 1, "f")
assert (rows, cols) == (1, 6), (rows, cols)
assert abs(k[0] - 601) < 1e-3 and abs(k[1] - 701.2425) < 1e-3 and k[2:] == [1, 0, 0, 1], k
assert table("descriptors", 1, "B") == (1, 4, [1, 1, 1, 1])
assert table("keypoints", 2, "f")[0] == 2 and table("descriptors", 2, "B")[0] == 2
assert db.execute("SELECT COUNT(*) FROM matches").fetchone()[0] == 0
assert db.execute("SELECT COUNT(*) FROM two_view_geometries").fetchone()[0] == 0
PY
printf 'no metadata' >"$work/images/a.jpg"
set +e
"$script" "$work/db.db" "$work/model" "$work/images" 30 2>"$work/err.txt"
code=$?
set -e
[ "$code" = 2 ] || fail "a photo without speed: exit $code"
grep -q "a.jpg: no drone-dji flight speed" "$work/err.txt" || fail "message: $(cat "$work/err.txt")"
echo "odm_rs_correct: the known answer, the dropped observation and the refusal hold"
