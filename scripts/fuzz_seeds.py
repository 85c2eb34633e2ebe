#!/usr/bin/env python3
"""Small fuzz seeds from real logs: what each format needs to reach its decoders, in a few KiB.

A whole log makes every fuzz execution slow (the readers are linear in the input); a plain prefix
holds only the start of the definitions. This keeps, per format:
  ulog       the header, flag bits, the formats of the topics the reader decodes (and the nested
             types they use), their subscriptions, the first data messages of each, dropouts, logs;
  dataflash  the FMT records of the messages the reader decodes, the unit tables and the first
             messages of each of those types;
  mp4        ftyp and moov (without udta) with every sample table cut to its first entries (the media data is
             dropped: the offsets then point past the end, which the reader must refuse cleanly);
  gpmf       the first GoPro telemetry sample (a GPMF payload) of an MP4's gpmd track;
  prefix     the first N bytes (blackbox: the text header and the first frames).

Usage: fuzz_seeds.py ulog|dataflash|mp4|gpmf|prefix IN OUT [max_bytes]   (stdlib only)
"""
import re
import struct
import sys

ULOG_TOPICS = {"sensor_gyro_fifo", "sensor_gyro", "vehicle_angular_velocity", "sensor_combined",
               "camera_trigger", "camera_capture", "vehicle_local_position", "home_position"}
DATAFLASH_TYPES = {b"GYR", b"IMU", b"IMU2", b"IMU3", b"ISBH", b"ISBD", b"CAM", b"TRIG", b"FMTU",
                   b"UNIT", b"MULT"}


def ulog(data, max_bytes, per_topic=4):
    out = bytearray(data[:16])
    formats, subs = {}, {}
    messages = []
    p = 16
    while p + 3 <= len(data):
        size, kind = struct.unpack_from("<HB", data, p)
        end = p + 3 + size
        if end > len(data):
            break
        messages.append((chr(kind), data[p:end]))
        if kind == ord("F"):
            text = data[p + 3:end].decode("latin-1")
            name, _, fields = text.partition(":")
            formats[name] = [f.split(" ")[0].split("[")[0] for f in fields.split(";") if f]
        p = end
    needed, todo = set(), [t for t in ULOG_TOPICS if t in formats]
    while todo:
        name = todo.pop()
        if name in needed:
            continue
        needed.add(name)
        todo += [t for t in formats.get(name, []) if t in formats]
    kept = {}
    for kind, msg in messages:
        body = msg[3:]
        if kind == "F":
            keep = body.decode("latin-1").partition(":")[0] in needed
        elif kind == "A":
            keep = body[3:].decode("latin-1") in ULOG_TOPICS
            if keep:
                subs[struct.unpack_from("<H", body, 1)[0]] = True
        elif kind == "D":
            msg_id = struct.unpack_from("<H", body, 0)[0]
            kept[msg_id] = kept.get(msg_id, 0) + 1
            keep = msg_id in subs and kept[msg_id] <= per_topic
        else:
            keep = kind in "BOL" and len(out) < max_bytes // 2
        if keep and len(out) + len(msg) <= max_bytes:
            out += msg
    return bytes(out)


def dataflash(data, max_bytes, per_type=4):
    """Walks the records by their FMT lengths; keeps FMTs of the decoded types and a few of each."""
    lengths, names, out, seen = {128: 89}, {}, bytearray(), {}
    p = 0
    while p + 3 <= len(data):
        if data[p] != 0xA3 or data[p + 1] != 0x95:
            p += 1
            continue
        kind = data[p + 2]
        length = lengths.get(kind)
        if length is None or p + length > len(data):
            p += 1
            continue
        record = data[p:p + length]
        if kind == 128:
            ftype, flen = record[3], record[4]
            name = record[5:9].rstrip(b"\0")
            lengths[ftype], names[ftype] = flen, name
            keep = name in DATAFLASH_TYPES or ftype == 128
        else:
            seen[kind] = seen.get(kind, 0) + 1
            keep = names.get(kind) in DATAFLASH_TYPES and seen[kind] <= per_type
        if keep and len(out) + length <= max_bytes:
            out += record
        p += length
    return bytes(out)


MP4_CONTAINERS = {b"moov", b"trak", b"mdia", b"minf", b"stbl", b"edts", b"dinf"}
# Sample tables: (header bytes after version/flags before the entries, bytes per entry).
MP4_TABLES = {b"stts": 8, b"ctts": 8, b"stsc": 12, b"stco": 4, b"co64": 8, b"stss": 4}


def mp4_boxes(data, begin, end):
    p = begin
    while p + 8 <= end:
        size, kind = struct.unpack_from(">I4s", data, p)
        header = 8
        if size == 1:
            size, header = struct.unpack_from(">Q", data, p + 8)[0], 16
        elif size == 0:
            size = end - p
        if size < header or p + size > end:
            return
        yield kind, data[p:p + size], header
        p += size


def mp4_slim(box_kind, box, header, entries):
    if box_kind == b"udta":  # the camera's settings (tens of KiB), which the readers skip
        return b""
    body = box[header:]
    if box_kind in MP4_CONTAINERS:
        body = b"".join(mp4_slim(k, b, h, entries) for k, b, h in mp4_boxes(box, header, len(box)))
    elif box_kind in MP4_TABLES and len(body) >= 8:
        count = min(struct.unpack_from(">I", body, 4)[0], entries)
        body = body[:4] + struct.pack(">I", count) + body[8:8 + count * MP4_TABLES[box_kind]]
    elif box_kind == b"stsz" and len(body) >= 12:
        fixed, count = struct.unpack_from(">II", body, 4)
        count = min(count, entries)
        body = body[:8] + struct.pack(">I", count) + (b"" if fixed else body[12:12 + 4 * count])
    return struct.pack(">I4s", 8 + len(body), box_kind) + body


def mp4(data, max_bytes, entries=4):
    out = b"".join(mp4_slim(k, b, h, entries) for k, b, h in mp4_boxes(data, 0, len(data))
                   if k in (b"ftyp", b"moov"))
    return out[:max_bytes]


def gpmf(data, max_bytes):
    """The first sample of the track whose sample description is 'gpmd'."""
    for kind, moov, header in mp4_boxes(data, 0, len(data)):
        if kind != b"moov":
            continue
        for tkind, trak, th in mp4_boxes(moov, header, len(moov)):
            if tkind == b"trak" and b"gpmd" in trak:
                stco = trak.find(b"stco")
                stsz = trak.find(b"stsz")
                offset = struct.unpack_from(">I", trak, stco + 12)[0]
                fixed, _ = struct.unpack_from(">II", trak, stsz + 8)
                size = fixed or struct.unpack_from(">I", trak, stsz + 16)[0]
                return data[offset:offset + min(size, max_bytes)]
    return b""


def main():
    mode, src, dst = sys.argv[1:4]
    max_bytes = int(sys.argv[4]) if len(sys.argv) > 4 else 8192
    data = open(src, "rb").read()
    if mode == "ulog":
        seed = ulog(data, max_bytes)
    elif mode == "dataflash":
        seed = dataflash(data, max_bytes)
    elif mode == "mp4":
        seed = mp4(data, max_bytes)
    elif mode == "gpmf":
        seed = gpmf(data, max_bytes)
    else:
        seed = data[:max_bytes]
    open(dst, "wb").write(seed)


if __name__ == "__main__":
    main()
