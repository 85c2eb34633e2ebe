#!/usr/bin/env python3
"""What every command that takes a log says about each real log in the shared data folder.

Runs `flight`, `noise`, `accuracy --reference-deg 1` and `analyze --every 2s` (each with --json and
its defaults) on every log that holds a gyro, and on a copy of each cut at 60 % of its bytes, and
prints one Markdown table: what the reader got (format, gyro source, samples, rate, duration),
what it said it lost (the warnings' kinds with their counts), and each command's outcome (its
exit code and, on an error, the one line it printed). docs/real-logs.md holds its output.

Usage: scripts/real_logs.py [--shutterlab build/bin/shutterlab] [--data ../shared/data] [--only TEXT]
  --only TEXT  only the logs whose path under the data folder holds TEXT
(stdlib only; SHUTTERLAB_DATA_DIR overrides the data folder)
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

# (path under the data folder, extra flags every command needs to read it); the same list as
# tests/app/real_logs_cli_test.cc's kRealLogs, which checks what these commands say about each
LOGS = [
    ("gyro/betaflight_blackbox/btfl_001.bbl", []),
    ("gyro/betaflight_blackbox/btfl_002.bbl", []),
    ("gyro/betaflight_blackbox/LOG00037.BFL", []),
    ("gyro/px4_ulog/sample.ulg", []),
    ("gyro/px4_ulog/sample_log_small.ulg", []),
    ("incoming/ardupilot_log171/log171.bin", []),
    ("incoming/ardupilot_isb_80k/backend_log_80k.bin", []),
    ("incoming/ardupilot_pymavlink_test/test.BIN", []),
    ("rs/gopro_karma/karma.mp4", []),
    ("incoming_rs/gopro_max_heromode/max-heromode.mp4", []),
    ("rs/phone_gyro_video_20200109_145447/gyro.txt", ["--columns", "4,1,2,3"]),
    ("rs/phone_gyro_video_20200109_145447/gyro_dump.txt", []),
]
COMMANDS = [
    ("flight", ["flight", "--json"]),
    ("noise", ["noise", "--json"]),
    ("accuracy", ["accuracy", "--json", "--reference-deg", "1"]),
    ("analyze", ["analyze", "--json", "--every", "2s"]),
]


def run(shutterlab, args):
    p = subprocess.run([shutterlab] + args, capture_output=True, text=True)
    data = None
    if p.returncode == 0:
        try:
            data = json.loads(p.stdout)
        except json.JSONDecodeError:
            data = None
    errors = [line for line in p.stderr.splitlines() if line.startswith("error:")]
    return p.returncode, data, errors[-1] if errors else ""


def kinds(warnings):
    counts = {}
    for w in warnings:
        counts[w["kind"]] = counts.get(w["kind"], 0) + 1
    return ", ".join(f"{k}" + (f" x{n}" if n > 1 else "") for k, n in counts.items()) or "none"


def outcome(name, code, data, error, path):
    if code != 0:
        text = error.replace("error: ", "").replace(path + ":", "")
        text = text.lstrip(": ")
        if text[:1].isdigit():
            text = "line " + text
        return f"exit {code}: " + (text if len(text) <= 110 else text[:107] + "...")
    if name == "flight":
        rows = data["rows"]
        refused = sum(1 for r in rows if r.get("too_few_samples"))
        return f"{len(rows) - refused} of {len(rows)} rows" + (
            f" ({refused} too few samples)" if refused else "")
    if name == "noise":
        return f"{data['windows']} windows"
    if name == "accuracy":
        return f"{len(data.get('rotations', []))} turns"
    verdict = data["verdict"]
    return (f"{verdict['images_in_trace']} images judged"
            + (f", {verdict.get('images_too_few_samples', 0)} too few samples"
               if verdict.get("images_too_few_samples") else ""))


def describe(shutterlab, path, flags, label):
    results = {}
    source, warnings = None, []
    for name, args in COMMANDS:
        code, data, error = run(shutterlab, args + flags + [path])
        results[name] = outcome(name, code, data, error, path)
        if name == "analyze" and data:
            source = data["source"]
            warnings = data["warnings"]
    if source:
        got = (f"{source['format']} {source['gyro']}: {source['samples']} samples, "
               f"{source['rate_hz']:.4g} Hz, {source['duration_s']:.1f} s")
    else:
        got = "(not read)"
    cells = [label, got, kinds(warnings)] + [results[name] for name, _ in COMMANDS]
    return "| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |"


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--shutterlab", default="build/bin/shutterlab")
    parser.add_argument("--data", default=os.environ.get("SHUTTERLAB_DATA_DIR", "../shared/data"))
    parser.add_argument("--only", default="", help="only the logs whose path holds this")
    args = parser.parse_args()
    if not any(args.only in rel for rel, _ in LOGS):
        print(f"real_logs.py: no log's path holds '{args.only}' (the list: LOGS in this script)",
              file=sys.stderr)
        return 2
    print("| log | read as | warnings (kinds) | flight | noise | accuracy | analyze --every 2s |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    with tempfile.TemporaryDirectory() as tmp:
        for rel, flags in LOGS:
            if args.only not in rel:
                continue
            path = os.path.join(args.data, rel)
            if not os.path.exists(path):
                print(f"missing: {path}", file=sys.stderr)
                continue
            print(describe(args.shutterlab, path, flags, rel))
            with open(path, "rb") as f:
                data = f.read()
            cut = os.path.join(tmp, "cut60_" + os.path.basename(rel))
            with open(cut, "wb") as f:
                f.write(data[: int(0.6 * len(data)) | 1])
            print(describe(args.shutterlab, cut, flags, f"{rel} cut at 60 %"))


if __name__ == "__main__":
    sys.exit(main())
