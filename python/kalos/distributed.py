"""Renders spread over a Dask cluster: a render's samples split into sample ranges, each a
Dask task that renders its range on whichever worker gets it and returns the film part's
bytes (the ``.kfilm`` format, so no shared disk is needed); the client merges the parts
in a fixed order. Film sums are exact integers and each sample is a pure function of
(seed, pixel, sample index), so the image is the one-process render's, bit for bit,
whatever the number of workers, whichever worker ran what, and whatever Dask re-ran after
losing a worker.

>>> from dask.distributed import Client, LocalCluster
>>> import kalos.distributed
>>> client = Client(LocalCluster(n_workers=2, threads_per_worker=1))
>>> img = kalos.distributed.render("cornell", spp=256, client=client, chunk_spp=32)

Workers need the ``kalos`` package (the same version) and, for scene files, the file at
the same path (built-in scenes need nothing).
"""

from __future__ import annotations

import json
import logging
import math
import os
import threading
import time
import uuid
from typing import Any, Callable, Dict, List, Optional, Tuple, Union

from . import Film, RenderResult, Scene, _argv, _kalos, job as _job, load, merge as _merge

log = logging.getLogger("kalos.distributed")

__all__ = ["light_ranges", "render", "render_dtf_part", "render_part", "sample_ranges"]

_SCENES: Dict[Tuple[str, Optional[float]], Scene] = {}
_SCENES_LOCK = threading.Lock()
_SCENES_KEPT = 4


def _cached_scene(spec: str) -> Scene:
    """The scene, loaded once per worker process (and again if the file changed)."""
    key = (spec, os.path.getmtime(spec) if os.path.isfile(spec) else None)
    with _SCENES_LOCK:
        s = _SCENES.get(key)
    if s is None:
        s = load(spec)
        with _SCENES_LOCK:
            if len(_SCENES) >= _SCENES_KEPT:
                _SCENES.clear()
            _SCENES[key] = s
    return s


def render_part(spec: str, argv: List[str], first: int, spp: int) -> Tuple[bytes, str]:
    """One task: render samples ``first..first+spp`` of the job ``argv`` describes (a
    ``kalos render`` argument vector without --spp/--first-sample) and return the film
    part's bytes and the part's stats (JSON)."""
    scene = _cached_scene(spec)
    out = _kalos.render(scene._native, list(argv) + [f"--first-sample={first}", f"--spp={spp}"], None)
    return out.film.to_bytes(), out.stats


def sample_ranges(first: int, spp: int, chunk_spp: int) -> List[Tuple[int, int]]:
    """The tasks' sample ranges: (first sample, samples) covering first..first+spp."""
    if chunk_spp < 1:
        raise ValueError(f"chunk_spp: must be at least 1, not {chunk_spp}")
    return [(a, min(chunk_spp, first + spp - a)) for a in range(first, first + spp, chunk_spp)]


