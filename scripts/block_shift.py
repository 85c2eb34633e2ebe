#!/usr/bin/python3
"""The best whole-pixel shift of a block of rows between two frames: a check of what a region
does that needs no flow and no model.

  /usr/bin/python3 scripts/block_shift.py EARLIER LATER ROW_FROM ROW_TO [MAX_SHIFT_PX]

For every (dx, dy) with |dx| <= MAX_SHIFT_PX / 2 and |dy| <= MAX_SHIFT_PX (default 16), the mean
squared grey difference between LATER's rows [ROW_FROM, ROW_TO) (columns 40 .. width - 40) and
EARLIER's same block moved by (dx, dy), each block less its own mean; prints the best shift (d =
its match in EARLIER minus the pixel in LATER, validate's video convention), its difference and
the difference at no shift. Needs numpy and PIL (Debian's python3-numpy, python3-pil).
"""
import sys

import numpy as np
from PIL import Image


def grey(path):
    return np.asarray(Image.open(path).convert('L'), dtype=float)


def main():
    if len(sys.argv) not in (5, 6):
        sys.exit(__doc__)
    earlier, later = grey(sys.argv[1]), grey(sys.argv[2])
    lo, hi = int(sys.argv[3]), int(sys.argv[4])
    reach = int(sys.argv[5]) if len(sys.argv) == 6 else 16
    if lo - reach < 0 or hi + reach > later.shape[0]:
        sys.exit('block_shift: rows %d..%d with shifts of %d px leave the image' % (lo, hi, reach))
    c0, c1 = 40, later.shape[1] - 40
    p = later[lo:hi, c0:c1] - later[lo:hi, c0:c1].mean()
    cost = {}
    for dy in range(-reach, reach + 1):
        for dx in range(-(reach // 2), reach // 2 + 1):
            q = earlier[lo + dy:hi + dy, c0 + dx:c1 + dx]
            cost[(dx, dy)] = np.mean((p - (q - q.mean())) ** 2)
    best = min(cost, key=cost.get)
    print('rows %d..%d: best shift (%d, %d) px, mean squared difference %.1f, at no shift %.1f' %
          (lo, hi, best[0], best[1], cost[best], cost[(0, 0)]))


if __name__ == '__main__':
    main()
