"""One kalos render at 1, 2 and 4 Dask worker processes, and the overhead of a 1-worker
distributed render (splitting into parts, moving them as bytes, merging) against a plain
`kalos.render`. Prints a Markdown table with the CPU model. Every image is checked to be
the plain render's, bit for bit.

    python bench/dask-scaling.py [--scene cornell] [--spp 128] [--res 256] [--chunk-spp 16] [--reps 3]

Needs the kalos module (maturin develop in python/) and dask + distributed. Timings are
medians of --reps runs on warm workers (the cluster's start-up is not counted).
"""

import argparse
import os
import platform
import statistics
import time

import numpy as np
from distributed import Client, LocalCluster

import kalos
import kalos.distributed


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def median_time(fn, reps):
    ts, out = [], None
    for _ in range(reps):
        t0 = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts), out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default="cornell")
    ap.add_argument("--spp", type=int, default=128)
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--chunk-spp", type=int, default=16)
    ap.add_argument("--reps", type=int, default=3)
    a = ap.parse_args()
    cores = os.cpu_count() or 1
    opts = dict(res=(a.res, a.res), seed=0)
    scene = kalos.load(a.scene)
    plain_s, ref = median_time(lambda: kalos.render(scene, spp=a.spp, **opts), a.reps)
    plain1_s, ref1 = median_time(lambda: kalos.render(scene, spp=a.spp, threads=1, **opts), a.reps)
    assert np.array_equal(ref, ref1)
    rows = []

    def distributed(workers, threads):
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                               host="127.0.0.1", dashboard_address=None)
        with cluster, Client(cluster) as client:
            run = lambda: kalos.distributed.render(scene, spp=a.spp, client=client, chunk_spp=a.chunk_spp,
                                                   threads=threads, **opts)
            run()  # warm: the workers import kalos and load the scene
            s, img = median_time(run, a.reps)
        return s, bool(np.array_equal(img, ref) and np.array_equal(img.variance, ref.variance))

    # overhead: the same threads as the plain render, one worker process
    one_s, one_same = distributed(1, None)
    for workers in (1, 2, 4):
        s, same = distributed(workers, 1)
        rows.append((workers, s, same))

    parts = -(-a.spp // a.chunk_spp)
    print(f"CPU: {cpu_model()}, {cores} logical CPUs; {a.scene} {a.res}x{a.res}, {a.spp} spp in "
          f"{parts} parts of {a.chunk_spp} spp; median of {a.reps} runs, warm workers")
    print()
    print("| render | threads per render task | seconds | speed-up over 1 worker | image == plain render |")
    print("|---|---|---|---|---|")
    print(f"| plain `kalos.render` | {cores} | {plain_s:.2f} | | (reference) |")
    print(f"| plain `kalos.render`, threads=1 | 1 | {plain1_s:.2f} | | yes |")
    base = rows[0][1]
    for workers, s, same in rows:
        print(f"| Dask, {workers} worker process{'es' if workers > 1 else ''} | 1 | {s:.2f} | {base / s:.2f} | {'yes' if same else 'NO'} |")
    print(f"| Dask, 1 worker process | {cores} | {one_s:.2f} | | {'yes' if one_same else 'NO'} |")
    print()
    print(f"Overhead of a 1-worker distributed render against a plain render: "
          f"{(one_s / plain_s - 1) * 100:+.1f}% ({cores} threads each), "
          f"{(rows[0][1] / plain1_s - 1) * 100:+.1f}% (1 thread each).")


if __name__ == "__main__":
    main()
