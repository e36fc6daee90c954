#!/usr/bin/env python3
"""kalos' default render against Mitsuba 3's default path tracer, at equal time.

Mitsuba 3 (`path`, rr_depth 5, unlimited depth, independent sampler, box filter; llvm_ad_rgb)
renders each scene with a sample count chosen to take about T seconds; kalos then renders the
same scene with `--time` set to the seconds Mitsuba took (its JIT warm-up excluded, kalos'
preprocess and pilot included). Both images are compared with `kalos compare --json` against
Mitsuba's own high-spp reference of the same triangles: RMSE and the perceptual error (share of
pixels more than 5% off). Run on a quiet machine; the CPU is printed first.

Usage (from the repository, Mitsuba from bench/mitsuba-setup.sh):
  bench/default-vs-mitsuba.py [--scenes cornell,room] [--times 10,60] [--seeds 0,1,2]
      [--kalos-args "..."] [--label NAME]...   (each --kalos-args is one kalos configuration)
  bench/default-vs-mitsuba.py --reference room --spp 8192   (renders a reference, in passes)

Scenes: `cornell` (kalos' built-in Cornell box; Mitsuba reads the same box from
MITSUBA_DIR/cornell-box.obj), `room` (assets/scenes/room.obj with its materials made diffuse,
as bench/compare-mitsuba.sh writes it, and that script's camera).

Environment: MITSUBA_VENV (/work/mitsuba-venv, else /tmp/mitsuba), LIBLLVM_PATH,
MITSUBA_DIR (/work/shared/bench/mitsuba), KALOS (target/release/kalos), THREADS (2).
"""
import argparse, json, os, re, subprocess, sys, tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
VENV = os.environ.get("MITSUBA_VENV") or next(
    (p for p in ("/work/mitsuba-venv", "/tmp/mitsuba") if os.path.isdir(p)), "/tmp/mitsuba")
LIBLLVM = os.environ.get("LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1")
MI_DIR = os.environ.get("MITSUBA_DIR", "/work/shared/bench/mitsuba")
KALOS = os.environ.get("KALOS", os.path.join(ROOT, "target/release/kalos"))
THREADS = int(os.environ.get("THREADS", "2"))
ROOM_DIR = "/tmp/kalos-bench-room"
ROOM_CAM = [5.6786, 1.5, 3.2143, 4.6786, 1.5, 3.2143, 0, 1, 0, 60]
REFS = {
    "cornell": os.path.join(ROOT, "assets/reference/cornell-256-reference.exr"),
    "room": os.path.join(ROOT, "docs/results/room-256-mitsuba-reference.exr"),
}


def room_files():
    os.makedirs(ROOM_DIR, exist_ok=True)
    with open(os.path.join(ROOT, "assets/scenes/room.obj")) as f, \
            open(os.path.join(ROOM_DIR, "room.obj"), "w") as g:
        g.write(f.read())
    with open(os.path.join(ROOT, "assets/scenes/room.mtl")) as f, \
            open(os.path.join(ROOM_DIR, "room.mtl"), "w") as g:
        g.writelines(l for l in f if not re.match(r"\s*(Ks|Ns|illum)\s", l))
    return os.path.join(ROOM_DIR, "room.obj")


def scene_args(scene):
    """(mitsuba obj and camera args, kalos scene and camera args)."""
    if scene == "cornell":
        return ["cornell-box.obj"], ["cornell"]
    if scene == "room":
        obj = room_files()
        return [obj, "--cam", *map(str, ROOM_CAM)], [obj, "--camera", ",".join(map(str, ROOM_CAM))]
    sys.exit(f"default-vs-mitsuba: unknown scene '{scene}' (cornell, room)")


MI_PASSES = r"""
import sys, json, time, runpy, numpy as np
import drjit as dr
dr.set_thread_count(int(sys.argv[1]))
spp, passes, seed0, out = int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
sys.argv = ['render_obj.py'] + sys.argv[6:] + ['--spp', '1']
g = runpy.run_path('render_obj.py', run_name='__main__')   # loads, warms up, renders 1 spp
mi, s = g['mi'], g['s']
acc = None; t0 = time.time()
for i in range(passes):
    img = np.array(mi.render(s, spp=spp, seed=seed0 + i), dtype=np.float64)
    acc = img if acc is None else acc + img
dt = time.time() - t0
mi.Bitmap((acc / passes).astype(np.float32)).write(out)
print(json.dumps({'seconds': dt, 'spp': spp * passes}))
"""


