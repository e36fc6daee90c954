#!/usr/bin/env python3
"""Bisect a disagreement between kalos and Mitsuba 3 on a textured principled scene.

Writes variants of one of Mitsuba's render-test scenes (test_texturedprincipled{1,2,thin}_path)
to a work folder: the scene as it is; every checkerboard replaced by a constant (its color0
everywhere, then its color1 everywhere); from the color0 variant, one parameter at a time back
to its checkerboard; from the color0 variant, one lobe at a time switched off (or metallic at
0 and 1). Each variant is rendered by Mitsuba 3 (the scene's own `moment` integrator, so the
per-pixel variance is known) and by kalos (`kalos render --method plain`), and a line per
variant is printed:

    variant  kalos/Mitsuba mean ratio per RGB channel  accepted%  worst region

`accepted%` is Mitsuba's render-test Z-test (per pixel and XYZ channel, z = |k - m| /
sqrt(var_m / spp_m + var_m / spp_k), Sidak-corrected alpha 0.01) at this spp; `worst`
names the 8x8 block of the 48x48 image (row, column) where the two differ most.

Usage (from the repository root; kalos built with `cargo build --release`):

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 \
    nice -n 19 /work/mitsuba-venv/bin/python bench/principled-bisect.py \
        test_texturedprincipled1_path [--spp 868] [--variant llvm_ad_rgb] [--only NAME...]
"""

import argparse
import copy
import math
import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

HERE = Path(__file__).resolve().parent.parent


def shared_scenes():
    env = os.environ.get("KALOS_CONFORMANCE_DIR")
    if env:
        return Path(env) / "mitsuba/tests/scenes"
    for d in HERE.parents:
        if (d / "shared/conformance").is_dir():
            return d / "shared/conformance/mitsuba/tests/scenes"
    sys.exit("principled-bisect: no shared/conformance folder found (set KALOS_CONFORMANCE_DIR)")


def load(scene_file):
    """The scene's tree with its <path> and <include> made absolute."""
    tree = ET.parse(scene_file)
    root = tree.getroot()
    for p in root.iter("path"):
        p.set("value", str((scene_file.parent / p.get("value")).resolve()))
    for inc in root.iter("include"):
        inc.set("filename", str((scene_file.parent / inc.get("filename")).resolve()))
    return tree


def bsdf_of(tree):
    for b in tree.getroot().iter("bsdf"):
        if b.get("type") in ("principled", "principledthin"):
            return b
    sys.exit("principled-bisect: the scene has no principled bsdf")


def checkers(bsdf):
    """{parameter: (color0, color1)} of the bsdf's checkerboard textures."""
    out = {}
    for t in bsdf.findall("texture"):
        if t.get("type") == "checkerboard":
            c = {f.get("name"): f.get("value") for f in t.findall("float")}
            out[t.get("name")] = (c.get("color0", "0.4"), c.get("color1", "0.2"))
    return out


def set_value(bsdf, name, value):
    for child in list(bsdf):
        if child.get("name") == name:
            bsdf.remove(child)
    ET.SubElement(bsdf, "float", {"name": name, "value": str(value)})


def variants(tree):
    """[(name, tree)] in bisection order."""
    base_bsdf = bsdf_of(tree)
    ch = checkers(base_bsdf)
    out = [("as is", tree)]

    def constant(k, keep=()):
        t = copy.deepcopy(tree)
        b = bsdf_of(t)
        for name, cs in ch.items():
            if name not in keep:
                set_value(b, name, cs[k])
        return t

    out.append(("all color0", constant(0)))
    out.append(("all color1", constant(1)))
    for name in ch:
        out.append((f"color0, {name} checker", constant(0, keep=(name,))))
    thin = base_bsdf.get("type") == "principledthin"
    lobes = [("anisotropic", 0), ("sheen", 0), ("spec_trans", 0)]
    if thin:
        lobes += [("diff_trans", 0)]
    else:
        lobes += [("clearcoat", 0), ("metallic", 0), ("metallic", 1), ("specular", 0)]
    for name, v in lobes:
        t = constant(0)
        set_value(bsdf_of(t), name, v)
        out.append((f"color0, {name} {v}", t))
    t = constant(0)
    b = bsdf_of(t)
    for name in ch:
        set_value(b, name, 0)
    out.append(("color0, all checkered params 0", t))
    return out