def render(
    scene: Union[str, os.PathLike, Scene],
    spp: Optional[int] = None,
    *,
    client: Any = None,
    chunk_spp: Optional[int] = None,
    progress: Optional[Callable[[int, int], Any]] = None,
    retries: int = 1,
    **options: Any,
) -> RenderResult:
    """Render ``scene`` with ``spp`` samples per pixel (default: the scene's) on a Dask
    cluster: tasks of ``chunk_spp`` samples each (default: about two tasks per worker
    thread), merged on the client in sample order. Every other keyword is an option of
    ``kalos.render`` (``seed``, ``res``, ``rr``, ``threads`` per task, ...).

    ``client`` is a ``distributed.Client`` (default: the current one). ``progress(done,
    total)`` is called as parts complete (parts done, parts planned); each part is also
    logged on the ``kalos.distributed`` logger. Tasks lost with a worker are re-run by
    Dask; ``retries`` re-runs a task that raised. Returns the ``RenderResult`` of the
    merged film: the same image as ``kalos.render(scene, spp=spp, **options)``.

    ``method="plain"`` (the default) and ``method="dtf"`` (each phase's pass split into
    sample ranges of about ``chunk_spp`` x pixels samples, over BDPT the light pass into
    ranges of as many light paths; the allocation, top-ups and filter on the client) with
    a sample budget or ``dtf_eps`` (not ``time``) can be distributed, with any integrator
    and DTF options. Raises ValueError for bad options before anything is sent."""
    try:
        from distributed import as_completed, get_client
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError("kalos.distributed needs Dask: pip install dask distributed") from e
    method = _distributable(options)
    # a distributed render is plain or dtf as asked, never chosen per part
    options["method"] = method
    if client is None:
        client = get_client()
    sc = scene if isinstance(scene, Scene) else load(scene)
    spec = sc.spec
    if os.path.exists(spec) and spec not in _kalos_builtin_names():
        spec = os.path.abspath(spec)
    if method == "dtf":
        return _render_dtf(client, sc, spec, spp, chunk_spp, progress, retries, options)
    first = int(options.pop("first_sample", None) or 0)
    spp = int(spp) if spp is not None else sc.default_spp
    # the client refuses bad options before any task is sent (the CLI's messages)
    _job(spec, spp=spp, first_sample=first, **options)
    argv = _argv(options)
    if chunk_spp is None:
        threads = max(1, sum(client.nthreads().values()))
        chunk_spp = max(1, math.ceil(spp / (2 * threads)))
    ranges = sample_ranges(first, spp, int(chunk_spp))
    token = uuid.uuid4().hex[:12]
    t0 = time.perf_counter()
    futures = [
        client.submit(render_part, spec, argv, a, n, key=f"kalos-part-{token}-{i}", pure=False, retries=retries)
        for i, (a, n) in enumerate(ranges)
    ]
    index = {f.key: i for i, f in enumerate(futures)}
    parts: Dict[int, Film] = {}
    stats: List[Dict[str, Any]] = [{} for _ in ranges]
    merged: Optional[Film] = None
    next_i = 0
    try:
        for done, fut in enumerate(as_completed(futures), start=1):
            i = index[fut.key]
            data, st = fut.result()
            a, n = ranges[i]
            parts[i] = Film.from_bytes(data, f"part {i} (samples {a}..{a + n})")
            stats[i] = json.loads(st)
            fut.release()
            # merge the parts in sample order as soon as they are contiguous
            while next_i in parts:
                p = parts.pop(next_i)
                merged = p if merged is None else _merge([merged, p])
                next_i += 1
            log.info(
                "part %d/%d done (samples %d..%d, %.2f s in the task), %.1f s elapsed",
                done, len(ranges), a, a + n, stats[i].get("seconds", 0.0), time.perf_counter() - t0,
            )
            if progress is not None:
                progress(done, len(ranges))
    except BaseException:
        client.cancel(futures)
        raise
    assert merged is not None and next_i == len(ranges)
    img = merged.image()
    s0 = stats[0]
    img.stats = {
        **{k: s0[k] for k in ("scene", "width", "height", "threads", "spectral", "sampler", "dependent",
                              "max_depth", "integrator", "rr", "rr_weight", "rr_min_depth", "bsdf_select",
                              "seed", "method") if k in s0},
        "spp": spp,
        "first_sample": first,
        "seconds": time.perf_counter() - t0,
        "task_seconds": sum(s.get("seconds", 0.0) for s in stats),
        "paths": sum(s.get("paths", 0) for s in stats),
        "rays": sum(s.get("rays", 0) for s in stats),
        "rejected_samples": sum(s.get("rejected_samples", 0) for s in stats),
        "parts": len(ranges),
        "chunk_spp": int(chunk_spp),
        "workers": len(client.nthreads()),
        "interrupted": False,
        "mean_rgb": [float(img[..., c].mean(dtype="float64")) for c in range(3)],
    }
    img.warnings = []
    return img


