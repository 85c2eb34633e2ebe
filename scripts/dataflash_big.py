#!/usr/bin/env python3
"""Writes a large ArduPilot DataFlash log, to measure the memory and time of reading one.

The gyro is the batch sampler's (ISBH headers, ISBD packets of 32 samples per axis) at 4 kHz in
batches of 1,024 samples, back to back; beside it IMU at 400 Hz (a second, slower gyro stream that
the reader must summarise and pass over), and a CAM event every 10 s at 50 m above home. The first
10 s are still (noise only), then the rates swing as in a survey flight. Sample values repeat from
a pool, so the file is quick to write; the reader neither knows nor cares.

Usage: scripts/dataflash_big.py --samples 100000000 --out /tmp/isb8.bin
(stdlib only; 10^8 samples is 1.0 GB and takes about a minute)
"""
import argparse
import math
import random
import struct

RATE_HZ = 4000
BATCH = 1024
PACKET = 32
MUL = 1000  # raw / mul = rad/s
IMU_EVERY = RATE_HZ // 400
CAM_EVERY_S = 10


def header(msg_type):
    return bytes([0xA3, 0x95, msg_type])


def fmt(msg_type, length, name, form, labels):
    return (header(128) + struct.pack("<BB", msg_type, length) + name.encode().ljust(4, b"\0")
            + form.encode().ljust(16, b"\0") + labels.encode().ljust(64, b"\0"))


ISBH, ISBD, IMU, CAM = 20, 21, 22, 23


def definitions():
    return b"".join([
        fmt(128, 89, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns"),
        fmt(ISBH, 3 + 8 + 2 + 1 + 1 + 2 + 2 + 8 + 4, "ISBH", "QHBBHHQf",
            "TimeUS,N,type,instance,mul,smp_cnt,SampleUS,smp_rate"),
        fmt(ISBD, 3 + 8 + 2 + 2 + 3 * 64, "ISBD", "QHHaaa", "TimeUS,N,seqno,x,y,z"),
        fmt(IMU, 3 + 8 + 1 + 24, "IMU", "QBffffff", "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ"),
        fmt(CAM, 46, "CAM", "QBHIHLLeeeccC",
            "TimeUS,I,Img,GPSTime,GPSWeek,Lat,Lng,Alt,RelAlt,GPSAlt,R,P,Y"),
    ])


def packet_pool(rng, moving):
    """64 packets' worth of (x, y, z) int16 values: noise, or noise on swinging rates."""
    pool = []
    for p in range(64):
        axes = []
        for axis in range(3):
            values = []
            for k in range(PACKET):
                t = (p * PACKET + k) / RATE_HZ
                v = rng.gauss(0.0, 0.004)
                if moving:
                    v += 0.03 * math.sin(2 * math.pi * (0.7 + axis) * t + axis)
                values.append(max(-32768, min(32767, round(v * MUL))))
            axes.append(values)
        pool.append(axes)
    return pool


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, required=True, help="gyro samples (ISBD)")
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
    rng = random.Random(8)
    still, moving = packet_pool(rng, False), packet_pool(rng, True)
    t0_us = 1_000_000
    batches = (args.samples + BATCH - 1) // BATCH
    written = 0
    image = 0
    with open(args.out, "wb") as out:
        out.write(definitions())
        for n in range(batches):
            count = min(BATCH, args.samples - written)
            start_us = t0_us + written * 1_000_000 // RATE_HZ
            block = [header(ISBH), struct.pack("<QHBBHHQf", start_us + 10, n & 0xFFFF, 1, 0, MUL,
                                               count, start_us, float(RATE_HZ))]
            pool = still if start_us - t0_us < 10_000_000 else moving
            for seq in range((count + PACKET - 1) // PACKET):
                x, y, z = pool[(n * 32 + seq) % 64]
                block.append(header(ISBD) + struct.pack("<QHH", start_us + 20, n & 0xFFFF, seq)
                             + struct.pack("<32h", *x) + struct.pack("<32h", *y)
                             + struct.pack("<32h", *z))
            for k in range(0, count, IMU_EVERY):
                t_us = start_us + k * 1_000_000 // RATE_HZ
                gx, gy, gz = (v[k % PACKET] / MUL for v in pool[(n * 32 + k // PACKET) % 64])
                block.append(header(IMU) + struct.pack("<QBffffff", t_us + 5, 0, gx, gy, gz,
                                                       0.0, 0.0, -9.81))
                if (t_us - t0_us) // 1_000_000 >= (image + 1) * CAM_EVERY_S:
                    image += 1
                    block.append(header(CAM) + struct.pack(
                        "<QBHIHiiiiihhH", t_us + 7, 0, image, 0, 0, 473977000, 85456000, 50000,
                        5000, 50000, 0, 0, 0))
            out.write(b"".join(block))
            written += count


if __name__ == "__main__":
    main()
