#!/usr/bin/env python3
"""OIDN (colour only) on plain path tracing, beside DTF, against the same reference.

A benchmark script, not a kalos dependency: OIDN comes from the `pyoidn` package
(`python3 -m venv V && V/bin/pip install pyoidn numpy`, then run this with V/bin/python).

Usage: dtf_oidn.py RESULTS.csv REFERENCE.exr SCENE RES SEEDS SPPS [KALOS]
  e.g. dtf_oidn.py docs/results/cornell-dtf-results/results.csv \\
         docs/results/cornell-128-reference.exr cornell 128x128 0,1 64,256,1024

For each spp budget and each seed given, renders plain
path tracing with the experiment's seed (`kalos render SCENE --res RES --spp B --seed S`,
the very image the experiment measured: renders are deterministic), denoises it with
OIDN's RT filter (hdr, colour only, quality high) and measures it with `kalos compare`.
Prints per budget, averaged over the seeds: the perceptual error (share of pixels more
than 5% off) and the RMSE of plain, OIDN and DTF (the last two from results.csv, same
seeds), and DTF / OIDN."""
import csv, os, re, subprocess, sys, tempfile
from collections import defaultdict

import numpy as np
import pyoidn


def read_pfm(path):
    with open(path, "rb") as f:
        kind = f.readline()
        dims = f.readline()
        scale = f.readline()
        data = f.read()
    w, h = map(int, dims.split())
    endian = "<" if float(scale) < 0 else ">"
    img = np.frombuffer(data, dtype=endian + "f4").reshape(h, w, 3)
    return (kind, dims, scale), img


def write_pfm(path, header, img):
    kind, dims, scale = header
    endian = "<" if float(scale) < 0 else ">"
    with open(path, "wb") as f:
        f.write(kind + dims + scale)
        f.write(np.ascontiguousarray(img, dtype=endian + "f4").tobytes())


def compare(kalos, img, ref):
    out = subprocess.run([kalos, "compare", img, ref], capture_output=True, text=True, check=True).stdout
    rmse = float(re.search(r"rmse\s+([0-9.eE+-]+)", out).group(1))
    perc = float(re.search(r"\(([0-9.]+)%\)", out).group(1)) / 100
    return rmse, perc


def main():
    results, ref, scene, res, seeds, budgets = sys.argv[1:7]
    kalos = sys.argv[7] if len(sys.argv) > 7 else "target/release/kalos"
    seeds = [int(s) for s in seeds.split(",")]
    budgets = [int(b) for b in budgets.split(",")]
    avg = lambda v: sum(v) / len(v)
    oidn = {}
    with tempfile.TemporaryDirectory() as tmp:
        for b in budgets:
            o = []
            for s in seeds:
                plain = os.path.join(tmp, f"p{b}-{s}.pfm")
                subprocess.run([kalos, "render", scene, "--res", res, "--spp", str(b), "--seed",
                                str(s), "-q", "-o", plain], check=True)
                header, img = read_pfm(plain)
                den = pyoidn.denoise(np.ascontiguousarray(img, dtype=np.float32), hdr=True)
                out = os.path.join(tmp, f"o{b}-{s}.pfm")
                write_pfm(out, header, den)
                o.append(compare(kalos, out, ref))
            oidn[b] = o
            print(f"OIDN {scene} {b} spp, seeds {seeds}: rmse {[x[0] for x in o]}, perceptual {[x[1] for x in o]}",
                  flush=True)
    print(f"{scene} {res}, seeds {seeds}")
    print("| spp | plain RMSE / perceptual | OIDN on plain | DTF | DTF / OIDN perceptual |")
    print("|---|---|---|---|---|")
    # DTF and plain on the same seeds, from the experiment (read last: it may still run)
    csv_m = defaultdict(list)
    for r in csv.DictReader(open(results)):
        if int(r["seed"]) in seeds:
            csv_m[(r["config"], int(float(r["budget"])))].append(
                (float(r["rmse"]), float(r["perceptual_share"])))
    for b in budgets:
        o = oidn[b]
        pr = csv_m[("path", b)]
        dr = csv_m[("dtf", b)]
        orm, opc = avg([x[0] for x in o]), avg([x[1] for x in o])
        prm, ppc = avg([x[0] for x in pr]), avg([x[1] for x in pr])
        drm, dpc = avg([x[0] for x in dr]), avg([x[1] for x in dr])
        print(f"| {b} | {prm:.4f} / {ppc:.1%} | {orm:.4f} / {opc:.1%} | {drm:.4f} / {dpc:.1%} "
              f"| {dpc / opc:.2f}x |", flush=True)


if __name__ == "__main__":
    main()