def _distributable(options: Dict[str, Any]) -> str:
    """The method of a render that can be split into sample ranges, or ValueError: the
    one place that says what is distributed (``render`` and ``kalos render --dask``)."""
    if options.get("time") is not None:
        raise ValueError("time: a distributed render splits a sample budget: give spp (--spp), not time (--time)")
    method = options.get("method") or "plain"
    if method not in ("plain", "dtf"):
        raise ValueError(f"method {method!r}: only plain and dtf renders are distributed so far")
    return method


def render_dtf_part(spec: str, argv: List[str], dependent: bool, stream: int, first: int, n: int,
                    counts: Optional[bytes], rays: bool, k: Optional[bytes] = None, light_paths: int = 0,
                    rest: bool = False) -> Tuple[bytes, Optional[bytes], bytes, int, int, int]:
    """One task of a DTF pass: samples ``first..first+n`` of every pixel (or
    ``first..first+counts[p]``) of the phase, or with ``light_paths`` light paths
    ``first..first+light_paths`` (phase 2's light pass over BDPT); ``k`` is the pass's
    K[p] (BDPT's light-tracing ratio, float32 bytes), ``rest`` asks for the film of the
    samples less their emission seen directly too. Returns the film bytes, the rest film's
    bytes (or None), rays per pixel, paths, rays and light rays."""
    scene = _cached_scene(spec)
    return _kalos.render_dtf_part(scene._native, list(argv), dependent, stream, first, n, counts, rays,
                                  k, light_paths, rest)


def light_ranges(count: int, target: int) -> List[Tuple[int, int]]:
    """A light pass's tasks: (first light path, paths) covering 0..count, ``target`` paths
    each (the last fewer). Path m is a pure function of m and the film's sums are
    integers, so any cut gives the one-process film: no alignment to its chunks needed."""
    target = max(1, int(target))
    return [(a, min(target, count - a)) for a in range(0, count, target)]


def _balanced_ranges(per_index, target: int) -> List[Tuple[int, int]]:
    """Sample index ranges (first, count) holding about ``target`` samples each, given the
    samples at each index (a DTF pass's per-pixel counts fall off with the index)."""
    target = max(1, int(target))
    ranges, a, acc = [], 0, 0
    for j, c in enumerate(per_index.tolist()):
        acc += c
        if acc >= target:
            ranges.append((a, j + 1 - a))
            a, acc = j + 1, 0
    if a < len(per_index):
        ranges.append((a, len(per_index) - a))
    return ranges or [(0, 0)]