def mitsuba_render(mi, np, path, spp):
    """(mean RGB, mean XYZ, per-sample XYZ variance) of the scene's moment integrator."""
    scene = mi.load_file(str(path), spp=spp, integrator="path")
    film = scene.sensors()[0].film()
    mi.render(scene, seed=1, spp=spp)
    layers = dict(film.bitmap().split())
    keys = [n for n in layers if n != "<root>"]
    m = np.array(layers[[n for n in keys if not n.startswith("m2_")][0]], dtype=np.float64)
    s = np.array(layers[[n for n in keys if n.startswith("m2_")][0]], dtype=np.float64)
    xyz = mi.Bitmap(m.astype(np.float32), mi.Bitmap.PixelFormat.XYZ)
    rgb = np.array(xyz.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False))
    return rgb.astype(np.float64), m, np.maximum(s - m * m, 1e-4)


def kalos_render(mi, np, kalos, path, spp, out):
    subprocess.run(
        [kalos, "render", str(path), "--spp", str(spp), "--method", "plain", "--output", str(out)],
        check=True,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    bm = mi.Bitmap(str(out))
    rgb = np.array(bm, dtype=np.float64)[..., :3]
    xyz = np.array(
        mi.Bitmap(rgb.astype(np.float32), mi.Bitmap.PixelFormat.RGB).convert(
            mi.Bitmap.PixelFormat.XYZ, mi.Struct.Type.Float32, False
        ),
        dtype=np.float64,
    )
    return rgb, xyz


def compare(np, km, kx, mm, mx, var, spp_m, spp_k):
    ratio = km.reshape(-1, 3).sum(0) / np.maximum(mm.reshape(-1, 3).sum(0), 1e-30)
    z = np.abs(kx - mx) / np.sqrt(var / spp_m + var / spp_k)
    p = np.vectorize(lambda z: math.erfc(z / math.sqrt(2.0)))(z)
    h, w = z.shape[:2]
    alpha = 1.0 - (1.0 - 0.01) ** (1.0 / (h * w))
    accepted = 100.0 * (p > alpha).mean()
    d = np.abs(km - mm).sum(-1)
    b = 8
    blocks = d[: h // b * b, : w // b * b].reshape(h // b, b, w // b, b).sum((1, 3))
    r, c = np.unravel_index(np.argmax(blocks), blocks.shape)
    sub = (slice(r * b, (r + 1) * b), slice(c * b, (c + 1) * b))
    br = km[sub].reshape(-1, 3).sum(0) / np.maximum(mm[sub].reshape(-1, 3).sum(0), 1e-30)
    return ratio, accepted, (r, c, br)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", help="scene stem, e.g. test_texturedprincipled1_path")
    ap.add_argument("--spp", type=int, default=868)
    ap.add_argument("--mitsuba-spp", type=int, default=4 * 868)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--work", default="/tmp/principled-bisect")
    ap.add_argument("--kalos", default=str(HERE / "target/release/kalos"))
    ap.add_argument("--only", nargs="*", help="variant names to render (default: all)")
    a = ap.parse_args()

    import mitsuba as mi
    import numpy as np

    mi.set_variant(a.variant)
    src = shared_scenes() / "bsdf_spheres" / f"{a.scene}.xml"
    if not src.is_file():
        sys.exit(f"principled-bisect: {src}: no such scene")
    work = Path(a.work) / a.scene
    work.mkdir(parents=True, exist_ok=True)
    print(f"{a.scene}: kalos {a.spp} spp, Mitsuba 3.9.1 {a.variant} {a.mitsuba_spp} spp")
    print("| variant | kalos/Mitsuba R | G | B | accepted | worst 8x8 block (row, col): ratio RGB |")
    print("|---|---:|---:|---:|---:|---|")
    for i, (name, tree) in enumerate(variants(load(src))):
        if a.only and name not in a.only:
            continue
        path = work / f"v{i:02}.xml"
        tree.write(path)
        mm, mx, var = mitsuba_render(mi, np, path, a.mitsuba_spp)
        km, kx = kalos_render(mi, np, a.kalos, path, a.spp, work / f"v{i:02}-kalos.exr")
        ratio, acc, (r, c, br) = compare(np, km, kx, mm, mx, var, a.mitsuba_spp, a.spp)
        rs = " | ".join(f"{x:.4f}" for x in ratio)
        bs = ", ".join(f"{x:.3f}" for x in br)
        print(f"| {name} | {rs} | {acc:.2f}% | ({r}, {c}): {bs} |", flush=True)


if __name__ == "__main__":
    sys.exit(main())
