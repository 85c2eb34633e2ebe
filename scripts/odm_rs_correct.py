#!/usr/bin/python3
"""ODM's own rolling-shutter treatment, reproduced on a COLMAP database (docs/photogrammetry.md).

  scripts/odm_rs_correct.py DB MODEL IMAGES READOUT_MS

DB          a copy of the rolling-shutter reconstruction's COLMAP database; rewritten in place
MODEL       that reconstruction as a text model, aligned to the photos' positions (metres, x east,
            y north, z up: `colmap model_aligner`), as OpenSfM's is by the photos' GPS
IMAGES      the photos, whose DJI XMP flight speed (drone-dji:FlightX/Y/ZSpeed) is read
READOUT_MS  the sensor's readout, ms (ODM's --rolling-shutter-readout)

The method is OpenSfM's `rs_correct` as ODM runs it with --rolling-shutter (OpenSfM
opensfm/actions/rs_correct.py, ODM opendm/photo.py and opendm/osfm.py), after the first
reconstruction:
  - each photo's speed is its XMP's, as ODM's exif writes it: [FlightYSpeed, FlightXSpeed,
    FlightZSpeed] (east, north, and DJI's down speed unchanged: level flights have none);
  - every observation of a reconstructed point, at pixel row y of an image h rows high, moves by
    proj(X, C - v * readout * (y - h/2) / h) - proj(X, C): translation only, about the middle row;
  - each corrected photo keeps only its corrected observations (the rest are dropped);
    a photo outside the reconstruction, or with no observation in it, keeps its features;
Only the one model given is corrected (OpenSfM corrects every partial reconstruction: the surveys
here make one).
ODM then matches the corrected features again and reconstructs once more: the caller runs COLMAP's
matcher and mapper on DB. Only what the method needs of COLMAP's models: the pinhole family and
OPENCV. Debian's python3 alone (sqlite3, array).
"""
import array
import math
import os
import re
import sqlite3
import sys


def fail(message):
    print("odm_rs_correct: %s" % message, file=sys.stderr)
    sys.exit(2)


def read_cameras(path):
    """camera_id -> (model, width, height, params), cameras.txt."""
    cameras = {}
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            parts = line.split()
            cameras[int(parts[0])] = (parts[1], int(parts[2]), int(parts[3]),
                                      [float(p) for p in parts[4:]])
    return cameras


def read_images(path):
    """image_id -> (name, camera_id, R (cam_from_world, rows), t, [(x, y, point3D_id)])."""
    images = {}
    with open(path) as f:
        lines = [l for l in f.read().splitlines() if not l.startswith("#")]
    for header, points in zip(lines[0::2], lines[1::2]):
        parts = header.split()
        if len(parts) < 10:
            continue
        qw, qx, qy, qz, tx, ty, tz = (float(p) for p in parts[1:8])
        rotation = [
            [1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qw * qz), 2 * (qx * qz + qw * qy)],
            [2 * (qx * qy + qw * qz), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qw * qx)],
            [2 * (qx * qz - qw * qy), 2 * (qy * qz + qw * qx), 1 - 2 * (qx * qx + qy * qy)]]
        values = points.split()
        observations = [(float(values[i]), float(values[i + 1]), int(values[i + 2]))
                        for i in range(0, len(values) - 2, 3)]
        images[int(parts[0])] = (parts[9], int(parts[8]), rotation, [tx, ty, tz], observations)
    return images


def read_points(path):
    """point3D_id -> [x, y, z], points3D.txt."""
    points = {}
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            parts = line.split()
            points[int(parts[0])] = [float(p) for p in parts[1:4]]
    return points


def project(camera, rotation, centre, point):
    """The pixel of a world point seen from a camera at centre (COLMAP's camera models)."""
    model, _, _, p = camera
    d = [point[i] - centre[i] for i in range(3)]
    x, y, z = (sum(rotation[r][c] * d[c] for c in range(3)) for r in range(3))
    u, v = x / z, y / z
    if model == "SIMPLE_PINHOLE":
        return p[0] * u + p[1], p[0] * v + p[2]
    if model in ("SIMPLE_RADIAL", "RADIAL"):
        r2 = u * u + v * v
        k2 = p[4] if model == "RADIAL" else 0.0
        radial = 1 + p[3] * r2 + k2 * r2 * r2
        return p[0] * u * radial + p[1], p[0] * v * radial + p[2]
    if model == "PINHOLE":
        return p[0] * u + p[2], p[1] * v + p[3]
    if model == "OPENCV":
        k1, k2, p1, p2 = p[4:8]
        r2 = u * u + v * v
        radial = 1 + k1 * r2 + k2 * r2 * r2
        ud = u * radial + 2 * p1 * u * v + p2 * (r2 + 2 * u * u)
        vd = v * radial + p1 * (r2 + 2 * v * v) + 2 * p2 * u * v
        return p[0] * ud + p[2], p[1] * vd + p[3]
    fail("camera model %s is not one this reproduction projects (pinhole family, OPENCV)" % model)