def _render_dtf(client, sc, spec, spp, chunk_spp, progress, retries, options) -> RenderResult:
    """DTF on the cluster: each pass (phase 1, phase 2, top-ups) split into sample ranges
    as tasks, over BDPT phase 2's light pass into ranges of light paths, every task given
    the pass's K[p] and, with ``dtf_direct="split"``, returning its rest film too; the
    allocation, K, top-ups and filter run on the client (in Rust)."""
    import numpy as np
    from distributed import as_completed

    if options.get("first_sample"):
        raise ValueError("first_sample: a dtf render is not a sample range")
    argv = _argv(dict(options, spp=spp))
    threads = max(1, sum(client.nthreads().values()))
    w, h = _job(spec, **dict(options, spp=spp))["res"] or sc.info()["default_res"] or (256, 256)
    native_pixels = int(w) * int(h)
    token = uuid.uuid4().hex[:12]
    t0 = time.perf_counter()
    passes = []

    def run_pass(dependent, stream, n, counts, rays, k=None, light_paths=0, rest=False):
        pixels = native_pixels
        if light_paths:
            # phase 2's light paths of their own: ranges of path numbers, each reading K
            target = pixels * int(chunk_spp) if chunk_spp else math.ceil(light_paths / (2 * threads))
            tasks = [(dependent, a, 0, None, rays, m) for a, m in light_ranges(light_paths, target)]
        else:
            arr = None if counts is None else np.frombuffer(counts, dtype="<u4").astype(np.int64)
            # samples at each index j: all pixels (uniform) or those whose count exceeds j
            if arr is None:
                per_index = np.full(n, pixels, dtype=np.int64)
            else:
                hist = np.bincount(arr, minlength=int(arr.max(initial=0)) + 1)
                per_index = pixels - np.cumsum(hist)[:-1]
            ranges = _balanced_ranges(per_index, pixels * int(chunk_spp) if chunk_spp
                                      else math.ceil(int(per_index.sum()) / (2 * threads)))
            tasks = [(dependent, a, m, None if arr is None else np.clip(arr - a, 0, m).astype("<u4").tobytes(),
                      rays, 0) for a, m in ranges]
        futures = []
        for i, (dep, a, m, part, r, paths) in enumerate(tasks):
            futures.append(client.submit(render_dtf_part, spec, argv, dep, stream, a, m, part, r, k, paths, rest,
                                         key=f"kalos-dtf-{token}-s{stream}-{i}", pure=False, retries=retries))
        index = {f.key: i for i, f in enumerate(futures)}
        out = [None] * len(futures)
        try:
            for done, fut in enumerate(as_completed(futures), start=1):
                out[index[fut.key]] = fut.result()
                fut.release()
                if progress is not None:
                    progress(done, len(futures))
        except BaseException:
            client.cancel(futures)
            raise
        passes.append((stream, len(futures)))
        log.info("dtf pass on stream %d: %d parts%s, %.1f s elapsed", stream, len(futures),
                 f" of {light_paths} light paths" if light_paths else "", time.perf_counter() - t0)
        return out

    native = _kalos.render_dtf_with(sc._native, argv, run_pass)
    from . import _arrays

    img = _arrays(native.width, native.height, native.image, native.variance, native.count)
    img.stats = json.loads(native.stats)
    img.stats.update(seconds=time.perf_counter() - t0, passes=len(passes), parts=sum(p for _, p in passes),
                     workers=len(client.nthreads()))
    img.job = json.loads(native.job)
    img.warnings = list(native.warnings)
    img.film = None
    return img


def _kalos_builtin_names() -> List[str]:
    return [n for n, _ in _kalos.scenes()]


# --- `kalos render --dask` (`python -m kalos render --dask`): the command line ----------

_CLI_USAGE = (
    "usage: kalos render --dask ADDRESS [--dask-chunk-spp N] SCENE "
    "[kalos render options] [-o OUT] [--stats FILE] [--aovs] [--exposure STOPS] [-q]"
)


def _parse_cli(argv: List[str]) -> Dict[str, Any]:
    """``kalos render``'s argument vector -> the scene, the render keywords and the
    outputs. Options of the job are looked up in the CLI's own table (``kalos.options()``),
    so names and values are checked by the same clap definition as the CLI's."""
    from . import _BY_NAME

    by_flag = {o["flag"]: o for o in _BY_NAME.values()}
    out: Dict[str, Any] = dict(scheduler=None, chunk_spp=None, scene=None, output="out.exr", stats=None,
                               aovs=False, exposure=0.0, quiet=False, options={})
    own_values = {"--dask": "scheduler", "--dask-chunk-spp": "chunk_spp", "-o": "output", "--output": "output",
                  "--stats": "stats", "--exposure": "exposure"}
    own_flags = {"--aovs": "aovs", "-q": "quiet", "--quiet": "quiet"}
    not_here = ("--dtf-layers", "--rw-layers", "--bdpt-strategies")
    i = 0
    while i < len(argv):
        tok = argv[i]
        name, eq, value = tok.partition("=") if tok.startswith("--") else (tok, "", "")
        i += 1
        if name in not_here:
            raise ValueError(f"{name}: not written by a distributed render (render without --dask for it)")
        if name in own_flags:
            out[own_flags[name]] = True
            continue
        if name in own_values or name in by_flag:
            o = by_flag.get(name)
            if o is not None and not o["takes_value"]:
                out["options"][o["name"]] = True
                continue
            if not eq:
                if i >= len(argv):
                    raise ValueError(f"{name}: a value is required")
                value = argv[i]
                i += 1
            if name in own_values:
                out[own_values[name]] = value
            else:
                out["options"][o["name"]] = value
            continue
        if tok.startswith("-") and tok != "-":
            raise ValueError(f"unexpected argument '{tok}' ({_CLI_USAGE})")
        if out["scene"] is not None:
            raise ValueError(f"unexpected argument '{tok}': the scene is {out['scene']!r} ({_CLI_USAGE})")
        out["scene"] = tok
    if out["scheduler"] is None:
        raise ValueError(f"--dask: the Dask scheduler's address is required ({_CLI_USAGE})")
    if out["scene"] is None:
        raise ValueError(f"the scene is required ({_CLI_USAGE})")
    try:
        out["chunk_spp"] = None if out["chunk_spp"] is None else int(out["chunk_spp"])
        out["exposure"] = float(out["exposure"])
    except ValueError as e:
        raise ValueError(f"--dask-chunk-spp/--exposure: {e}") from None
    return out


