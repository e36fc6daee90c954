#!/usr/bin/env python3
"""Fetch the FZK-Haus, a furnished house modelled by KIT, and write it as OBJ/MTL for kalos.

The FZK-Haus is the Karlsruhe Institute of Technology's (KIT / IAI) reference building for
IFC: a two-storey detached house with walls, windows and doors, stairs, a pitched roof on
beams and 21 pieces of furniture, modelled in ArchiCAD 14 (2010) by KIT, not by this
project. Debian ships it in its assimp test data (`assimp-testmodels` 5.2.5~ds0-1,
`usr/share/assimp/models/IFC/AC14-FZK-Haus.ifc`; the package is BSD-3-Clause and the
model's note beside it says "Used with permission and fine to redistribute, KIT/IAI would
appreciate if the attribution was retained"). Nothing of it is committed to this
repository: this script downloads the package with apt (`apt-get download`), checks its
SHA-256, and writes into scenes/ifc/public/ (ignored by git):

    public/AC14-FZK-Haus.ifc          the model, unchanged
    public/AC14-FZK-Haus.source.txt   the model's note (origin, permission), as shipped
    public/copyright-assimp           the package's copyright file, as shipped
    public/SOURCE.txt                 package, version, SHA-256, licence, what was changed
    public/fzk-haus.obj, .mtl         the triangles and materials, converted as below
    public/sky.obj, sky.mtl           the sky: an emitting box around the model
    public/fzk-haus.toml              the scene kalos renders: both OBJs and a camera
    public/venv/                      the converter's Python environment

IFC is a building model, not a mesh: walls are extruded profiles with the window openings
cut out, furniture is boundary representations. The conversion is IfcOpenShell's
(`ifcopenshell` 0.9.0.post1 from PyPI, LGPL-3.0-or-later, installed by this script into
public/venv), a tool outside the renderer: every element's triangles in world coordinates
(metres, z up), except the opening volumes and the room volumes (IfcOpeningElement,
IfcSpace), which are not surfaces. IfcOpenShell gives no vertex normals for this model:
every facet is shaded flat, as the model is faceted (its curved furniture included). Each
IFC surface style becomes one MTL material: `Kd` is the style's diffuse colour as
IfcOpenShell computes it; the styles give a specular colour but no highlight exponent, so
they are written diffuse; the one transparent style (transparency 0.88: the panes of the
windows and glazed doors, and the furniture's glass) is written as glass (`illum 7`,
`Ni 1.5`, the index of window glass; the panes are 2 cm solid boxes), since an IFC
transparency asks for a see-through pane.

The model has no light, as an architect's model has none: it is lit as such a house is,
by daylight through its windows: a uniform sky of radiance 1 around it, beyond the model's
own site plane. The sky is a closed box of emitting triangles facing inwards (sky.obj,
`Ke 1 1 1`, `Kd 0`), 5 m outside the model's bounds: inside it every direction sees
radiance 1, as under a constant environment, but as an area light it is one that every
estimator kalos has can sample (BDPT and the radiosity solution know area lights only).
The camera (below) stands in the ground floor's living room, looking along it; it is
this script's choice.

Usage (from anywhere; needs apt-get with Debian's package lists, pip, and network access
to Debian and PyPI):

    python3 scenes/ifc/fetch_fzk_haus.py            # fetch, convert and write
    python3 scenes/ifc/fetch_fzk_haus.py --deb assimp-testmodels_5.2.5~ds0-1_all.deb
"""

import argparse
import hashlib
import os
import shutil
import subprocess
import sys
import tempfile

PACKAGE = "assimp-testmodels"
VERSION = "5.2.5~ds0-1"
DEB = "assimp-testmodels_5.2.5~ds0-1_all.deb"
SHA256 = "526f326186000cd6f631ea806128548a7d3d391abd8149fddc5c4c8513e80b8a"
IFC_IN_DEB = "usr/share/assimp/models/IFC/AC14-FZK-Haus.ifc"
NOTE_IN_DEB = "usr/share/assimp/models/IFC/AC14-FZK-Haus.source.txt"
COPYRIGHT_IN_DEB = "usr/share/doc/assimp-testmodels/copyright"
CONVERTER = "ifcopenshell==0.9.0.post1"

# Elements that are volumes, not surfaces.
NOT_SURFACES = ("IfcOpeningElement", "IfcSpace")
GLASS_IOR = 1.5