def photo_speed(path):
    """ODM's speed of a DJI photo, m/s: [FlightYSpeed, FlightXSpeed, FlightZSpeed], or None."""
    with open(path, "rb") as f:
        data = f.read()
    values = []
    for axis in ("Y", "X", "Z"):
        found = re.search(rb"drone-dji:Flight%sSpeed(?:=\"|>)([-+0-9.eE]+)" % axis.encode(), data)
        if not found:
            return None
        values.append(float(found.group(1)))
    return values


def main():
    if len(sys.argv) != 5:
        fail("usage: scripts/odm_rs_correct.py DB MODEL IMAGES READOUT_MS")
    db_path, model, image_dir, readout_ms = sys.argv[1:5]
    readout_s = float(readout_ms) / 1000.0
    cameras = read_cameras(os.path.join(model, "cameras.txt"))
    images = read_images(os.path.join(model, "images.txt"))
    points = read_points(os.path.join(model, "points3D.txt"))
    db = sqlite3.connect(db_path)
    moved_px = []
    for image_id, (name, camera_id, rotation, t, observations) in sorted(images.items()):
        speed = photo_speed(os.path.join(image_dir, name))
        if speed is None:
            # ODM computes every speed from the poses when one photo lacks it; the survey's all have it.
            fail("%s: no drone-dji flight speed (this reproduction reads the photos' own)" % name)
        camera = cameras[camera_id]
        height = camera[2]
        # The camera centre, world: C = -R^T t.
        centre = [-sum(rotation[r][c] * t[r] for r in range(3)) for c in range(3)]
        row = db.execute("SELECT rows, cols, data FROM keypoints WHERE image_id = ?",
                         (image_id,)).fetchone()
        descriptor = db.execute("SELECT rows, cols, data FROM descriptors WHERE image_id = ?",
                                (image_id,)).fetchone()
        if row is None or descriptor is None or row[0] != len(observations):
            fail("%s: the database's keypoints do not match the model's %d observations"
                 % (name, len(observations)))
        keypoints = array.array("f", row[2])
        descriptors = array.array("B", descriptor[2])
        cols, descriptor_cols = row[1], descriptor[1]
        kept_keypoints, kept_descriptors = array.array("f"), array.array("B")
        for index, (x, y, point_id) in enumerate(observations):
            if point_id < 0 or point_id not in points:
                continue
            point = points[point_id]
            shift_s = readout_s * (y - height / 2.0) / height
            moved = [centre[i] - speed[i] * shift_s for i in range(3)]
            x0, y0 = project(camera, rotation, centre, point)
            x1, y1 = project(camera, rotation, moved, point)
            keypoint = keypoints[index * cols:(index + 1) * cols]
            keypoint[0] = x + (x1 - x0)
            keypoint[1] = y + (y1 - y0)
            moved_px.append(math.hypot(x1 - x0, y1 - y0))
            kept_keypoints.extend(keypoint)
            kept_descriptors.extend(descriptors[index * descriptor_cols:(index + 1) * descriptor_cols])
        kept = len(kept_keypoints) // cols
        if kept == 0:
            continue  # OpenSfM loads and rewrites only the features of photos with observations
        db.execute("UPDATE keypoints SET rows = ?, data = ? WHERE image_id = ?",
                   (kept, kept_keypoints.tobytes(), image_id))
        db.execute("UPDATE descriptors SET rows = ?, data = ? WHERE image_id = ?",
                   (kept, kept_descriptors.tobytes(), image_id))
    # ODM matches the corrected features again.
    db.execute("DELETE FROM matches")
    db.execute("DELETE FROM two_view_geometries")
    db.commit()
    moved_px.sort()
    median = moved_px[len(moved_px) // 2] if moved_px else 0.0
    print("odm_rs_correct: %d photos, %d observations moved (median %.3f px, largest %.3f px)"
          % (len(images), len(moved_px), median, moved_px[-1] if moved_px else 0.0))


if __name__ == "__main__":
    main()
