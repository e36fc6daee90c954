"""Writes the large-mesh benchmark scene of bench/compare-mitsuba.sh: a closed room (diffuse
walls facing inwards, a downward-facing light quad under the ceiling) whose floor is a
height field of about 1M triangles. Only Kd/Ke materials, so that kalos and Mitsuba
(render_obj.py) render the same scene with the same BSDFs.

With --open the field stands alone under one light (no walls, no ceiling): the open scene
seen from above, where most paths leave the scene after a bounce or two and the camera and
shadow rays are coherent.

Usage: python heightfield.py OUT.obj [TRIANGLES] [--open]   (needs numpy; y is up)
"""
import os
import sys

import numpy as np

argv = [a for a in sys.argv[1:] if a != "--open"]
open_scene = len(argv) < len(sys.argv) - 1
if not argv or len(argv) > 2:
    sys.exit("heightfield.py: usage: heightfield.py OUT.obj [TRIANGLES] [--open]")
out = argv[0]
target = int(argv[1]) if len(argv) > 1 else 1_000_000
n = int((target / 2) ** 0.5)  # n x n cells, 2 triangles each
xs = np.linspace(-1.0, 1.0, n + 1)
x, z = np.meshgrid(xs, xs, indexing="ij")
y = 0.08 * np.sin(9 * x) * np.cos(7 * z) + 0.03 * np.sin(31 * x + 17 * z) + 0.02 * np.cos(45 * z - 13 * x)
verts = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)
idx = np.arange((n + 1) * (n + 1)).reshape(n + 1, n + 1) + 1
a, b, c, d = idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]
# (x, z) -> (x + dx, z) -> (x + dx, z + dz) winds clockwise seen from +y: reverse for an upward normal
field = np.concatenate([np.stack([a, c, b], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)])

lo, hi, top = -0.5, 1.0, 2.0
walls = [  # quads wound counter-clockwise seen from inside
    [(-hi, lo, -hi), (-hi, top, -hi), (hi, top, -hi), (hi, lo, -hi)][::-1],  # back, faces +z
    [(-hi, lo, hi), (-hi, top, hi), (hi, top, hi), (hi, lo, hi)],  # front, faces -z
    [(-hi, lo, -hi), (-hi, lo, hi), (-hi, top, hi), (-hi, top, -hi)][::-1],  # left, faces +x
    [(hi, lo, -hi), (hi, lo, hi), (hi, top, hi), (hi, top, -hi)],  # right, faces -x
    [(-hi, top, -hi), (hi, top, -hi), (hi, top, hi), (-hi, top, hi)],  # ceiling, faces -y
]
light = [(-0.3, top - 0.01, -0.3), (0.3, top - 0.01, -0.3), (0.3, top - 0.01, 0.3), (-0.3, top - 0.01, 0.3)]

def normal(q):
    p = np.array(q)
    return np.cross(p[1] - p[0], p[2] - p[0])

assert normal(walls[0])[2] > 0 and normal(walls[1])[2] < 0 and normal(walls[2])[0] > 0
assert normal(walls[3])[0] < 0 and normal(walls[4])[1] < 0 and normal(light)[1] < 0
v0 = verts[a.ravel()[0] - 1]
assert np.cross(verts[field[0][1] - 1] - v0, verts[field[0][2] - 1] - v0)[1] > 0

mtl = os.path.splitext(out)[0] + ".mtl"
with open(out, "w") as f:
    f.write(f"mtllib {os.path.basename(mtl)}\n")
    f.write("".join(f"v {p[0]:.6f} {p[1]:.6f} {p[2]:.6f}\n" for p in verts))
    nv = len(verts)
    def quads(name, qs):
        global nv
        f.write(f"usemtl {name}\n")
        for q in qs:
            f.write("".join(f"v {p[0]} {p[1]} {p[2]}\n" for p in q))
            f.write(f"f {nv + 1} {nv + 2} {nv + 3}\nf {nv + 1} {nv + 3} {nv + 4}\n")
            nv += 4
    if open_scene:
        # one light above the field, larger and brighter than the closed room's: the same
        # downward-facing quad, at 1.5 above the field's mean height
        quads("light", [[(2 * x, 1.5, 2 * z) for x, _, z in light]])
    else:
        quads("wall", walls)
        quads("light", [light])
    f.write("usemtl field\n")
    np.savetxt(f, field, fmt="f %d %d %d")
with open(mtl, "w") as f:
    f.write("newmtl wall\nKd 0.7 0.7 0.7\nnewmtl light\nKd 0 0 0\nKe 20 20 20\nnewmtl field\nKd 0.6 0.5 0.4\n")
print(f"wrote {out}: {len(field) + (2 if open_scene else 12)} triangles ({len(field)} in the height field)", file=sys.stderr)
