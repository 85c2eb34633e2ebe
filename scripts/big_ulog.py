#!/usr/bin/env python3
"""Writes a long synthetic PX4 ULog, to measure what reading one costs (docs/speed.md, memory).

The gyro is sensor_gyro_fifo (PX4's batched topic: 32 int16 samples a message, dt and scale),
which keeps 10^8 samples near 700 MB; with it camera_capture every 2 s and
vehicle_local_position (dist_bottom 50 m) at 10 Hz. The motion is a smooth sway of a few deg/s
plus a small deterministic jitter, repeated every 4096 messages (the file's size and parse work
are what matter, not its content).

Usage: scripts/big_ulog.py SAMPLES OUT.ulg [--rate-hz 4000]   (stdlib only)
"""
import argparse
import math
import struct


def message(kind, payload):
    return struct.pack("<HB", len(payload), ord(kind)) + payload


FORMATS = [
    b"sensor_gyro_fifo:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float dt;"
    b"float scale;uint8_t samples;int16_t[32] x;int16_t[32] y;int16_t[32] z;uint8_t[1] _padding0;",
    b"camera_capture:uint64_t timestamp;uint32_t seq;uint8_t[4] _padding0;",
    b"vehicle_local_position:uint64_t timestamp;float dist_bottom;bool dist_bottom_valid;"
    b"uint8_t[3] _padding0;",
]
TOPICS = [b"sensor_gyro_fifo", b"camera_capture", b"vehicle_local_position"]
SCALE = 1e-4  # rad/s per count: +-3.3 rad/s in int16
PATTERN = 4096  # distinct sample blocks, repeated


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("samples", type=int)
    parser.add_argument("out")
    parser.add_argument("--rate-hz", type=float, default=4000.0)
    args = parser.parse_args()
    dt_us = 1e6 / args.rate_hz
    per = 32
    blocks = []
    for b in range(PATTERN):
        axes = []
        for axis in range(3):
            values = []
            for i in range(per):
                k = b * per + i
                w = 0.05 * math.sin(2 * math.pi * k * dt_us * 1e-6 * (0.3 + 0.2 * axis))
                w += 0.002 * (((k * 2654435761 + axis * 97) % 1000) / 500.0 - 1.0)
                values.append(int(round(w / SCALE)))
            axes.append(values)
        blocks.append(struct.pack("<32h32h32h", *axes[0], *axes[1], *axes[2]))
    t0_us = 1_000_000
    with open(args.out, "wb") as f:
        f.write(b"ULog\x01\x12\x35\x01" + struct.pack("<Q", t0_us))
        f.write(message("B", bytes(40)))
        for fmt in FORMATS:
            f.write(message("F", fmt))
        for msg_id, topic in enumerate(TOPICS):
            f.write(message("A", struct.pack("<BH", 0, msg_id) + topic))
        written = 0
        n_msg = 0
        next_camera_us = t0_us + 2_000_000
        next_position_us = t0_us
        seq = 0
        out = []
        while written < args.samples:
            n = min(per, args.samples - written)
            newest_us = t0_us + int(round((written + n - 1) * dt_us))
            body = blocks[n_msg % PATTERN]
            if n < per:
                body = struct.pack("<32h32h32h", *(
                    v if i < n else 0
                    for a in range(3)
                    for i, v in enumerate(struct.unpack_from("<32h", body, 64 * a))))
            out.append(message("D", struct.pack("<HQQIffB", 0, newest_us, newest_us, 1, dt_us,
                                                SCALE, n) + body))
            while next_position_us <= newest_us:
                out.append(message("D", struct.pack("<HQfB", 2, next_position_us, 50.0, 1)))
                next_position_us += 100_000
            while next_camera_us <= newest_us:
                out.append(message("D", struct.pack("<HQI", 1, next_camera_us, seq)))
                seq += 1
                next_camera_us += 2_000_000
            written += n
            n_msg += 1
            if len(out) >= 4096:
                f.write(b"".join(out))
                out = []
        f.write(b"".join(out))


if __name__ == "__main__":
    main()
