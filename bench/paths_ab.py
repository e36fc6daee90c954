#!/usr/bin/env python3
"""Render throughput of two kalos binaries, alternated round by round (A/B of two builds).

Usage: paths_ab.py ROUNDS KALOS_A KALOS_B -- RENDER ARGS...
  e.g. paths_ab.py 6 /tmp/kalos-old target/release/kalos -- cornell --method plain \\
           --integrator path --spp 16 --res 256x256 --rr off --max-depth 8 --threads 1

Each round runs both (in alternating order) and reads `paths_per_second` from `--stats`
(render time only: scene loading and the BVH build are left out, which matters on large
meshes); prints each round and the median of the per-round B/A ratios. The arguments go to
both as they are: name the work (`--method plain --integrator path --sampler random` for the
path tracer alone; kalos' default method runs pilots and filtering). Prints the CPU model
and its vector extensions first: a ratio holds for the CPU it ran on."""
import json, os, statistics, subprocess, sys, tempfile

n, a, b = int(sys.argv[1]), sys.argv[2], sys.argv[3]
if sys.argv[4] != "--":
    sys.exit("paths_ab.py: ROUNDS KALOS_A KALOS_B -- RENDER ARGS...")
args = sys.argv[5:]
info = open("/proc/cpuinfo").read()
model = next((l.split(":", 1)[1].strip() for l in info.splitlines() if l.startswith("model name")), "?")
flags = next((l.split(":", 1)[1].split() for l in info.splitlines() if l.startswith("flags")), [])
ext = [f for f in ("sse4_2", "avx", "avx2", "fma", "avx512f") if f in flags]
print(f"CPU {model}, {os.cpu_count()} cores, {' '.join(ext)}; load {os.getloadavg()[0]:.2f}")
rs = []
with tempfile.TemporaryDirectory() as tmp:
    out, stats = os.path.join(tmp, "x.exr"), os.path.join(tmp, "s.json")
    for i in range(n):
        v = {}
        for kalos in (a, b) if i % 2 == 0 else (b, a):
            subprocess.run([kalos, "render", *args, "-q", "-o", out, "--stats", stats],
                           check=True, stderr=subprocess.DEVNULL)
            v[kalos] = json.load(open(stats))["paths_per_second"]
        rs.append(v[b] / v[a])
        print(f"round {i}: A {v[a]:.4g} paths/s, B {v[b]:.4g} paths/s, B/A {rs[-1]:.3f}", flush=True)
print(f"median B/A {statistics.median(rs):.3f} ({', '.join('%.3f' % r for r in rs)})")
