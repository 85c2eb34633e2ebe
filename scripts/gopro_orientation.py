#!/usr/bin/python3
"""What a GoPro's own orientation streams say, from an imported dataset alone (no images).

  /usr/bin/python3 scripts/gopro_orientation.py DIR

DIR is `shutterlab import`'s output for a GoPro that writes CORI and IORI (gyro.csv and
image_orientation.csv). Prints:
  - how well CORI's frame-to-frame rotations match the integrated gyro.csv (the best of the 24 axis
    labellings, either sense, and a time shift of the gyro within +-0.1 s): the relative squared
    residual and the mapping;
  - the median frame-to-frame rotation of the body (CORI) and of CORI x IORI and CORI x IORI^-1:
    the stabilised camera's orientation is the product that turns far less than the body.
Needs numpy (Debian's python3-numpy).
"""
import itertools
import sys

import numpy as np


def qmul(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


def qconj(q):
    return np.array([q[0], -q[1], -q[2], -q[3]])


def qexp(v):
    a = np.linalg.norm(v)
    if a < 1e-12:
        return np.array([1.0, v[0] / 2, v[1] / 2, v[2] / 2])
    return np.concatenate([[np.cos(a / 2)], np.sin(a / 2) * v / a])


def qlog(q):
    q = q / np.linalg.norm(q)
    if q[0] < 0:
        q = -q
    s = np.linalg.norm(q[1:])
    return 2 * q[1:] if s < 1e-12 else 2 * np.arctan2(s, q[0]) * q[1:] / s


def axis_rotations():
    out = []
    for p in itertools.permutations(range(3)):
        for signs in itertools.product([1, -1], repeat=3):
            m = np.zeros((3, 3))
            for i in range(3):
                m[i, p[i]] = signs[i]
            if np.linalg.det(m) > 0:
                out.append(m)
    return out


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    d = sys.argv[1]
    gyro = np.loadtxt(d + '/gyro.csv', delimiter=',', skiprows=1)
    orientation = np.loadtxt(d + '/image_orientation.csv', delimiter=',', skiprows=1)
    t_frame, iori, cori = orientation[:, 1], orientation[:, 3:7], orientation[:, 8:12]
    t = gyro[:, 0]
    body = [np.array([1.0, 0, 0, 0])]  # the integrated gyro, trapezoidal rates
    for k in range(1, len(t)):
        w = 0.5 * (gyro[k - 1, 1:4] + gyro[k, 1:4])
        body.append(qmul(body[-1], qexp(w * (t[k] - t[k - 1]))))

    def body_at(tt):
        k = min(max(np.searchsorted(t, tt) - 1, 0), len(t) - 2)
        a = (tt - t[k]) / (t[k + 1] - t[k])
        return qmul(body[k], qexp(a * qlog(qmul(qconj(body[k]), body[k + 1]))))

    def steps(q, sense=1):
        q = q if sense > 0 else np.array([qconj(x) for x in q])
        return np.array([qlog(qmul(qconj(q[k - 1]), q[k])) for k in range(1, len(q))])

    best = None
    for shift in np.arange(-0.1, 0.1, 0.005):
        inside = (t_frame[1:] + shift > t[0] + 0.02) & (t_frame[1:] + shift < t[-1] - 0.02)
        g = np.array([qlog(qmul(qconj(body_at(t_frame[k - 1] + shift)), body_at(t_frame[k] + shift)))
                      for k in range(1, len(t_frame))])
        for sense in (1, -1):
            c = steps(cori, sense)
            for m in axis_rotations():
                e = np.sum((g[inside] - (c @ m.T)[inside]) ** 2) / np.sum(g[inside] ** 2)
                if best is None or e < best[0]:
                    best = (e, shift, sense, m)
    e, shift, sense, m = best
    print('CORI against the integrated gyro: relative squared residual %.2g (gyro shifted %+.3f s, '
          'CORI read %s, axes %s)' % (e, shift, 'inverse' if sense < 0 else 'as written',
                                      m.astype(int).tolist()))

    def median_step(q):
        return np.median(np.linalg.norm(steps(q), axis=1))

    print('median rotation per frame: body (CORI) %.4f rad' % median_step(cori))
    for name, f in (('CORI x IORI', lambda c, i: qmul(c, i)),
                    ('CORI x IORI^-1', lambda c, i: qmul(c, qconj(i)))):
        q = np.array([f(c, i) for c, i in zip(cori, iori)])
        print('  %s %.4f rad (%.2fx the body)' % (name, median_step(q),
                                                   median_step(q) / median_step(cori)))


if __name__ == '__main__':
    main()
