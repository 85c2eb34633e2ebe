#!/usr/bin/env python3
"""Are validate's standard errors honest, for every effect and every model it reports?

Renders N seeded datasets through the command line (`shutterlab render`, then `shutterlab
validate --report`), each with ONE effect in the truth that camera.json does not declare, a random
value of it, stills or video in turn, every third with a camera-fixed patch and a moving car
(render --camera-fixed-patch, --moving-patch). For every model the report prints (stills: the
loop; video: rotation_only and translation) that reports the injected effect, each parameter's
z = (fitted - true) / stderr is recorded (none where validate withholds the standard error: a
model whose errors do not hold). Prints the table per effect and model: datasets, identified (the
model reported the effect), withheld, the share of parameters within 2 standard errors, the
share of datasets with every parameter within 2, and the median and largest |z|.

Usage: scripts/coverage_study.py [--clips N] [--first-seed S] [--out DIR] [--size WxH] [--csv F]
                                [--fail-above Z] [--effects A,B] [--quiet]
  --clips N       datasets (default 200)
  --first-seed S  the first dataset's seed (default 1); dataset k uses seed S + k
  --out DIR       work folder (default /tmp/shutterlab_coverage; each dataset removed after use)
  --size WxH      frame size (default 320x240; f scales with it, 550 px at 640)
  --csv F         also write one row per (dataset, model) to F
  --fail-above Z  exit 1 when a reported standard error misses the truth by more than Z of them,
                  or a dataset failed (the suite's seeded subset: a gross miscalibration, not
                  the 90-98 % coverage)
  --effects A,B   only these effects (stills and video in turn where both can show them)
  --quiet         no progress
(stdlib only.) Exit 0 when it ran (and nothing is above --fail-above); 2 on bad usage. A
dataset whose commands fail is said on stderr and left out.
"""
import argparse
import csv
import json
import math
import os
import random
import shutil
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHUTTERLAB = os.environ.get("SHUTTERLAB", os.path.join(ROOT, "build", "bin", "shutterlab"))

# Effects a still dataset and a video clip can each show (video: no velocity; its translation model
# holds the motion). readout_direction has no standard error and is left out.
STILL_EFFECTS = ["time_offset", "readout_time", "gyro_to_camera", "gyro_scale", "gyro_bias",
                 "lens_distortion", "velocity"]
VIDEO_EFFECTS = ["time_offset", "readout_time", "gyro_to_camera", "gyro_scale", "gyro_bias",
                 "lens_distortion", "clock_rate"]


def run(args, **kw):
    return subprocess.run(args, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, **kw)


