#!/usr/bin/env python3
"""Fetch three public research scenes in Mitsuba 3 XML from PyPI and make them renderable.

The scenes are the city models that NVIDIA's Sionna RT ships inside its wheel
(`sionna-rt` on PyPI, Apache License 2.0): Paris' Place de l'Etoile, Munich's centre and
Florence's centre, each a Mitsuba 3 XML file with hundreds of binary PLY meshes
(OpenStreetMap geometry, face normals). Nothing of them is committed to this repository:
this script downloads the wheel with pip (`pip download --no-deps sionna-rt==2.2.0`),
checks its SHA-256, and writes into scenes/mitsuba/public/ (ignored by git):

    public/LICENSE-sionna-rt     the wheel's licence file, as shipped
    public/SOURCE.txt            package, version, SHA-256, licence, what was changed
    public/<scene>/meshes/*.ply  the meshes, unchanged
    public/<scene>.xml           the scene, changed only as below

Sionna's scenes are made for radio propagation: their materials are Sionna's own plugin
`itu-radio-material` (an ITU-R P.2040 radio material, which Mitsuba 3 alone cannot load),
and they have no camera and no light. The script turns each into what Sionna RT's own
renderer (`sionna.rt.Scene.render`) draws: every `itu-radio-material` becomes a `twosided`
`diffuse` of the material's display colour (read from the wheel's
`ITURadioMaterial.ITU_MATERIAL_COLORS`), lit by a `constant` sky of radiance 1, with
Sionna's default `path` integrator depth (8). A perspective camera and an `hdrfilm` are
added (the view is this script's choice, written below). Both Mitsuba 3 and kalos then
read the same file (bench/mitsuba-xml.sh).

Besides, `etoile-rough.xml` is the same Etoile scene with the `metal` material as
Mitsuba's `roughconductor` (aluminium, alpha 0.1, Mitsuba's default distribution, which is
Beckmann) and `marble` as a `roughplastic` (alpha 0.2, Beckmann): a public scene with the
rough plugins as research scenes write them, without `distribution="ggx"`.

Usage (from anywhere; needs pip and network access to PyPI):

    python3 scenes/mitsuba/fetch_public.py            # fetch and write
    python3 scenes/mitsuba/fetch_public.py --wheel sionna_rt-2.2.0-py3-none-any.whl
"""

import argparse
import ast
import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET
import zipfile

PACKAGE = "sionna-rt"
VERSION = "2.2.0"
WHEEL = "sionna_rt-2.2.0-py3-none-any.whl"
SHA256 = "ffd5b5fea0fd3fee9d64a9e2b0ff1f2f4b4bfc010fa3d59d7479955fbdfc0e8e"
LICENCE_IN_WHEEL = "sionna_rt-2.2.0.dist-info/licenses/LICENSE"
COLOURS_IN_WHEEL = "sionna/rt/radio_materials/itu_material.py"

