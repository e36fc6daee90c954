"""The module against the CLI: the same job gives the same bits, the same options and
defaults, the same error messages."""

import json
import pathlib
import warnings

import numpy as np
import pytest

import kalos
from conftest import ROOT, cli_error

# Small jobs: the point is equality, not the picture.
JOBS = [
    dict(spp=4, res=(24, 16)),
    dict(spp=3, res=(16, 16), rr="spectral", spectral="8", seed=7, max_depth=4),
    dict(spp=2, res=(16, 12), sampler="sobol", first_sample=5, threads=1),
    dict(spp=2, res=(16, 16), integrator="bdpt", max_depth=3),
]


def cli_args(opts):
    """The CLI spelling of keyword options (what the module builds internally, written
    out by hand here so the test does not reuse the module's translation)."""
    out = []
    for k, v in opts.items():
        flag = "--" + k.replace("_", "-")
        if v is True:
            out.append(flag)
        elif isinstance(v, tuple):
            out += [flag, "x".join(map(str, v)) if k == "res" else ",".join(map(str, v))]
        else:
            out += [flag, str(v)]
    return out


@pytest.mark.parametrize("opts", JOBS, ids=lambda o: ",".join(o))
def test_image_equals_the_cli_bit_for_bit(tmp_path, cli, opts):
    exr, film = tmp_path / "cli.exr", tmp_path / "cli.kfilm"
    cli("render", "cornell", *cli_args(opts), "-q", "--aovs", "-o", exr)
    cli("render", "cornell", *cli_args(opts), "-q", "-o", film)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", kalos.KalosWarning)
        img = kalos.render("cornell", **opts)
    w, h = opts["res"]
    assert img.shape == (h, w, 3) and img.dtype == np.float32
    assert img.variance.shape == (h, w, 3) and img.count.shape == (h, w)
    # the EXR's float32 pixels, and the film file's sums, are the module's
    assert np.array_equal(kalos.read(exr), img)
    f = kalos.Film.read(film)
    assert f.to_bytes() == img.film.to_bytes()
    ref = f.image()
    assert np.array_equal(ref, img)
    assert np.array_equal(ref.variance, img.variance)
    assert np.array_equal(ref.count, img.count)
    assert np.all(img.count == opts["spp"])
    assert img.stats["spp"] == opts["spp"] and img.stats["width"] == w


@pytest.mark.parametrize(
    "opts",
    [dict(method="dtf", spp=16, res=(16, 16), dtf_n=8), dict(method="rw", spp=8, res=(16, 16), rw_pilot_res=8)],
    ids=["dtf", "rw"],
)
def test_dtf_and_rw_images_equal_the_cli(tmp_path, cli, opts):
    exr = tmp_path / "cli.exr"
    cli("render", "cornell", *cli_args(opts), "-q", "-o", exr)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", kalos.KalosWarning)
        img = kalos.render("cornell", **opts)
    assert np.array_equal(kalos.read(exr), img)
    assert img.film is None and img.stats["method"] == opts["method"]
    with pytest.raises(ValueError, match="plain render"):
        kalos.write(tmp_path / "x.kfilm", img)


def test_options_and_defaults_are_the_clis(tmp_path, cli):
    # the job the CLI records in a film file with no options is kalos.job() with none,
    # its method as rendered (a film file is a plain render's: the default auto is plain)
    film = tmp_path / "d.kfilm"
    cli("render", "cornell", "-q", "--spp", "1", "--res", "8x8", "-o", film)
    cli_job = kalos.Film.read(film).job
    assert cli_job == kalos.job("cornell", spp=1, res=(8, 8), method="plain")
    d = kalos.defaults()
    assert d["method"] == "auto"
    assert {k: v for k, v in cli_job.items() if k not in ("scene", "spp", "res", "method")} == {
        k: v for k, v in d.items() if k not in ("scene", "spp", "res", "method")
    }
    # every option in the table is one of `kalos render --help`'s, with its default
    help_text = cli("render", "--help").stdout
    for o in kalos.options():
        assert o["flag"] in help_text, o["flag"]
        if o["default"] is not None:
            shown = o["default"].replace(",", " ")
            assert f"[default: {shown}]" in help_text, o
    # a job with many options set: the CLI's film records the module's job
    opts = dict(spp=1, res=(8, 8), rr="spectral-estimate", rr_weight="flat", bsdf_select="mis",
                dtf_categories=(0, 5, 9), dtf_no_cost=True, rw_no_filter=True, max_depth=-1,
                camera=(0, 1, 3.5, 0, 1, 0, 0, 1, 0, 40), seed=11, dependent=True, method="plain")
    cli("render", "cornell", "-q", *cli_args(opts), "-o", film)
    assert kalos.Film.read(film).job == kalos.job("cornell", **opts)
    j = kalos.job("cornell", **opts)
    assert j["dtf"]["cost_aware"] is False and j["dtf"]["categories"] == [0, 5, 9]
    assert j["roulette"]["mode"] == "spectral-estimate" and j["max_depth"] == -1


