#!/usr/bin/env python3
"""The angle between the gyro_to_camera a validation report identified and the injected one.

  scripts/rotation_error.py REPORT.json R00,R01,...,R22

Reads the report's first gyro_to_camera effect at full precision (the table rounds it to 4 digits,
too coarse for tenths of a degree) and prints theta of R_found^T R_true, trace = 1 + 2 cos theta.
Standard library only.
"""
import json
import math
import sys


def main():
    report, truth = sys.argv[1], [float(x) for x in sys.argv[2].split(",")]
    effects = json.load(open(report))["effects"]
    found = next((e["value"] for e in effects if e["name"] == "gyro_to_camera"), None)
    if found is None:
        sys.exit(f"{report}: no gyro_to_camera effect identified")
    trace = sum(found[i // 3][i % 3] * truth[i] for i in range(9))
    cos = max(-1.0, min(1.0, (trace - 1) / 2))
    print(f"gyro_to_camera found within {math.degrees(math.acos(cos)):.3f} deg of the injected rotation")


if __name__ == "__main__":
    main()