def rotation(axis, angle):
    n = math.sqrt(sum(a * a for a in axis))
    x, y, z = (a / n for a in axis)
    c, s, t = math.cos(angle), math.sin(angle), 1 - math.cos(angle)
    return [[t * x * x + c, t * x * y - s * z, t * x * z + s * y],
            [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
            [t * x * z - s * y, t * y * z + s * x, t * z * z + c]]


def draw(effect, rng):
    """(the --inject text, the true value in the report's JSON shape)."""
    sign = lambda: rng.choice([-1.0, 1.0])  # noqa: E731
    if effect == "time_offset":
        v = sign() * rng.uniform(1e-3, 8e-3)
        return f"time_offset={v!r}s", v
    if effect == "readout_time":
        v = rng.uniform(0.024, 0.036)
        return f"readout_time={v!r}s", v
    if effect == "clock_rate":
        v = sign() * rng.uniform(100, 400)
        return f"clock_rate={v!r}ppm", v
    if effect == "gyro_scale":
        v = [rng.uniform(0.95, 1.05) for _ in range(3)]
        return "gyro_scale=" + ",".join(repr(a) for a in v), v
    if effect == "gyro_bias":
        v = [rng.uniform(-0.01, 0.01) for _ in range(3)]
        return "gyro_bias=" + ",".join(f"{a!r}rad/s" for a in v), v
    if effect == "velocity":
        v = [rng.uniform(-3, 3) for _ in range(3)]
        return "velocity=" + ",".join(f"{a!r}m/s" for a in v), v
    if effect == "gyro_to_camera":
        m = rotation([rng.gauss(0, 1) for _ in range(3)], math.radians(rng.uniform(2, 5)))
        return "gyro_to_camera=" + ",".join(repr(a) for row in m for a in row), m
    if effect == "lens_distortion":
        v = {"k1": sign() * rng.uniform(0.02, 0.06), "k2": rng.uniform(-0.01, 0.01)}
        return f"lens_distortion={v['k1']!r},{v['k2']!r}", v
    raise ValueError(effect)


def zs(effect, value, stderr, truth):
    """Each parameter's (fitted - true) / stderr; None where a standard error is missing."""
    if effect == "lens_distortion":
        pairs = [(value[k], stderr.get(k) if stderr else None, truth[k]) for k in ("k1", "k2")]
    elif effect == "gyro_to_camera":
        pairs = [(value[i][j], stderr[i][j] if stderr else None, truth[i][j])
                 for i in range(3) for j in range(3) if i != j]
    elif isinstance(truth, list):
        pairs = [(value[i], stderr[i] if stderr else None, truth[i]) for i in range(3)]
    else:
        pairs = [(value, stderr, truth)]
    out = []
    for v, s, t in pairs:
        out.append(None if s is None or not s > 0 else (v - t) / s)
    return out


def frames_csv(path, times):
    with open(path, "w") as f:
        f.write("frame,t_first_row\n")
        for i, t in enumerate(times):
            f.write(f"{i},{t:.9f}\n")


def one_dataset(k, seed, out, width, height, scene, gyros, only=None):
    rng = random.Random(seed)
    video = k % 2 == 1
    kind_effects = lambda v: [e for e in (VIDEO_EFFECTS if v else STILL_EFFECTS)  # noqa: E731
                              if not only or e in only]
    if not kind_effects(video):
        video = not video
    effects = kind_effects(video)
    effect = effects[(k // 2) % len(effects)]
    inject, truth = draw(effect, rng)
    clutter = k % 3 == 2
    flight_seed = 1 + k % 5
    camera = os.path.join(out, "camera.json")
    f_px = 550.0 * width / 640
    with open(camera, "w") as f:
        json.dump({"format": "rig/1", "image": {"width": width, "height": height},
                   "intrinsics": {"fx": f_px, "fy": f_px, "cx": (width - 1) / 2,
                                  "cy": (height - 1) / 2},
                   "rolling_shutter": {"readout_s": 0.030, "direction": "top_to_bottom"},
                   "scene": {"altitude_m": 50.0}}, f)
    times = os.path.join(out, "times.csv")
    if video and effect == "clock_rate":
        start = rng.uniform(8.0, 9.0)
        frames_csv(times, [start + i / 5.0 for i in range(50)])  # 10 s: the drift shows
    elif video:
        start = rng.uniform(8.0, 25.0)
        frames_csv(times, [start + i / 30.0 for i in range(16)])
    else:
        start = rng.uniform(8.0, 12.0)
        frames_csv(times, [start + 2.0 * i for i in range(8)])
    ds = os.path.join(out, f"ds{k}")
    cmd = [SHUTTERLAB, "render", "--scene", scene, "--camera", camera, "--gyro",
           gyros[flight_seed], "--frames", times, "--out", ds, "--no-pictures", "--inject", inject]
    if video:
        cmd.append("--video")
    if clutter:
        cmd += ["--camera-fixed-patch", "0.25", "--moving-patch", "10m/s"]
    run(cmd)
    report = os.path.join(out, f"r{k}.json")
    run([SHUTTERLAB, "validate", ds, "--report", report])
    with open(report) as f:
        r = json.load(f)
    shutil.rmtree(ds, ignore_errors=True)
    os.remove(report)
    models = {"rotation_only": r["rotation_only"], "translation": r["translation"]} if video \
        else {"still": r}
    rows = []
    for model, loop in models.items():
        found = [e for e in loop.get("effects", []) if e["name"] == effect]
        row = {"dataset": k, "seed": seed, "kind": "video" if video else "still",
               "clutter": clutter, "effect": effect, "model": model,
               "preferred": r.get("model", "still") == model or not video,
               "identified": bool(found), "z": ""}
        if found:
            e = found[0]
            row["z"] = ";".join("nan" if z is None else f"{z:.3f}"
                                for z in zs(effect, e["value"], e.get("stderr"), truth))
        rows.append(row)
    return rows


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--clips", type=int, default=200)
    p.add_argument("--first-seed", type=int, default=1)
    p.add_argument("--out", default="/tmp/shutterlab_coverage")
    p.add_argument("--size", default="320x240")
    p.add_argument("--csv")
    p.add_argument("--fail-above", type=float)
    p.add_argument("--quiet", action="store_true")
    p.add_argument("--effects")
    a = p.parse_args()
    width, height = (int(x) for x in a.size.split("x"))
    os.makedirs(a.out, exist_ok=True)
    scene = os.path.join(a.out, "scene.png")
    gyros = {s: os.path.join(a.out, f"gyro{s}.csv") for s in range(1, 6)}
    try:
        if not os.path.exists(scene):
            # The scene's ground sample distance the camera's (altitude / f), at most scene's 20 cm.
            gsd_cm = min(20.0, 50.0 / (550.0 * width / 640) * 100)
            run([SHUTTERLAB, "scene", "--out", scene, "--width", "3000", "--height", "3000",
                 "--gsd", f"{gsd_cm:.6f}cm"])
        for s, path in gyros.items():
            if not os.path.exists(path):
                run([SHUTTERLAB, "synth", "flight", "--ideal", "--rate", "1000Hz", "--duration",
                     "40s", "--seed", str(s), "--out", path])
    except (subprocess.CalledProcessError, OSError) as e:
        detail = e.stderr.decode().strip() if isinstance(e, subprocess.CalledProcessError) else e
        print(f"{sys.argv[0]}: cannot make the inputs: {detail}", file=sys.stderr)
        sys.exit(2)
    rows, failed = [], 0
    for k in range(a.clips):
        try:
            rows += one_dataset(k, a.first_seed + k, a.out, width, height, scene, gyros,
                                a.effects.split(",") if a.effects else None)
        except subprocess.CalledProcessError as e:
            failed += 1
            print(f"dataset {k}: {' '.join(e.cmd[:2])}: {e.stderr.decode().strip()}", file=sys.stderr)
        if not a.quiet:
            print(f"\r{k + 1}/{a.clips}", end="", file=sys.stderr, flush=True)
    if not a.quiet:
        print(file=sys.stderr)
    if not rows:
        print(f"{sys.argv[0]}: no dataset could be rendered and validated", file=sys.stderr)
        sys.exit(1)
    if a.csv:
        with open(a.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
            w.writeheader()
            w.writerows(rows)
    print("| effect | model | datasets | identified | standard error withheld | parameters within "
          "2 SE | datasets with every parameter within 2 SE | median, largest abs(z) |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    keys = sorted({(r["effect"], r["model"]) for r in rows})
    worst = 0.0
    for effect, model in keys:
        group = [r for r in rows if r["effect"] == effect and r["model"] == model]
        found = [r for r in group if r["identified"]]
        withheld, covered, judged, all_z = 0, 0, 0, []
        for r in found:
            z = [abs(float(x)) for x in r["z"].split(";")]
            finite = [x for x in z if math.isfinite(x)]
            if not finite:
                withheld += 1
                continue
            judged += 1
            all_z += finite
            covered += 1 if max(finite) <= 2 else 0
        inside = sum(1 for x in all_z if x <= 2)
        params = f"{inside} of {len(all_z)} ({100 * inside / len(all_z):.0f} %)" if all_z else "-"
        whole = f"{covered} of {judged} ({100 * covered / judged:.0f} %)" if judged else "-"
        zs_text = f"{sorted(all_z)[len(all_z) // 2]:.2f}, {max(all_z):.2f}" if all_z else "-"
        worst = max([worst] + all_z)
        print(f"| {effect} | {model} | {len(group)} | {len(found)} | {withheld} | {params} | "
              f"{whole} | {zs_text} |")
    if a.fail_above is not None and failed:
        print(f"{sys.argv[0]}: {failed} dataset(s) could not be rendered and validated",
              file=sys.stderr)
        sys.exit(1)
    if a.fail_above is not None and worst > a.fail_above:
        print(f"{sys.argv[0]}: a reported standard error missed the truth by {worst:.1f} of them "
              f"(above --fail-above {a.fail_above:g})", file=sys.stderr)
        sys.exit(1)

if __name__ == "__main__":
    main()