@pytest.mark.parametrize(
    "opts",
    [
        dict(res="abc"),
        dict(res=(0, 5)),
        dict(max_depth=0),
        dict(rr="nope"),
        dict(spp=0),
        dict(seed=-3),
        dict(spp=3, time=1.5),
        dict(time=-1.0),
        dict(method="dtf", dtf_categories=(5, 1)),
        dict(rw_d=-1.0),
    ],
    ids=repr,
)
def test_bad_options_raise_value_error_with_the_cli_message(cli, opts):
    proc = cli("render", "cornell", "-q", "-o", "/tmp/never-written.exr",
               *[f"--{k.replace('_', '-')}={'x'.join(map(str, v)) if isinstance(v, tuple) and k == 'res' else ','.join(map(str, v)) if isinstance(v, tuple) else v}"
                 for k, v in opts.items()],
               check=False)
    with pytest.raises(ValueError) as e:
        kalos.render("cornell", **opts)
    assert str(e.value) == cli_error(proc)
    assert "\n" not in str(e.value)


def test_unknown_keywords_and_non_bool_flags_are_type_errors():
    with pytest.raises(TypeError, match="did you mean spp"):
        kalos.render("cornell", sppp=4)
    with pytest.raises(TypeError, match="True or False"):
        kalos.render("cornell", dependent="yes")


def test_scene_errors(tmp_path, cli):
    # a missing file
    with pytest.raises(FileNotFoundError, match="nothere.obj: no such file"):
        kalos.load(tmp_path / "nothere.obj")
    with pytest.raises(FileNotFoundError):
        kalos.render(str(tmp_path / "nothere.toml"), spp=1)
    # neither a built-in name nor a scene file
    with pytest.raises(ValueError, match="not a built-in scene"):
        kalos.load("cornel")
    with pytest.raises(ValueError, match=r"nor an \.obj, \.toml or Mitsuba \.xml file"):
        kalos.load(tmp_path / "mesh.ply")
    # a broken file: SceneError with the CLI's file:line message
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nf 1 2 7\n")
    with pytest.raises(kalos.SceneError) as e:
        kalos.load(bad)
    assert str(e.value) == cli_error(cli("render", bad, "-q", "--spp", "1", check=False))
    assert "bad.obj:3" in str(e.value)


def test_mitsuba_xml_loads_as_in_the_cli(cli):
    xml = ROOT / "scenes" / "mitsuba" / "cornell-box.xml"
    info = kalos.load(xml).info()
    cli_info = json.loads(cli("info", xml, "--json").stdout)
    for k in ("name", "triangles", "materials", "emitters", "bounds_min", "bounds_max"):
        assert info[k] == cli_info[k], k
    assert info["emitters"] > 0


