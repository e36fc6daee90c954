#!/usr/bin/env python3
"""Radiosity bias of the gather from two seeds per configuration (README, RW section):
bias^2 = MSE(a0, ref) - MSE(a0, a1)/2 - var_ref, var_ref = MSE(p0, ref) - MSE(p0, p1)/2.

Usage: python3 docs/results/rw_gather_bias.py KALOS REFERENCE.exr DIR NAME...
DIR holds NAME-0.exr, NAME-1.exr (+ .json stats) per configuration and path-{0,1}.exr:
  for s in 0 1; do
    kalos render rw-room --res 256x256 --spp 256 --seed $s -o DIR/path-$s.exr --stats DIR/path-$s.json
    kalos render rw-room --res 256x256 --spp 256 --seed $s --gather radiosity OPTIONS \
      -o DIR/NAME-$s.exr --stats DIR/NAME-$s.json
  done
with OPTIONS "--radiosity-max-area 0.3", "" (default), "--radiosity-source-level 0",
"--radiosity-max-area 0.029"; REFERENCE is rw-room-256-results/reference.exr."""
import json, subprocess, sys
K, ref, d = sys.argv[1], sys.argv[2], sys.argv[3]
def cmp(a, b):
    return json.loads(subprocess.run([K, "compare", "--json", a, b], capture_output=True, text=True, check=True).stdout)
def pair(name):
    r0 = cmp(f"{d}/{name}-0.exr", ref); r1 = cmp(f"{d}/{name}-1.exr", ref); x = cmp(f"{d}/{name}-0.exr", f"{d}/{name}-1.exr")
    js = [json.load(open(f"{d}/{name}-{s}.json")) for s in (0, 1)]
    return (r0["mse"] + r1["mse"]) / 2, x["mse"] / 2, (r0["luminance_ratio"] + r1["luminance_ratio"]) / 2, js
mp, vp, lp, _ = pair("path")
var_ref = mp - vp
print(f"path: mse vs ref {mp:.3e}, per-image variance {vp:.3e}, reference variance {var_ref:.3e}, luminance ratio {lp:.4f}")
for name in sys.argv[4:]:
    m, v, l, js = pair(name)
    b2 = m - v - var_ref
    prep = sum(j["prepare_seconds"] for j in js) / 2
    sec = sum(j["seconds"] for j in js) / 2
    print(f"{name}: mse vs ref {m:.3e}, variance {v:.3e} ({v/vp:.2f}x path's), bias^2 {b2:.3e} (rms bias {max(b2,0)**0.5:.4f}), luminance ratio {l:.4f}, prepare {prep:.1f} s, render {sec:.1f} s")
