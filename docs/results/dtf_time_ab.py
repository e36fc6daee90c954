#!/usr/bin/env python3
"""Wall-clock time of `--method dtf` against the plain render, run side by side.

Usage: dtf_time_ab.py PAIRS KALOS SCENE [RENDER OPTIONS...]
  e.g. dtf_time_ab.py 3 target/release/kalos cornell            # the defaults
       dtf_time_ab.py 3 target/release/kalos room --res 200x200 --spp 256

Alternates plain and DTF renders (plain first, then DTF, PAIRS times) so that a shared
machine's load falls on both alike, and prints each pair's seconds, their ratio DTF / plain
and the median ratio. The image is written to a temporary file and discarded."""
import os, statistics, subprocess, sys, tempfile, time

pairs, kalos, scene, opts = int(sys.argv[1]), sys.argv[2], sys.argv[3], sys.argv[4:]
ratios = []
with tempfile.TemporaryDirectory() as tmp:
    out = os.path.join(tmp, "x.exr")

    def run(extra):
        t = time.perf_counter()
        subprocess.run([kalos, "render", scene, *opts, *extra, "-q", "-o", out], check=True)
        return time.perf_counter() - t

    for i in range(pairs):
        p = run([])
        d = run(["--method", "dtf"])
        ratios.append(d / p)
        print(f"pair {i}: plain {p:.2f} s, dtf {d:.2f} s, ratio {d / p:.3f}", flush=True)
print(f"{scene} {' '.join(opts)}: median ratio dtf / plain {statistics.median(ratios):.3f} over {pairs} pairs")
