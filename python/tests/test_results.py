"""Seeing results from Python: the tqdm progress bar of kalos.render (on by default,
progress=False turns it off, a callable still works), FLIP in kalos.compare (as
`kalos compare` computes it), and the distribution's metadata (the name on PyPI, tqdm)."""

import json
import pathlib
import sys

import numpy as np
import pytest

import kalos

ROOT = pathlib.Path(__file__).resolve().parents[2]
FLIP_DATA = ROOT / "tests" / "data" / "flip"


def test_progress_bar_by_default_and_off(capfd):
    kalos.render("cornell", spp=2, res=(16, 16), seed=0)
    err = capfd.readouterr().err
    assert "kalos cornell" in err and "sample" in err, err  # tqdm's bar
    kalos.render("cornell", spp=2, res=(16, 16), seed=0, progress=False)
    assert capfd.readouterr().err == ""
    seen = []
    kalos.render("cornell", spp=2, res=(16, 16), seed=0, progress=lambda d, t: seen.append((d, t)))
    assert capfd.readouterr().err == ""
    with pytest.raises(TypeError, match="progress"):
        kalos.render("cornell", spp=2, res=(16, 16), progress="yes")


def test_compare_has_flip_as_the_cli(cli):
    png = kalos.compare(FLIP_DATA / "test.png", FLIP_DATA / "reference.png")
    assert png["flip_range"] == "LDR"
    # flip-evaluator 1.7 gives 0.15554501 for this pair (tests/flip.rs)
    assert abs(png["flip"] - 0.15554501) < 0.01 * 0.15554501
    exr = kalos.compare(FLIP_DATA / "test.exr", FLIP_DATA / "reference.exr")
    cli_m = json.loads(cli("compare", FLIP_DATA / "test.exr", FLIP_DATA / "reference.exr", "--json").stdout)
    assert exr["flip_range"] == "HDR" and exr["flip"] == cli_m["flip"]
    # arrays are radiance: HDR-FLIP; identical images: 0
    a = kalos.read(FLIP_DATA / "reference.exr")
    same = kalos.compare(a, a)
    assert same["flip_range"] == "HDR" and same["flip"] == 0.0
    assert kalos.compare(np.zeros_like(a) + 0.5, a)["flip"] > 0.1


@pytest.mark.skipif(sys.version_info < (3, 11), reason="tomllib is Python 3.11's")
def test_distribution_name_and_dependencies():
    import tomllib

    meta = tomllib.loads((ROOT / "python" / "pyproject.toml").read_text())["project"]
    # "kalos" on PyPI is another project: pip install kalos-render gets this one
    assert meta["name"] == "kalos-render"
    assert "tqdm" in meta["dependencies"]
    assert (ROOT / "python" / meta["readme"]).is_file()
