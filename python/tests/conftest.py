"""Shared fixtures: the CLI binary the module is checked against, and a Dask cluster."""

import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def kalos_bin():
    """The `kalos` CLI of this checkout (KALOS_BIN, else target/release/kalos)."""
    p = pathlib.Path(os.environ.get("KALOS_BIN", ROOT / "target" / "release" / "kalos"))
    if not p.is_file():
        pytest.fail(f"{p}: build the CLI first (cargo build --release) or set KALOS_BIN")
    return p


@pytest.fixture(scope="session")
def cli(kalos_bin):
    """Run `kalos ARGS...`; returns the CompletedProcess (text mode)."""

    def run(*args, check=True, cwd=None):
        r = subprocess.run([str(kalos_bin), *map(str, args)], capture_output=True, text=True, cwd=cwd)
        if check and r.returncode != 0:
            raise AssertionError(f"kalos {' '.join(map(str, args))} failed: {r.stderr}")
        return r

    return run


def cli_error(proc):
    """The CLI's one-line error message, without its `kalos: error: ` prefix (or, for
    clap's own usage errors, the first line without `error: `)."""
    assert proc.returncode != 0, proc.stdout
    for prefix in ("kalos: error: ", "error: "):
        lines = [l for l in proc.stderr.splitlines() if l.startswith(prefix)]
        if lines:
            return lines[0][len(prefix):]
    raise AssertionError(proc.stderr)


@pytest.fixture(scope="module")
def dask_client():
    """Two worker processes with one thread each, loopback only, no dashboard."""
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address=None,
    )
    client = distributed.Client(cluster)
    try:
        yield client
    finally:
        client.close()
        cluster.close()