def test_scenes_info_write_compare(tmp_path, cli):
    names = [l.split()[0] for l in cli("scenes").stdout.splitlines() if l.strip()]
    assert list(kalos.scenes()) == names
    s = kalos.load("cornell")
    info = s.info()
    cli_info = json.loads(cli("info", "cornell", "--json").stdout)
    for k in ("name", "triangles", "materials", "emitters", "bounds_min", "bounds_max"):
        assert info[k] == cli_info[k], k
    assert info["default_spp"] == s.default_spp == 64
    a = kalos.render(s, spp=2, res=(16, 16), seed=1)
    b = kalos.render(s, spp=8, res=(16, 16), seed=2)
    for ext in ("exr", "pfm", "png"):
        kalos.write(tmp_path / f"a.{ext}", a)
    assert np.array_equal(kalos.read(tmp_path / "a.exr"), a)
    assert np.array_equal(kalos.read(tmp_path / "a.pfm"), a)
    kalos.write(tmp_path / "b.exr", b, aovs=True)
    kalos.write(tmp_path / "b.kfilm", b)
    assert kalos.Film.read(tmp_path / "b.kfilm").to_bytes() == b.film.to_bytes()
    # compare: kalos compare --json's numbers, from arrays or from paths
    m = kalos.compare(a, tmp_path / "b.exr")
    cli_m = json.loads(cli("compare", tmp_path / "a.exr", tmp_path / "b.exr", "--json").stdout)
    assert m == cli_m
    assert kalos.compare(b, b)["rmse"] == 0.0
    with pytest.raises(ValueError, match="sizes differ"):
        kalos.compare(a, a[:8])
    with pytest.raises(ValueError, match="unknown|extension|format"):
        kalos.write(tmp_path / "a.txt", a)


def test_film_parts_merge_exactly_in_memory(tmp_path, cli):
    """Parts rendered by the module and by the CLI merge, as bytes or files, into the
    one-piece render, and merge refuses parts that do not belong together."""
    whole = kalos.render("cornell", spp=6, res=(16, 16))
    p1 = kalos.render("cornell", spp=2, res=(16, 16)).film
    cli("render", "cornell", "-q", "--spp", "4", "--first-sample", "2", "--res", "16x16", "-o", tmp_path / "p2.kfilm")
    m = kalos.merge([p1.to_bytes(), tmp_path / "p2.kfilm"])
    assert m.ranges == [(0, 2), (2, 6)] and m.spp == 6
    assert np.array_equal(m.image(), whole)
    assert np.array_equal(kalos.merge([tmp_path / "p2.kfilm", p1]).image(), whole)
    with pytest.raises(ValueError, match="overlap"):
        kalos.merge([p1, p1])
    other = kalos.render("cornell", spp=2, first_sample=2, res=(16, 16), seed=1).film
    with pytest.raises(ValueError, match="another render"):
        kalos.merge([p1, other])
    with pytest.raises(ValueError, match="truncated"):
        kalos.Film.from_bytes(p1.to_bytes()[:-3])
    # a Film pickles as its bytes
    import pickle
    assert pickle.loads(pickle.dumps(p1)).to_bytes() == p1.to_bytes()


def test_stub_lists_exactly_the_options():
    """The .pyi's render() and job() keywords are RenderJob's options, with the CLI's
    choices: the stub cannot drift from the CLI."""
    import ast

    stub = pathlib.Path(kalos.__file__).with_name("__init__.pyi")
    tree = ast.parse(stub.read_text())
    funcs = {n.name: n for n in tree.body if isinstance(n, ast.FunctionDef)}
    table = {o["name"]: o for o in kalos.options()}
    for fname, extra in (("render", {"progress"}), ("job", set())):
        kw = {a.arg: a.annotation for a in funcs[fname].args.kwonlyargs}
        assert set(kw) - extra == set(table), fname
        for name, ann in kw.items():
            if name in extra:
                continue
            text = ast.unparse(ann)
            if table[name]["choices"]:
                lit = [n for n in ast.walk(ann) if isinstance(n, ast.Subscript) and ast.unparse(n.value) == "Literal"]
                assert lit, (name, text)
                consts = [c.value for c in ast.walk(lit[0].slice) if isinstance(c, ast.Constant)]
                assert consts == table[name]["choices"], name
            if not table[name]["takes_value"]:
                assert "bool" in text, name
    # and every public function has a docstring
    for name in kalos.__all__:
        obj = getattr(kalos, name)
        if callable(obj) and not isinstance(obj, type) or name in ("Film", "Scene", "RenderResult"):
            assert obj.__doc__, name