# Camera: origin, target, up (z is up in the model), vertical field of view in degrees.
# In the ground floor's living room ("Wohnen", x 3.8-11.7 m, y 0.3-4.0 m) at its west end,
# at eye height, looking east along it: the terrace door and a window on the right, the
# spiral stair, the fireplace and the east window ahead.
CAMERA = ((4.3, 0.8, 1.6), (11.0, 3.0, 1.0), (0.0, 0.0, 1.0), 70.0)
RES = (160, 120)
SKY_RADIANCE = 1.0
SKY_MARGIN = 5.0  # metres between the model's bounds and the sky box


def sha256(path):
    with open(path, "rb") as f:
        return hashlib.file_digest(f, "sha256").hexdigest()  # Python 3.11


def fetch_deb(dest):
    subprocess.run(["apt-get", "download", f"{PACKAGE}={VERSION}"], check=True, cwd=dest)
    return os.path.join(dest, DEB)


def venv_python(out):
    """The converter's environment: public/venv with the pinned IfcOpenShell."""
    venv = os.path.join(out, "venv")
    py = os.path.join(venv, "bin", "python")
    if not os.path.exists(py):
        subprocess.run([sys.executable, "-m", "venv", venv], check=True)
        subprocess.run([py, "-m", "pip", "install", "--quiet", CONVERTER], check=True)
    return py


def value(attr):
    """An IfcOpenShell material field: a method in some versions, a value in others."""
    return attr() if callable(attr) else attr