def mitsuba(scene, spp, seed, out, passes=1):
    mi_scene, _ = scene_args(scene)
    env = dict(os.environ, DRJIT_LIBLLVM_PATH=LIBLLVM)
    cmd = [os.path.join(VENV, "bin/python"), "-c", MI_PASSES, str(THREADS), str(spp), str(passes),
           str(seed), out, *mi_scene, "/tmp/default-vs-mitsuba-warmup.exr", "--res", "256", "256"]
    r = subprocess.run(cmd, cwd=MI_DIR, env=env, capture_output=True, text=True)
    lines = [l for l in r.stdout.splitlines() if l.startswith("{")]
    if r.returncode != 0 or not lines:
        sys.exit(f"default-vs-mitsuba: mitsuba failed on {scene}: {r.stderr.strip()[-400:]}")
    return json.loads(lines[-1])["seconds"]


def kalos(scene, seconds, seed, out, extra):
    _, k_scene = scene_args(scene)
    stats = out + ".json"
    cmd = [KALOS, "render", *k_scene, "--res", "256x256", "--time", f"{seconds:.3f}", "--seed",
           str(seed), "--threads", str(THREADS), "-q", "--stats", stats, "-o", out, *extra]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"default-vs-mitsuba: kalos failed: {' '.join(cmd)}: {r.stderr.strip()}")
    with open(stats) as f:
        return json.load(f)


def compare(img, ref):
    r = subprocess.run([KALOS, "compare", img, ref, "--json"], capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"default-vs-mitsuba: compare failed: {r.stderr.strip()}")
    j = json.loads(r.stdout)
    return j["rmse"], j["perceptual_share"]


def cpu_line():
    model = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
    flags = next((l.split(":", 1)[1].split() for l in open("/proc/cpuinfo") if l.startswith("flags")), [])
    ext = [f for f in ("sse4_2", "avx", "avx2", "fma", "avx512f") if f in flags]
    return f"CPU {model}, {os.cpu_count()} cores, {' '.join(ext)}; {THREADS} threads each"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenes", default="cornell,room")
    ap.add_argument("--times", default="10,60")
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--kalos-args", action="append", default=None,
                    help="one kalos configuration (repeatable); default: no options")
    ap.add_argument("--label", action="append", default=None)
    ap.add_argument("--reference", help="render SCENE's Mitsuba reference instead")
    ap.add_argument("--spp", type=int, default=8192)
    a = ap.parse_args()
    if a.reference:
        passes = max(1, a.spp // 512)
        out = REFS[a.reference]
        sec = mitsuba(a.reference, a.spp // passes, 1_000_000, out, passes)
        print(f"reference {a.reference}: {a.spp} spp in {sec:.1f} s -> {out}")
        return
    configs = a.kalos_args or [""]
    labels = a.label or [c or "default" for c in configs]
    print(cpu_line())
    print("scene | T | seed | mitsuba s | mitsuba spp | mitsuba RMSE | mitsuba perc | "
          + " | ".join(f"{l} RMSE ratio | {l} perc ratio | {l} method" for l in labels))
    tmp = tempfile.mkdtemp(prefix="default-vs-mitsuba-")
    for scene in a.scenes.split(","):
        ref = REFS[scene]
        # Mitsuba's paths per second on this scene, for its sample count at each budget.
        t16 = mitsuba(scene, 16, 999, os.path.join(tmp, "cal.exr"))
        for T in map(float, a.times.split(",")):
            spp = max(1, round(16 * T / t16))
            for seed in map(int, a.seeds.split(",")):
                mo = os.path.join(tmp, f"mi-{scene}-{T}-{seed}.exr")
                ms = mitsuba(scene, spp, seed, mo)
                m_rmse, m_perc = compare(mo, ref)
                row = [scene, f"{T:g}", str(seed), f"{ms:.2f}", str(spp), f"{m_rmse:.5f}", f"{m_perc:.4f}"]
                for i, c in enumerate(configs):
                    ko = os.path.join(tmp, f"k{i}-{scene}-{T}-{seed}.exr")
                    st = kalos(scene, ms, seed, ko, c.split())
                    k_rmse, k_perc = compare(ko, ref)
                    row += [f"{k_rmse / m_rmse:.3f}", f"{k_perc / max(m_perc, 1e-9):.3f}",
                            str(st.get("method", st.get("integrator", "?")))]
                print(" | ".join(row), flush=True)


if __name__ == "__main__":
    main()
