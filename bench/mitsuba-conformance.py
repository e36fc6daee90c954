#!/usr/bin/env python3
"""Reference images for the Mitsuba conformance test (tests/mitsuba_conformance.rs).

Renders each of Mitsuba 3's render-test scenes (outside participating_media/) with Mitsuba
itself, through the scene's `moment` integrator, and writes the per-pixel mean and the
per-sample variance (second moment minus the squared mean, not floored: the test floors it
at 1e-4 as Mitsuba's protocol does) as two small RGB float32 EXRs:

    tests/conformance/<scene>.exr      mean
    tests/conformance/<scene>-var.exr  variance

The moment integrator accumulates in XYZ; the files hold RGB as Mitsuba's own references do
(the test converts them back to XYZ, which is linear and exact up to float rounding).

Each scene is loaded as Mitsuba's test_renders.py loads it (`spp` and `integrator` defines,
the integrator named by the file's last `_` word) and rendered in `--passes` passes of the
test's budget (2e6 // pixels samples per pixel) with seeds 1, 2, ...; the passes' means and
second moments are averaged. The particle tracer cannot write AOVs: as Mitsuba's own
references are made, that scene is rendered by `moment` around `path` of the same max_depth.

Usage (Mitsuba 3.9.1 from PyPI in a venv; llvm_ad_rgb needs libLLVM, see bench/mitsuba-setup.sh):

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 \
    nice -n 10 /work/mitsuba-venv/bin/python bench/mitsuba-conformance.py \
        --scenes ../shared/conformance/mitsuba/tests/scenes --passes 32 [names...]

A line per scene (name, pixels, spp, seconds, variant) is appended to
tests/conformance/references.tsv. Existing references are skipped unless --force.
"""

import argparse
import os
import sys
import time
from pathlib import Path

BUDGET = 2_000_000


def scene_files(root):
    out = []
    for p in sorted(Path(root).rglob("*.xml")):
        rel = p.relative_to(root)
        if rel.parts[0] == "participating_media" or "fragments" in rel.parts:
            continue
        out.append(p)
    return out


def main():
    here = Path(__file__).resolve().parent.parent
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    shared = os.environ.get("KALOS_CONFORMANCE_DIR") or next(
        (str(d / "shared/conformance") for d in here.parents if (d / "shared/conformance").is_dir()),
        str(here.parent / "shared/conformance"),
    )
    ap.add_argument("--scenes", default=str(Path(shared) / "mitsuba/tests/scenes"))
    ap.add_argument("--out", default=str(here / "tests/conformance"))
    ap.add_argument("--passes", type=int, default=32)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--force", action="store_true")
    ap.add_argument("names", nargs="*", help="scene file stems (default: all)")
    a = ap.parse_args()

    import mitsuba as mi
    import numpy as np

    mi.set_variant(a.variant)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    files = scene_files(a.scenes)
    if not files:
        sys.exit(f"mitsuba-conformance: no scenes under {a.scenes} (set --scenes or KALOS_CONFORMANCE_DIR)")
    for path in files:
        name = path.stem
        if a.names and name not in a.names:
            continue
        mean_f, var_f = out / f"{name}.exr", out / f"{name}-var.exr"
        if mean_f.exists() and var_f.exists() and not a.force:
            continue
        integrator = name.split("_")[-1]
        scene = mi.load_file(str(path), spp=1, integrator=integrator)
        film = scene.sensors()[0].film()
        w, h = film.size()
        spp = BUDGET // (w * h)
        override = None
        if integrator == "ptracer":
            depth = scene.integrator().max_depth if hasattr(scene.integrator(), "max_depth") else 4
            override = mi.load_dict(
                {"type": "moment", "nested": {"type": "path", "max_depth": int(depth)}}
            )
        t = time.time()
        mean = m2 = None
        for k in range(a.passes):
            mi.render(scene, integrator=override, seed=k + 1, spp=spp)
            layers = dict(film.bitmap().split())
            keys = [n for n in layers if n != "<root>"]
            m = np.array(layers[[n for n in keys if not n.startswith("m2_")][0]], dtype=np.float64)
            s = np.array(layers[[n for n in keys if n.startswith("m2_")][0]], dtype=np.float64)
            mean = m if mean is None else mean + m
            m2 = s if m2 is None else m2 + s
        mean /= a.passes
        m2 /= a.passes
        var = m2 - mean * mean
        secs = time.time() - t
        for arr, f in ((mean, mean_f), (var, var_f)):
            xyz = mi.Bitmap(arr.astype(np.float32), mi.Bitmap.PixelFormat.XYZ)
            rgb = xyz.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False)
            rgb.write(str(f))
        line = f"{name}\t{w}x{h}\t{spp * a.passes}\t{secs:.1f}\t{a.variant}\n"
        with open(out / "references.tsv", "a") as log:
            log.write(line)
        print(line, end="", flush=True)


if __name__ == "__main__":
    sys.exit(main())
