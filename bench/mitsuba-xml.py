"""Render the same Mitsuba XML scene with Mitsuba 3 and with kalos and compare them.

Run with the Python of a venv that has mitsuba and numpy (bench/mitsuba-setup.sh), from the
repository root, after `cargo build --release`:

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 \
        /tmp/mitsuba/bin/python bench/mitsuba-xml.py scenes/mitsuba/cornell-box.xml

For each scene: the file is copied beside itself with the film set to --res and a box pixel
filter (kalos' filter; the mean is the same, edges agree better); Mitsuba renders a
reference at --ref-spp; then Mitsuba and kalos each render it at every --spp with their own
seeds. Printed per scene and spp: the mean of all channels over the reference's (kalos,
Mitsuba) and the per-pixel RMSE against the reference (kalos, Mitsuba). A PNG with the
reference and kalos' image at the largest spp side by side goes to --png-dir, and one JSON
line per scene to stdout after the table (for scripts).
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

import numpy as np
import mitsuba as mi


def rewrite(path, res):
    """The scene with the film at res x res and a box filter, beside the original."""
    tree = ET.parse(path)
    root = tree.getroot()
    for film in root.iter("film"):
        for name in ("width", "height"):
            el = [c for c in film if c.get("name") == name]
            if el:
                el[0].set("value", str(res))
            else:
                ET.SubElement(film, "integer", name=name, value=str(res))
        for rf in [c for c in film if c.tag == "rfilter"]:
            film.remove(rf)
        ET.SubElement(film, "rfilter", type="box")
    d = os.path.dirname(os.path.abspath(path))
    fd, out = tempfile.mkstemp(suffix=".xml", prefix=".bench-", dir=d)
    os.close(fd)
    tree.write(out)
    return out


def mitsuba_render(scene_file, spp, seed):
    scene = mi.load_file(scene_file)
    img = mi.render(scene, spp=spp, seed=seed)
    return np.array(img)[:, :, :3].astype(np.float64)


def kalos_render(kalos, scene_file, spp, seed, res, extra=()):
    fd, out = tempfile.mkstemp(suffix=".exr")
    os.close(fd)
    subprocess.run(
        [kalos, "render", scene_file, "--spp", str(spp), "--seed", str(seed),
         "--res", f"{res}x{res}", "--quiet", "-o", out, *extra],
        check=True, stderr=subprocess.DEVNULL)
    img = np.array(mi.Bitmap(out))[:, :, :3].astype(np.float64)
    os.remove(out)
    return img


def to_png(img, path):
    bmp = mi.Bitmap(img.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB)
    bmp.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, srgb_gamma=True).write(path)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scenes", nargs="+")
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--spp", type=int, nargs="+", default=[16, 256])
    ap.add_argument("--ref-spp", type=int, default=8192)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--kalos", default="target/release/kalos")
    ap.add_argument("--png-dir", default="docs/results/mitsuba-xml")
    ap.add_argument("--kalos-args", default="",
                    help="more kalos render options, e.g. \"--rr-min-depth 5\"")
    args = ap.parse_args()
    mi.set_variant(args.variant)
    os.makedirs(args.png_dir, exist_ok=True)
    print("| scene | spp | mean kalos / ref | mean Mitsuba / ref | RMSE kalos | RMSE Mitsuba |")
    print("|---|---|---|---|---|---|")
    lines = []
    for path in args.scenes:
        name = os.path.splitext(os.path.basename(path))[0]
        tmp = rewrite(path, args.res)
        try:
            ref = mitsuba_render(tmp, args.ref_spp, 1_000_003)
            ref_mean = ref.mean()
            row = {"scene": name, "res": args.res, "ref_spp": args.ref_spp,
                   "ref_mean": ref_mean, "runs": []}
            last_k = None
            for spp in args.spp:
                m = mitsuba_render(tmp, spp, 7)
                k = kalos_render(args.kalos, tmp, spp, 7, args.res, args.kalos_args.split())
                r = {
                    "spp": spp,
                    "kalos_mean_ratio": k.mean() / ref_mean,
                    "mitsuba_mean_ratio": m.mean() / ref_mean,
                    "kalos_rmse": float(np.sqrt(((k - ref) ** 2).mean())),
                    "mitsuba_rmse": float(np.sqrt(((m - ref) ** 2).mean())),
                }
                row["runs"].append(r)
                print(f"| {name} | {spp} | {r['kalos_mean_ratio']:.4f} | "
                      f"{r['mitsuba_mean_ratio']:.4f} | {r['kalos_rmse']:.4f} | "
                      f"{r['mitsuba_rmse']:.4f} |", flush=True)
                last_k = k
            gap = np.ones((args.res, 4, 3))
            to_png(np.concatenate([ref, gap, last_k], axis=1),
                   os.path.join(args.png_dir, f"{name}.png"))
            lines.append(row)
        finally:
            os.remove(tmp)
    for row in lines:
        print(json.dumps(row))


if __name__ == "__main__":
    sys.exit(main())
