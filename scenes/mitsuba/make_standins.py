"""Write the meshes and images of the stand-in research scenes (interior-*.xml,
spheres-envmap.xml): binary little-endian PLY meshes with normals and UVs, an 8-bit PNG
texture and an equirectangular EXR sky. They are stand-ins written for kalos, not published
research scenes (those ship their PLY meshes as binary files this project cannot fetch).

    /tmp/mitsuba/bin/python scenes/mitsuba/make_standins.py

Needs numpy and mitsuba (for the PNG and EXR writers).
"""

import os
import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")
HERE = os.path.dirname(os.path.abspath(__file__))


def write_ply(name, pos, nrm, uv, tris):
    header = (
        "ply\nformat binary_little_endian 1.0\ncomment kalos stand-in scene mesh\n"
        f"element vertex {len(pos)}\n"
        "property float x\nproperty float y\nproperty float z\n"
        "property float nx\nproperty float ny\nproperty float nz\n"
        "property float u\nproperty float v\n"
        f"element face {len(tris)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    v = np.hstack([pos, nrm, uv]).astype("<f4")
    f = np.zeros(len(tris), dtype=[("n", "u1"), ("i", "<i4", 3)])
    f["n"] = 3
    f["i"] = tris
    os.makedirs(os.path.join(HERE, "meshes"), exist_ok=True)
    with open(os.path.join(HERE, "meshes", name), "wb") as fh:
        fh.write(header.encode())
        fh.write(v.tobytes())
        fh.write(f.tobytes())


def box(lo, hi, inward=False):
    """An axis-aligned box as 12 triangles, normals out (or in), uv per face."""
    lo, hi = np.array(lo, float), np.array(hi, float)
    pos, nrm, uv, tris = [], [], [], []
    for axis in range(3):
        for side in (0, 1):
            n = np.zeros(3)
            n[axis] = 1 if side else -1
            u_ax, v_ax = [a for a in range(3) if a != axis]
            corners = []
            for (a, b) in ((0, 0), (1, 0), (1, 1), (0, 1)):
                p = np.where(side, hi, lo).astype(float).copy()
                p[axis] = hi[axis] if side else lo[axis]
                p[u_ax] = hi[u_ax] if a else lo[u_ax]
                p[v_ax] = hi[v_ax] if b else lo[v_ax]
                corners.append((p, (a, b)))
            # counter-clockwise seen from the normal's side
            e1 = corners[1][0] - corners[0][0]
            e2 = corners[2][0] - corners[0][0]
            flip = np.dot(np.cross(e1, e2), n) < 0
            if inward:
                n = -n
                flip = not flip
            base = len(pos)
            for p, (a, b) in corners:
                pos.append(p)
                nrm.append(n)
                uv.append((a, b))
            t = [[0, 1, 2], [0, 2, 3]]
            if flip:
                t = [[0, 2, 1], [0, 3, 2]]
            tris += [[base + i for i in tri] for tri in t]
    return [np.array(x, float) for x in (pos, nrm, uv)] + [np.array(tris)]


def merge(*meshes):
    pos, nrm, uv, tris, off = [], [], [], [], 0
    for p, n, u, t in meshes:
        pos.append(p)
        nrm.append(n)
        uv.append(u)
        tris.append(t + off)
        off += len(p)
    return [np.vstack(x) for x in (pos, nrm, uv)] + [np.vstack(tris)]


def torus(R, r, nu=96, nv=48):
    u = np.linspace(0, 2 * np.pi, nu + 1)
    v = np.linspace(0, 2 * np.pi, nv + 1)
    U, V = np.meshgrid(u, v, indexing="ij")
    c = np.stack([np.cos(U), np.zeros_like(U), np.sin(U)], -1)
    n = np.cos(V)[..., None] * c + np.sin(V)[..., None] * np.array([0, 1, 0])
    p = R * c + r * n
    uv = np.stack([U / (2 * np.pi), V / (2 * np.pi)], -1)
    idx = np.arange((nu + 1) * (nv + 1)).reshape(nu + 1, nv + 1)
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c2, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    tris = np.concatenate([np.stack([a, d, b], 1), np.stack([b, d, c2], 1)])
    return p.reshape(-1, 3), n.reshape(-1, 3), uv.reshape(-1, 2), tris


def main():
    # the room: 6 x 3 x 5, walls facing in (one open window gap is left out: closed)
    write_ply("room.ply", *box((-3, 0, -2.5), (3, 3, 2.5), inward=True))
    # furniture: a sofa of three blocks, a table (top and four legs), a shelf
    sofa = merge(box((-2.6, 0, -2.4), (0.2, 0.45, -1.5)),
                 box((-2.6, 0.45, -2.4), (0.2, 1.0, -2.1)),
                 box((-2.6, 0.45, -2.1), (-2.3, 0.7, -1.5)))
    write_ply("sofa.ply", *sofa)
    legs = [box((x, 0, z), (x + 0.08, 0.7, z + 0.08))
            for x in (0.6, 1.9) for z in (-0.4, 0.5)]
    write_ply("table.ply", *merge(box((0.5, 0.7, -0.5), (2.1, 0.76, 0.7)), *legs))
    write_ply("shelf.ply", *merge(box((2.6, 0, 0.8), (2.95, 2.2, 2.3)),
                                  box((2.3, 1.0, 0.9), (2.6, 1.05, 2.2))))
    write_ply("torus.ply", *torus(0.35, 0.12))
    # a checker texture for the floor (8-bit sRGB PNG)
    n = 256
    ij = np.indices((n, n)).sum(0) // 32 % 2
    img = np.where(ij[..., None] == 1, [0.55, 0.42, 0.30], [0.35, 0.25, 0.16])
    os.makedirs(os.path.join(HERE, "textures"), exist_ok=True)
    mi.Bitmap(img.astype(np.float32)).convert(
        mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, srgb_gamma=True
    ).write(os.path.join(HERE, "textures", "floor.png"))
    # an equirectangular sky: blue above, warm ground, a bright sun disc
    h, w = 64, 128
    th = (np.arange(h) + 0.5) / h * np.pi
    ph = (np.arange(w) + 0.5) / w * 2 * np.pi
    TH, PH = np.meshgrid(th, ph, indexing="ij")
    up = np.cos(TH)
    sky = np.where(up[..., None] > 0,
                   np.array([0.35, 0.55, 1.0]) * (0.4 + 0.6 * up[..., None]),
                   np.array([0.3, 0.25, 0.2]))
    d = np.stack([np.sin(TH) * np.cos(PH), np.cos(TH), np.sin(TH) * np.sin(PH)], -1)
    sun = np.array([0.4, 0.8, 0.3])
    sun /= np.linalg.norm(sun)
    sky = sky + (d @ sun > 0.995)[..., None] * 200.0
    mi.Bitmap(sky.astype(np.float32)).write(os.path.join(HERE, "textures", "sky.exr"))


if __name__ == "__main__":
    main()
