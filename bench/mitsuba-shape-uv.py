"""Mitsuba 3's texture coordinates on its built-in and mesh shapes, by `ray_intersect`:
the known answers of tests/mitsuba_shape_uv.rs (the disk's polar uv, the cube's per-face
uv, a PLY's texture coordinates unflipped beside an OBJ's flipped ones). Rays run down
-z onto the disk, along -n onto each cube face, down -y onto the rectangle meshes.

    /work/mitsuba-venv/bin/python bench/mitsuba-shape-uv.py
"""
import os
import tempfile

import mitsuba as mi

mi.set_variant("scalar_rgb")
d = tempfile.mkdtemp()
VERTS = [(-2.85, 0, -7.6, 0.950589, 0.988416), (-2.85, 0, 0.6, 0.025105, 0.988416),
         (2.85, 0, 0.6, 0.025105, 0.689127), (2.85, 0, -7.6, 0.950589, 0.689127)]
with open(os.path.join(d, "rect.ply"), "w") as f:
    f.write("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
            "property float z\nproperty float u\nproperty float v\nelement face 2\n"
            "property list uchar int vertex_indices\nend_header\n")
    for v in VERTS:
        f.write(" ".join(map(str, v)) + "\n")
    f.write("3 0 1 2\n3 0 2 3\n")
with open(os.path.join(d, "rect.obj"), "w") as f:
    for v in VERTS:
        f.write(f"v {v[0]} {v[1]} {v[2]}\n")
    for v in VERTS:
        f.write(f"vt {v[3]} {v[4]}\n")
    f.write("f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n")


def show(shape, rays):
    s = mi.load_dict({"type": "scene", "s": shape})
    for o, dd in rays:
        si = s.ray_intersect(mi.Ray3f(o, dd))
        print(f"  ({o}, {dd}): uv ({si.uv[0]:.6f}, {si.uv[1]:.6f})")


print("disk")
show({"type": "disk"}, [([x, y, 1.0], [0, 0, -1]) for x, y in
                        [(0.5, 0.0), (0.0, 0.5), (-0.3, 0.0), (0.0, -0.9), (0.6, -0.1), (-0.08, 0.06)]])
print("cube")
cube_rays = []
for n in [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]:
    p = [0.3 if c == 0 else 3.0 * c for c in n]
    p[[i for i in range(3) if n[i] == 0][1]] = -0.6
    cube_rays.append((p, [-c for c in n]))
show({"type": "cube"}, cube_rays)
for kind in ["ply", "obj"]:
    print(kind)
    show({"type": kind, "filename": os.path.join(d, f"rect.{kind}")},
         [([1.0, 5.0, -3.0], [0, -1, 0]), ([-2.0, 5.0, 0.0], [0, -1, 0])])