def main(argv: List[str]) -> int:
    """``kalos render --dask tcp://HOST:8786 SCENE [options]`` (the binary runs ``python -m
    kalos render ...``, which calls this with the arguments after ``render``): the render
    ``kalos render SCENE [options]`` would make, on the Dask cluster, written to ``-o``.
    Errors are one ``kalos: error:`` line and exit status 1 (2 for a bad command line)."""
    import sys

    try:
        a = _parse_cli(argv)
    except ValueError as e:
        print(f"kalos: error: {e}", file=sys.stderr)
        return 2
    from . import SceneError, write

    try:
        from distributed import Client
    except ImportError:
        print("kalos: error: --dask needs Dask in this Python: pip install dask distributed", file=sys.stderr)
        return 1
    opts = dict(a["options"])
    spp = opts.pop("spp", None)
    quiet = a["quiet"]

    def progress(done: int, total: int) -> None:
        if not quiet:
            print(f"kalos: part {done}/{total} done, {time.perf_counter() - t0:.1f} s", file=sys.stderr)

    t0 = time.perf_counter()
    try:
        # refuse what cannot be distributed before connecting (the outputs were checked
        # by the kalos binary that runs this)
        _distributable(opts)
        sc = load(a["scene"])
        if not quiet:
            for w in sc.warnings:
                print(f"kalos: warning: {w}", file=sys.stderr)
        _job(sc, spp=spp, **opts)
        with Client(a["scheduler"], timeout="20s") as client:
            if not quiet:
                n = sum(client.nthreads().values())
                print(f"kalos: {a['scene']} on {a['scheduler']}: {len(client.nthreads())} workers, {n} threads",
                      file=sys.stderr)
            img = render(sc, spp, client=client, chunk_spp=a["chunk_spp"], progress=progress, **opts)
        write(a["output"], img, exposure=a["exposure"], aovs=a["aovs"])
        if a["stats"]:
            with open(a["stats"], "w") as f:
                json.dump(img.stats, f, indent=2)
                f.write("\n")
    except KeyboardInterrupt:
        print("kalos: error: interrupted: the distributed render was cancelled, nothing written", file=sys.stderr)
        return 130
    except (ValueError, TypeError, SceneError, OSError) as e:
        msg = " ".join(str(e).split())
        print(f"kalos: error: {msg}", file=sys.stderr)
        return 1
    if not quiet:
        s = img.stats or {}
        print(f"kalos: {a['scene']} {img.shape[1]}x{img.shape[0]} {s.get('spp', '?')} spp in "
              f"{time.perf_counter() - t0:.2f} s on the cluster ({s.get('parts', '?')} parts) -> {a['output']}",
              file=sys.stderr)
    return 0
