"""Closest-hit rays per second of Mitsuba 3 on an OBJ, the rays uniform in the scene's bounds
with uniformly distributed directions (the kind `cargo run --release --example trace_file`
traces in kalos), one wavefront of RAYS rays per pass, best of four passes after a first that
compiles the kernel. Wall-clock rate over all of Dr.Jit's threads (the machine's cores unless
THREADS is given).

    export DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1
    /tmp/mitsuba/bin/python bench/mitsuba_trace.py SCENE.obj [VARIANT [RAYS [THREADS]]]
"""
import json, sys, time

import drjit as dr
import mitsuba as mi

obj = sys.argv[1]
variant = sys.argv[2] if len(sys.argv) > 2 else "llvm_ad_rgb"
if not variant.startswith("llvm"):
    # A scalar variant traces one ray per call: a wavefront of RAYS rays is an LLVM one.
    sys.exit(f"mitsuba_trace.py: VARIANT must be an LLVM one (llvm_ad_rgb, llvm_rgb), not {variant!r}")
mi.set_variant(variant)
n = int(sys.argv[3]) if len(sys.argv) > 3 else 1 << 20
if len(sys.argv) > 4:
    dr.set_thread_count(int(sys.argv[4]))
scene = mi.load_dict({"type": "scene", "m": {"type": "obj", "filename": obj}})
lo, hi = scene.bbox().min, scene.bbox().max
best = 0.0
for k in range(5):
    # New rays every pass, evaluated before the clock starts, so that no pass reuses a result.
    rng = mi.PCG32(size=n, initstate=k + 1)
    u = rng.next_float32
    o = mi.Point3f(lo.x + (hi.x - lo.x) * u(), lo.y + (hi.y - lo.y) * u(), lo.z + (hi.z - lo.z) * u())
    d = mi.warp.square_to_uniform_sphere(mi.Point2f(u(), u()))
    dr.eval(o, d)
    dr.sync_thread()
    t0 = time.perf_counter()
    si = scene.ray_intersect_preliminary(mi.Ray3f(o, d))
    dr.eval(si.t)
    dr.sync_thread()
    if k > 0:
        best = max(best, n / (time.perf_counter() - t0))
print(json.dumps({"scene": obj, "variant": mi.variant(), "threads": dr.thread_count(),
                  "rays": n, "rays_per_s": best, "hits": int(dr.count(si.is_valid())[0])}))
