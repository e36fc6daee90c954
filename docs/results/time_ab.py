#!/usr/bin/env python3
"""Wall-clock time of configurations against a baseline render, run side by side.

Usage: time_ab.py PAIRS KALOS SCENE [COMMON OPTIONS...] -- CONFIG OPTIONS [-- CONFIG OPTIONS ...]
  e.g. time_ab.py 3 target/release/kalos cornell -- --method dtf
       time_ab.py 2 target/release/kalos rw-room --res 128x128 --spp 64 --threads 1 \\
           -- --gather radiosity -- --method rw --gather radiosity

Each round renders the baseline (the common options alone), then every configuration, PAIRS
rounds, so that a shared machine's load falls on all alike; prints each round's seconds,
each configuration's ratio to the baseline of its round, and the median ratios. Images go
to a temporary file and are discarded."""
import os, statistics, subprocess, sys, tempfile, time


def split_groups(args):
    """Splits arguments at each "--": (the common options, [each configuration's])."""
    groups, cur = [], []
    for a in args:
        if a == "--":
            groups.append(cur)
            cur = []
        else:
            cur.append(a)
    groups.append(cur)
    return groups[0], groups[1:]


def main():
    args = sys.argv[1:]
    pairs, kalos, scene = int(args[0]), args[1], args[2]
    common, configs = split_groups(args[3:])
    if not configs:
        sys.exit("time_ab.py: give at least one configuration after --")
    ratios = [[] for _ in configs]
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "x.exr")

        def run(extra):
            t = time.perf_counter()
            subprocess.run([kalos, "render", scene, *common, *extra, "-q", "-o", out], check=True)
            return time.perf_counter() - t

        for i in range(pairs):
            base = run([])
            line = [f"round {i}: baseline {base:.2f} s"]
            for k, c in enumerate(configs):
                t = run(c)
                ratios[k].append(t / base)
                line.append(f"[{' '.join(c)}] {t:.2f} s ({t / base:.3f})")
            print(", ".join(line), flush=True)
    for c, r in zip(configs, ratios):
        print(f"{scene} {' '.join(common)}: [{' '.join(c)}] / baseline, median {statistics.median(r):.3f} over {pairs} rounds")


if __name__ == "__main__":
    main()