# Scene name -> camera (origin, target, up; z is up in Sionna's scenes), vertical fov.
# Chosen by looking at each scene's bounds (`kalos info`): an oblique view from above
# the streets, over the middle of the model.
SCENES = {
    "etoile": ((-330.0, -330.0, 260.0), (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 45.0),
    "munich": ((-220.0, -320.0, 200.0), (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 45.0),
    "florence": ((-220.0, -320.0, 200.0), (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 45.0),
}
WIDTH, HEIGHT = 256, 192


def fetch_wheel(dest):
    cmd = [sys.executable, "-m", "pip", "download", "--no-deps", "--only-binary", ":all:",
           f"{PACKAGE}=={VERSION}", "-d", dest]
    subprocess.run(cmd, check=True)
    return os.path.join(dest, WHEEL)


def sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def display_colours(source):
    """ITURadioMaterial.ITU_MATERIAL_COLORS from the wheel's source, without importing it."""
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Assign) and any(
                isinstance(t, ast.Name) and t.id == "ITU_MATERIAL_COLORS" for t in node.targets):
            return ast.literal_eval(node.value)
    raise SystemExit(f"fetch_public: no ITU_MATERIAL_COLORS in {COLOURS_IN_WHEEL}")


def rgb(parent, name, value):
    ET.SubElement(parent, "rgb", name=name, value=", ".join(f"{v:g}" for v in value))


def sionna_look(root, colours, rough=False):
    """Replace each itu-radio-material by what Sionna's renderer draws (see the docstring)."""
    for i, bsdf in enumerate(list(root)):
        if bsdf.tag != "bsdf" or bsdf.get("type") != "itu-radio-material":
            continue
        kind = next(c.get("value") for c in bsdf if c.get("name") == "type")
        colour = colours[kind]
        new = ET.Element("bsdf", type="twosided", id=bsdf.get("id"))
        if rough and kind == "metal":
            inner = ET.SubElement(new, "bsdf", type="roughconductor")
            ET.SubElement(inner, "string", name="material", value="Al")
            ET.SubElement(inner, "float", name="alpha", value="0.1")
        elif rough and kind == "marble":
            inner = ET.SubElement(new, "bsdf", type="roughplastic")
            rgb(inner, "diffuse_reflectance", colour)
            ET.SubElement(inner, "float", name="alpha", value="0.2")
        else:
            inner = ET.SubElement(new, "bsdf", type="diffuse")
            rgb(inner, "reflectance", colour)
        new.tail = bsdf.tail
        root.remove(bsdf)
        root.insert(i, new)


def add_camera_and_light(root, camera):
    (origin, target, up, fov) = camera
    integ = ET.Element("integrator", type="path")
    ET.SubElement(integ, "integer", name="max_depth", value="8")
    sensor = ET.Element("sensor", type="perspective")
    ET.SubElement(sensor, "float", name="fov", value=f"{fov:g}")
    ET.SubElement(sensor, "string", name="fov_axis", value="y")
    tw = ET.SubElement(sensor, "transform", name="to_world")
    fmt = lambda v: ", ".join(f"{x:g}" for x in v)
    ET.SubElement(tw, "lookat", origin=fmt(origin), target=fmt(target), up=fmt(up))
    sampler = ET.SubElement(sensor, "sampler", type="independent")
    ET.SubElement(sampler, "integer", name="sample_count", value="64")
    film = ET.SubElement(sensor, "film", type="hdrfilm")
    ET.SubElement(film, "integer", name="width", value=str(WIDTH))
    ET.SubElement(film, "integer", name="height", value=str(HEIGHT))
    ET.SubElement(film, "rfilter", type="box")
    sky = ET.Element("emitter", type="constant")
    rgb(sky, "radiance", (1.0, 1.0, 1.0))
    for k, el in enumerate((integ, sensor, sky)):
        el.tail = "\n"
        root.insert(k, el)


def write_scene(z, scene, out_dir, colours, camera, name=None, rough=False):
    name = name or scene
    prefix = f"sionna/rt/scenes/{scene}/"
    src = z.read(prefix + f"{scene}.xml").decode("utf-8")
    root = ET.fromstring(src)
    sionna_look(root, colours, rough)
    add_camera_and_light(root, camera)
    # Mesh paths are relative to the XML: point them into public/<scene>/.
    for s in root.iter("string"):
        if s.get("name") == "filename" and s.get("value", "").startswith("meshes/"):
            s.set("value", f"{scene}/{s.get('value')}")
    if not rough:
        for member in z.namelist():
            if member.startswith(prefix + "meshes/") and member.endswith(".ply"):
                target = os.path.join(out_dir, scene, "meshes", os.path.basename(member))
                os.makedirs(os.path.dirname(target), exist_ok=True)
                with z.open(member) as f, open(target, "wb") as g:
                    shutil.copyfileobj(f, g)
    header = (f"<!-- {name}: Sionna RT {VERSION}'s scene '{scene}' (PyPI {PACKAGE}, Apache-2.0,"
              f" see LICENSE-sionna-rt), written by scenes/mitsuba/fetch_public.py -->\n")
    with open(os.path.join(out_dir, f"{name}.xml"), "w", encoding="utf-8") as f:
        f.write(header + ET.tostring(root, encoding="unicode") + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--wheel", help="use this downloaded wheel instead of fetching it")
    ap.add_argument("--out", default=os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                  "public"))
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        wheel = args.wheel or fetch_wheel(tmp)
        digest = sha256(wheel)
        if digest != SHA256:
            raise SystemExit(f"fetch_public: {wheel}: SHA-256 {digest}, expected {SHA256}")
        os.makedirs(args.out, exist_ok=True)
        with zipfile.ZipFile(wheel) as z:
            colours = display_colours(z.read(COLOURS_IN_WHEEL).decode("utf-8"))
            with open(os.path.join(args.out, "LICENSE-sionna-rt"), "wb") as f:
                f.write(z.read(LICENCE_IN_WHEEL))
            for scene, camera in SCENES.items():
                write_scene(z, scene, args.out, colours, camera)
                print(f"fetch_public: wrote {os.path.join(args.out, scene + '.xml')}")
            write_scene(z, "etoile", args.out, colours, SCENES["etoile"],
                        name="etoile-rough", rough=True)
            print(f"fetch_public: wrote {os.path.join(args.out, 'etoile-rough.xml')}")
    with open(os.path.join(args.out, "SOURCE.txt"), "w", encoding="utf-8") as f:
        f.write(
            f"Source: PyPI package {PACKAGE} {VERSION}, file {WHEEL}\n"
            f"SHA-256: {SHA256}\n"
            "Licence: Apache License 2.0 (LICENSE-sionna-rt, from the wheel)\n"
            "Copyright (c) 2021-2026 NVIDIA CORPORATION & AFFILIATES\n"
            f"Scenes: {', '.join(SCENES)} (sionna/rt/scenes/<name>/ in the wheel)\n"
            "Changed: each itu-radio-material replaced by a twosided diffuse of its display\n"
            "colour (as Sionna's renderer draws it); a camera, film, constant sky of\n"
            "radiance 1 and path integrator (max_depth 8) added; mesh paths prefixed with\n"
            "the scene's folder. Meshes unchanged. etoile-rough.xml: metal as\n"
            "roughconductor (Al, alpha 0.1), marble as roughplastic (alpha 0.2), both with\n"
            "Mitsuba's default (Beckmann) distribution.\n")


if __name__ == "__main__":
    main()
