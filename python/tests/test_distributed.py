"""kalos.distributed on Dask: parts on worker processes, merged on the client, the same
bits as a one-process render; a worker lost mid-render changes nothing; a scheduler and
workers started as separate processes (loopback only) give the same image."""

import os
import signal
import socket
import subprocess
import sys
import time
import warnings

import numpy as np
import pytest

import kalos
import kalos.distributed

pytest.importorskip("distributed")

OPTS = dict(res=(48, 48), seed=3, method="plain")
SPP = 64


@pytest.fixture(scope="module")
def reference():
    """The one-process render."""
    return kalos.render("cornell", spp=SPP, **OPTS)


def same(a, b):
    return np.array_equal(a, b) and np.array_equal(a.variance, b.variance) and np.array_equal(a.count, b.count)


def test_sample_ranges_cover_the_budget():
    assert kalos.distributed.sample_ranges(0, 64, 8) == [(8 * i, 8) for i in range(8)]
    assert kalos.distributed.sample_ranges(5, 10, 4) == [(5, 4), (9, 4), (13, 2)]
    with pytest.raises(ValueError):
        kalos.distributed.sample_ranges(0, 8, 0)


def test_two_worker_processes_render_the_same_bits(dask_client, reference):
    seen = []
    img = kalos.distributed.render(
        "cornell", spp=SPP, client=dask_client, chunk_spp=8, progress=lambda d, t: seen.append((d, t)), **OPTS
    )
    assert seen[-1] == (8, 8) and len(seen) == 8
    assert img.stats["parts"] == 8 and img.stats["spp"] == SPP
    assert same(img, reference)
    assert img.film.ranges == [(8 * i, 8 * i + 8) for i in range(8)]
    # another split and a first sample offset: still the same samples
    a = kalos.distributed.render("cornell", spp=SPP - 10, first_sample=10, client=dask_client, chunk_spp=13, **OPTS)
    b = kalos.render("cornell", spp=10, **OPTS)
    assert same(kalos.merge([a.film, b.film]).image(), reference)


def test_bad_options_are_refused_before_sending(dask_client):
    with pytest.raises(ValueError, match="--rr"):
        kalos.distributed.render("cornell", spp=4, client=dask_client, rr="nope")
    with pytest.raises(ValueError, match="time"):
        kalos.distributed.render("cornell", client=dask_client, time=2.0)
    with pytest.raises(ValueError, match="plain and dtf"):
        kalos.distributed.render("cornell", spp=4, client=dask_client, method="rw")
    with pytest.raises(FileNotFoundError):
        kalos.distributed.render("nothere.obj", spp=4, client=dask_client)


@pytest.mark.parametrize(
    "scene,opts",
    [
        ("cornell", dict(spp=24, dtf_n=8, seed=2)),
        ("cornell", dict(dtf_eps=0.25, dtf_n=8)),
        ("cornell", dict(spp=8, dtf_n=4, integrator="bdpt", dtf_light="off", dtf_direct="filter")),
        # DTF over BDPT with its defaults (dtf_light="auto", dtf_direct="split"): on the
        # caustic phase 2 traces light paths of its own, weighed with K[p]
        ("caustic", dict(spp=8, dtf_n=4, seed=2, integrator="bdpt")),
        ("cornell", dict(spp=8, dtf_n=4, integrator="bdpt")),
    ],
    ids=["budget", "eps_r", "bdpt-filter", "bdpt-defaults-caustic", "bdpt-defaults-cornell"],
)
def test_dtf_phases_as_tasks_give_the_one_process_image(dask_client, scene, opts):
    """Phase 1, phase 2 (over BDPT its light pass too) and the top-ups split into sample
    (and light-path) ranges on the workers; the allocation and the filter on the client:
    the one-process DTF image, bit for bit."""
    res = (16, 16)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", kalos.KalosWarning)
        ref = kalos.render(scene, method="dtf", res=res, **opts)
        img = kalos.distributed.render(scene, client=dask_client, chunk_spp=3, method="dtf", res=res, **opts)
    assert same(img, ref)
    assert img.stats["passes"] >= 2 and img.stats["parts"] > img.stats["passes"]
    assert img.stats["dtf"]["n"] == ref.stats["dtf"]["n"]
    assert img.stats["dtf"]["light_paths"] == ref.stats["dtf"]["light_paths"]
    if scene == "caustic":
        # the light pass ran, in several tasks whose ranges are not the one-process
        # render's chunks of 1024 paths
        paths = ref.stats["dtf"]["light_paths"]
        assert paths > 16 * 16 * 3
        assert len(kalos.distributed.light_ranges(paths, 16 * 16 * 3)) > 1