def convert(ifc_path, obj_path, mtl_path):
    """Run inside the converter's environment: IFC -> OBJ + MTL (see the module text)."""
    import ifcopenshell
    import ifcopenshell.geom

    model = ifcopenshell.open(ifc_path)
    settings = ifcopenshell.geom.settings()
    settings.set("use-world-coords", True)
    it = ifcopenshell.geom.iterator(settings, model, 1, exclude=NOT_SURFACES)
    if not it.initialize():
        sys.exit(f"{ifc_path}: IfcOpenShell found no geometry")
    materials = {}  # style name -> (name in the MTL, diffuse, glass)
    groups = {}  # MTL name -> list of triangles (three 1-based vertex indices)
    verts = []
    while True:
        shape = it.get()
        geom = shape.geometry
        base = len(verts)
        v = geom.verts
        verts.extend(tuple(v[i:i + 3]) for i in range(0, len(v), 3))
        names = []
        for m in geom.materials:
            if m.name not in materials:
                glass = value(m.has_transparency) and value(m.transparency) > 0.0
                mtl_name = f"style{len(materials)}_{m.name.rsplit('-', 1)[-1]}"
                materials[m.name] = (mtl_name, tuple(m.diffuse.components), glass)
            names.append(materials[m.name][0])
        f, ids = geom.faces, geom.material_ids
        for t in range(len(f) // 3):
            mid = ids[t] if t < len(ids) else -1
            name = names[mid] if 0 <= mid < len(names) else "unstyled"
            groups.setdefault(name, []).append(tuple(base + f[3 * t + k] + 1 for k in range(3)))
        if not it.next():
            break
    with open(mtl_path, "w", encoding="utf-8") as out:
        out.write(f"# From {os.path.basename(ifc_path)} by IfcOpenShell; see SOURCE.txt\n")
        for mtl_name, kd, glass in sorted(materials.values()):
            out.write(f"\nnewmtl {mtl_name}\nKd {kd[0]:.6f} {kd[1]:.6f} {kd[2]:.6f}\n")
            out.write(f"Ni {GLASS_IOR}\nillum 7\n" if glass else "Ks 0 0 0\nillum 2\n")
        if "unstyled" in groups:
            out.write("\nnewmtl unstyled\nKd 0.8 0.8 0.8\nKs 0 0 0\nillum 2\n")
    with open(obj_path, "w", encoding="utf-8") as out:
        out.write(f"# From {os.path.basename(ifc_path)} by IfcOpenShell; see SOURCE.txt\n")
        out.write(f"mtllib {os.path.basename(mtl_path)}\n")
        out.writelines(f"v {x:.6f} {y:.6f} {z:.6f}\n" for x, y, z in verts)
        for name in sorted(groups):
            out.write(f"usemtl {name}\n")
            out.writelines(f"f {a} {b} {c}\n" for a, b, c in groups[name])
    tris = sum(len(g) for g in groups.values())
    print(f"{obj_path}: {tris} triangles, {len(materials)} materials")


def obj_bounds(obj_path):
    lo, hi = [float("inf")] * 3, [float("-inf")] * 3
    with open(obj_path, encoding="utf-8") as f:
        for line in f:
            if line.startswith("v "):
                p = [float(c) for c in line.split()[1:4]]
                lo = [min(a, b) for a, b in zip(lo, p)]
                hi = [max(a, b) for a, b in zip(hi, p)]
    return lo, hi


def write_sky(obj_path, mtl_path, lo, hi):
    """A closed box SKY_MARGIN outside (lo, hi), every face emitting towards the inside."""
    lo = [c - SKY_MARGIN for c in lo]
    hi = [c + SKY_MARGIN for c in hi]
    corner = [(x, y, z) for z in (lo[2], hi[2]) for y in (lo[1], hi[1]) for x in (lo[0], hi[0])]
    # Corners indexed x + 2y + 4z (1-based in the OBJ); each quad counter-clockwise as seen
    # from inside the box, the side `Ke` emits on.
    quads = ((1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4))
    with open(mtl_path, "w", encoding="utf-8") as f:
        f.write(f"newmtl sky\nKd 0 0 0\nKs 0 0 0\nKe {SKY_RADIANCE:g} {SKY_RADIANCE:g} "
                f"{SKY_RADIANCE:g}\nillum 2\n")
    with open(obj_path, "w", encoding="utf-8") as f:
        f.write(f"# A uniform sky around the FZK-Haus; see SOURCE.txt\nmtllib "
                f"{os.path.basename(mtl_path)}\n")
        f.writelines(f"v {x:g} {y:g} {z:g}\n" for x, y, z in corner)
        f.write("usemtl sky\n")
        f.writelines(f"f {a} {b} {c} {d}\n" for a, b, c, d in quads)


def write_toml(path, obj_name, sky_name):
    (o, t, u, fov) = CAMERA
    vec = lambda p: "[" + ", ".join(f"{c:g}" for c in p) + "]"  # noqa: E731
    with open(path, "w", encoding="utf-8") as f:
        f.write(f"""# The FZK-Haus (KIT / IAI) under a uniform sky; see SOURCE.txt
[camera]
origin = {vec(o)}
target = {vec(t)}
up = {vec(u)}
fov = {fov:g}

[render]
res = [{RES[0]}, {RES[1]}]

[[objects]]
file = "{obj_name}"

[[objects]]
file = "{sky_name}"
""")


def main():
    if len(sys.argv) == 5 and sys.argv[1] == "--convert":
        convert(*sys.argv[2:])
        return
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--deb", help="use this downloaded package instead of fetching it")
    ap.add_argument("--out", default=os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                  "public"))
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        deb = os.path.abspath(args.deb) if args.deb else fetch_deb(tmp)
        got = sha256(deb)
        if got != SHA256:
            sys.exit(f"{deb}: SHA-256 {got}, expected {SHA256} ({PACKAGE} {VERSION})")
        tree = os.path.join(tmp, "deb")
        subprocess.run(["dpkg-deb", "-x", deb, tree], check=True)
        for inside, name in ((IFC_IN_DEB, None), (NOTE_IN_DEB, None),
                             (COPYRIGHT_IN_DEB, "copyright-assimp")):
            shutil.copyfile(os.path.join(tree, inside),
                            os.path.join(args.out, name or os.path.basename(inside)))
    ifc = os.path.join(args.out, os.path.basename(IFC_IN_DEB))
    obj = os.path.join(args.out, "fzk-haus.obj")
    mtl = os.path.join(args.out, "fzk-haus.mtl")
    subprocess.run([venv_python(args.out), os.path.abspath(__file__), "--convert", ifc, obj, mtl],
                   check=True)
    write_sky(os.path.join(args.out, "sky.obj"), os.path.join(args.out, "sky.mtl"),
              *obj_bounds(obj))
    write_toml(os.path.join(args.out, "fzk-haus.toml"), os.path.basename(obj), "sky.obj")
    with open(os.path.join(args.out, "SOURCE.txt"), "w", encoding="utf-8") as f:
        f.write(f"""Package: {PACKAGE} {VERSION} (Debian), SHA-256 {SHA256}
Model: {IFC_IN_DEB}, by KIT / IAI (Karlsruhe Institute of Technology), ArchiCAD 14, 2010
Licence: the package BSD-3-Clause (copyright-assimp); the model "used with permission and
fine to redistribute, KIT/IAI would appreciate if the attribution was retained"
(AC14-FZK-Haus.source.txt)
Converted by: {CONVERTER} (PyPI, LGPL-3.0-or-later), in venv/
Written: fzk-haus.obj SHA-256 {sha256(obj)}, fzk-haus.mtl SHA-256 {sha256(mtl)}
Changed: openings and room volumes left out; surface styles written as Lambertian Kd, the
transparent style as glass (illum 7, Ni {GLASS_IOR}); a uniform sky of radiance
{SKY_RADIANCE:g} (sky.obj: an emitting box {SKY_MARGIN:g} m outside the model's bounds) and a
camera added (fzk-haus.toml); see scenes/ifc/fetch_fzk_haus.py
""")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
