#!/usr/bin/python3
"""The per-axis flight analysis (docs/FORMATS.md `flight`) in pandas, to compare with `shutterlab flight`.

Same definitions as estimate/flight: bias = per-axis mean rate over the first 5 s; angles =
cumulative sum of (w - b) * dt over the samples after the segment; a window of duration W starts at
every sample and holds the samples with t in [t_k, t_k + W); windows that run past the last sample
are left out; flagged when any axis's range (rolling max - min) exceeds atan(limit/altitude) + 20".

pandas' time-based rolling windows look back, (s - W, s]. Reversing time (s = t_last - t, increasing
after reversing the rows) turns that into exactly the forward window [t_k, t_k + W).

Usage: /usr/bin/python3 scripts/pandas_flight_bench.py [GYRO_CSV]   (default: the bench's file,
/tmp/shutterlab_bench_gyro.csv, made by build-*/bin/analysis_bench). Times are this process's CPU
time, to match analysis_bench.
"""
import math
import sys
import time

import numpy as np
import pandas as pd

ALTITUDE_M = 50.0
LIMITS_M = (0.05, 0.10)
WINDOWS_S = (0.010, 0.020)
ALLOWANCE_ARCSEC = 20.0
BIAS_END_S = 5.0
ARCSEC_PER_RAD = 180 * 3600 / math.pi


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else "/tmp/shutterlab_bench_gyro.csv"
    t0 = time.process_time()
    df = pd.read_csv(path, usecols=[0, 1, 2, 3], dtype=np.float64, engine="c")
    t_read = time.process_time() - t0
    n_all = len(df)

    t0 = time.process_time()
    t_ns = np.rint(df.iloc[:, 0].to_numpy() * 1e9).astype(np.int64)
    rates = df.iloc[:, 1:4].to_numpy()
    first = int(np.searchsorted(t_ns, t_ns[0] + int(round(BIAS_END_S * 1e9)), side="left"))
    bias = rates[:first].mean(axis=0)
    t_ns = t_ns[first:]
    dt = np.diff(t_ns) * 1e-9
    angles = np.zeros((len(t_ns), 3))
    angles[1:] = np.cumsum((rates[first + 1:] - bias) * dt[:, None], axis=0)
    # Reversed time as the index: s = t_last - t, increasing after reversing the rows.
    index = pd.to_timedelta((t_ns[-1] - t_ns)[::-1], unit="ns")
    frame = pd.DataFrame(angles[::-1], index=index, columns=["x", "y", "z"])
    rows = []
    for window_s in WINDOWS_S:
        window_ns = int(round(window_s * 1e9))
        rolling = frame.rolling(pd.Timedelta(window_ns, unit="ns"), closed="right")
        ranges = (rolling.max() - rolling.min()).to_numpy()[::-1]
        windows = int(np.searchsorted(t_ns, t_ns[-1] - window_ns, side="right"))
        max_range = ranges[:windows].max(axis=1)
        for limit_m in LIMITS_M:
            threshold = math.atan(limit_m / ALTITUDE_M) + ALLOWANCE_ARCSEC / ARCSEC_PER_RAD
            rows.append((limit_m, window_s, threshold * ARCSEC_PER_RAD, windows,
                         100.0 * np.count_nonzero(max_range > threshold) / windows))
    t_analysis = time.process_time() - t0

    print(f"pandas {pd.__version__}, numpy {np.__version__}; {path}: {n_all} samples")
    print(f"read_csv:            {t_read:8.2f} s CPU")
    print(f"per-axis analysis:   {t_analysis:8.2f} s CPU  ({len(t_ns) / t_analysis / 1e6:.2f} M samples/s, "
          f"{len(WINDOWS_S)} windows x {len(LIMITS_M)} limits)")
    print("limit_m  window_s  threshold_arcsec  windows  flagged_percent")
    for limit_m, window_s, threshold, windows, percent in sorted(rows):
        print(f"{limit_m:7.3f}  {window_s:8.3f}  {threshold:16.1f}  {windows:7d}  {percent:15.4f}")


if __name__ == "__main__":
    main()
