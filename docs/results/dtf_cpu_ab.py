#!/usr/bin/env python3
"""CPU time (user + system, from wait4) of kalos renders, alternated round by round.

Usage: dtf_cpu_ab.py ROUNDS SCENE [COMMON OPTIONS...] -- NAME KALOS [OPTIONS...] [-- NAME KALOS ...]
  e.g. dtf_cpu_ab.py 15 cornell --res 128x128 --spp 64 --threads 1 \\
           -- plain target/release/kalos -- dtf-main /tmp/kalos-main --method dtf \\
           -- dtf target/release/kalos --method dtf

Like time_ab.py, but each configuration names its own binary (an A/B of two builds) and
the time is the process's CPU seconds rather than wall-clock: with --threads 1 on a
shared machine, another job's load lengthens the wall clock of short renders far more
than their CPU time. Prints each round, then per configuration the median seconds and the
median of its per-round ratio to the first configuration."""
import os, statistics, subprocess, sys, tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from time_ab import split_groups

args = sys.argv[1:]
rounds, scene = int(args[0]), args[1]
common, configs = split_groups(args[2:])
if len(configs) < 2:
    sys.exit("dtf_cpu_ab.py: give at least two configurations after --")
secs = [[] for _ in configs]
with tempfile.TemporaryDirectory() as tmp:
    out = os.path.join(tmp, "x.exr")

    def run(kalos, extra):
        p = subprocess.Popen([kalos, "render", scene, *common, *extra, "-q", "-o", out])
        _, status, ru = os.wait4(p.pid, 0)
        if status != 0:
            sys.exit(f"{kalos} failed ({status})")
        return ru.ru_utime + ru.ru_stime

    for i in range(rounds):
        line = []
        for k, (name, kalos, *extra) in enumerate(configs):
            t = run(kalos, extra)
            secs[k].append(t)
            line.append(f"{name} {t:.3f} s")
        print(f"round {i}: " + ", ".join(line), flush=True)
base = configs[0][0]
for (name, *_), s in zip(configs, secs):
    r = [a / b for a, b in zip(s, secs[0])]
    print(f"{scene} {' '.join(common)}: {name} median {statistics.median(s):.3f} s, "
          f"median ratio to {base} {statistics.median(r):.3f} over {rounds} rounds")