def test_light_ranges_cover_the_light_paths():
    assert kalos.distributed.light_ranges(10, 4) == [(0, 4), (4, 4), (8, 2)]
    assert kalos.distributed.light_ranges(3, 0) == [(0, 1), (1, 1), (2, 1)]
    assert kalos.distributed.light_ranges(0, 5) == []


def test_a_worker_killed_mid_render_leaves_the_image_unchanged(dask_client, reference):
    pids = dask_client.run(os.getpid)
    killed = []

    def kill_one(done, total):
        # after the first part: kill a worker process (its running and queued parts are
        # lost; its nanny starts a new one, and Dask re-runs them)
        if not killed:
            addr, pid = sorted(pids.items())[0]
            os.kill(pid, signal.SIGKILL)
            killed.append(addr)

    img = kalos.distributed.render(
        "cornell", spp=SPP, client=dask_client, chunk_spp=4, progress=kill_one, **OPTS
    )
    assert killed
    assert same(img, reference)
    dask_client.wait_for_workers(2, timeout=60)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_scheduler_and_workers_as_separate_processes(reference, cli, tmp_path):
    """The module's render and `kalos render --dask ADDRESS` on a scheduler and two workers
    started as processes of their own: the one-process image, and the CLI's file."""
    distributed = pytest.importorskip("distributed")
    port = free_port()
    addr = f"tcp://127.0.0.1:{port}"
    bindir = os.path.dirname(sys.executable)
    dask = os.path.join(bindir, "dask")
    procs = [subprocess.Popen([dask, "scheduler", "--host", "127.0.0.1", "--port", str(port),
                               "--no-dashboard"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        for _ in range(2):
            procs.append(subprocess.Popen([dask, "worker", addr, "--host", "127.0.0.1", "--nthreads", "1",
                                           "--no-dashboard"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        client = distributed.Client(addr, timeout=60)
        try:
            client.wait_for_workers(2, timeout=60)
            img = kalos.distributed.render("cornell", spp=SPP, client=client, chunk_spp=16, **OPTS)
            assert img.stats["workers"] == 2
            assert same(img, reference)
            # the CLI's front end: the same EXR file, byte for byte, as without --dask
            os.environ["KALOS_PYTHON"] = sys.executable
            # (--dask renders plainly where no method is named: compared with --method plain)
            args = ["render", "cornell", "--spp", SPP, "--res", "48x48", "--seed", 3, "--aovs",
                    "--method", "plain"]
            r = cli(*args, "--dask", addr, "--dask-chunk-spp", 16, "-o", tmp_path / "d.exr",
                    "--stats", tmp_path / "d.json")
            assert "4 parts" in r.stderr and (tmp_path / "d.json").is_file()
            cli(*args, "-q", "-o", tmp_path / "p.exr")
            assert (tmp_path / "d.exr").read_bytes() == (tmp_path / "p.exr").read_bytes()
            # DTF over BDPT with its defaults (light pass, emission seen directly split off)
            dtf = ["render", "caustic", "--method", "dtf", "--integrator", "bdpt", "--spp", 8, "--dtf-n", 4,
                   "--res", "16x16", "--seed", 2, "-q"]
            cli(*dtf, "--dask", addr, "--dask-chunk-spp", 3, "-o", tmp_path / "dd.exr")
            cli(*dtf, "-o", tmp_path / "dp.exr")
            assert (tmp_path / "dd.exr").read_bytes() == (tmp_path / "dp.exr").read_bytes()
            # and its refusals are one line
            from conftest import cli_error
            assert "give spp (--spp), not time" in cli_error(cli("render", "cornell", "--time", 1, "--dask", addr,
                                                                 check=False))
            assert "only plain and dtf" in cli_error(cli("render", "cornell", "--method", "rw", "--dask", addr,
                                                         check=False))
            assert "--dtf-layers" in cli_error(cli("render", "cornell", "--dask", addr, "--dtf-layers",
                                                   "--method", "dtf", check=False))
        finally:
            client.close()
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                p.kill()
