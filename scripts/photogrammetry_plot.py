#!/usr/bin/python3
"""The camera-centre error of each photo along the flight, one line per variant, as an SVG.

  scripts/photogrammetry_plot.py OUT [TITLE]   reads OUT/colmap_*/score.json (photogrammetry.sh),
                                               writes OUT/centres.svg

Horizontal error, cm, of each photo in flight order (a gap where a photo is not registered);
plain SVG, no plotting library (Debian's python3 alone).
"""
import json
import os
import sys

VARIANTS = [("global", "global shutter", "#1b7837"), ("rolling", "rolling shutter", "#b2182b"),
            ("corrected", "corrected", "#2166ac"), ("wrong", "corrected, readout +20 %", "#f4a582"),
            ("odm", "ODM's (reproduced)", "#984ea3")]
W, H, LEFT, RIGHT, TOP, BOTTOM = 720, 360, 64, 200, 40, 48


def main():
    out = sys.argv[1]
    title = sys.argv[2] if len(sys.argv) > 2 else os.path.basename(os.path.normpath(out))
    series = []
    for name, label, colour in VARIANTS:
        path = os.path.join(out, "colmap_" + name, "score.json")
        if os.path.isfile(path):
            score = json.load(open(path))
            values = [100 * p["horizontal_error_m"] if p["registered"] and "horizontal_error_m" in p
                      else None for p in score["per_photo"]]
            series.append((label, colour, values))
    if not series:
        sys.exit("photogrammetry_plot.py: no %s/colmap_*/score.json" % out)
    n = max(len(v) for _, _, v in series)
    top = max([x for _, _, v in series for x in v if x is not None] + [1.0])
    top = next(s for s in (1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 1e9) if s >= top)
    px = lambda i: LEFT + (W - LEFT - RIGHT) * (i / max(1, n - 1))
    py = lambda v: TOP + (H - TOP - BOTTOM) * (1 - v / top)
    svg = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" font-family="sans-serif" '
           'font-size="12">' % (W, H), '<rect width="100%" height="100%" fill="white"/>',
           '<text x="%d" y="22" font-size="14">%s: camera centre error, horizontal, per photo</text>'
           % (LEFT, title)]
    for k in range(5):
        v = top * k / 4
        svg.append('<line x1="%d" x2="%d" y1="%.1f" y2="%.1f" stroke="#ddd"/>'
                   % (LEFT, W - RIGHT, py(v), py(v)))
        svg.append('<text x="%d" y="%.1f" text-anchor="end">%g cm</text>' % (LEFT - 6, py(v) + 4, v))
    for i in range(n):
        svg.append('<text x="%.1f" y="%d" text-anchor="middle">%d</text>' % (px(i), H - BOTTOM + 16, i + 1))
    svg.append('<text x="%.1f" y="%d" text-anchor="middle">photo, in flight order</text>'
               % ((LEFT + W - RIGHT) / 2, H - 12))
    for k, (label, colour, values) in enumerate(series):
        runs, run = [], []
        for i, v in enumerate(values):
            if v is None:
                runs, run = runs + [run] if run else runs, []
            else:
                run.append("%.1f,%.1f" % (px(i), py(v)))
        runs += [run] if run else []
        for r in runs:
            svg.append('<polyline fill="none" stroke="%s" stroke-width="2" points="%s"/>'
                       % (colour, " ".join(r)))
        y = TOP + 20 * k
        svg.append('<line x1="%d" x2="%d" y1="%d" y2="%d" stroke="%s" stroke-width="2"/>'
                   % (W - RIGHT + 12, W - RIGHT + 32, y, y, colour))
        svg.append('<text x="%d" y="%d">%s</text>' % (W - RIGHT + 38, y + 4, label))
    svg.append("</svg>")
    with open(os.path.join(out, "centres.svg"), "w") as f:
        f.write("\n".join(svg) + "\n")


if __name__ == "__main__":
    main()
