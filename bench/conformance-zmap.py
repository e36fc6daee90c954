"""Where a kalos image fails Mitsuba's render-test protocol: the per-pixel XYZ Z-test of
tests/mitsuba_conformance.rs against a reference mean and variance, summarised per block of
32 image columns (bad pixel-channels, rows, median z, kalos' and the reference's mean Y).

    kalos render SCENE.xml -D spp=N -D integrator=I --spp N --seed 0 -o k.exr
    /work/mitsuba-venv/bin/python bench/conformance-zmap.py k.exr tests/conformance/NAME.exr \
        tests/conformance/NAME-var.exr N
"""
import sys
from math import erfc

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")
img, ref, var, spp = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
XYZ = np.array([[0.412453, 0.357580, 0.180423],
                [0.212671, 0.715160, 0.072169],
                [0.019334, 0.119193, 0.950227]])


def load(p):
    b = mi.Bitmap(p).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, srgb_gamma=False)
    return np.array(b, dtype=np.float64) @ XYZ.T


a, r, v = load(img), load(ref), load(var)
h, w, _ = a.shape
z = np.abs(a - r) * np.sqrt(spp / np.maximum(v, 1e-4))
alpha = 1 - (1 - 0.01) ** (1 / (w * h))
bad = np.vectorize(erfc)(z / np.sqrt(2)) <= alpha
print(f"{w}x{h}: {100 * (1 - bad.mean()):.3f}% of pixel-channels accepted, {bad.sum()} not")
sel, zz = bad.any(axis=2), z.max(axis=2)
for c in range(0, w, 32):
    m = sel[:, c:c + 32]
    if m.any():
        rows = np.nonzero(m)[0]
        print(f"columns {c}-{c + 31}: {bad[:, c:c + 32].sum()} bad, rows {rows.min()}-{rows.max()}, "
              f"median z {np.median(zz[:, c:c + 32][m]):.1f}, "
              f"kalos Y {a[:, c:c + 32][m][:, 1].mean():.3f}, reference Y {r[:, c:c + 32][m][:, 1].mean():.3f}")
