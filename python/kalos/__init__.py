"""kalos from Python: render scenes to numpy arrays, merge film parts, compare images.

>>> import kalos
>>> img = kalos.render("cornell", spp=64, seed=0, res=(128, 128))
>>> img.shape, img.dtype            # (H, W, 3) linear sRGB, float32
((128, 128, 3), dtype('float32'))
>>> img.stats["spp"], img.variance.shape, img.count.shape
(64, (128, 128, 3), (128, 128))

Every option of ``kalos render`` is a keyword argument with the same name (underscores
for dashes) and the same default: the keywords are turned into ``--name value`` and parsed
by the command line's own definition, so names, defaults, choices and error messages are
the CLI's. ``kalos.options()`` lists them. ``kalos.distributed.render`` spreads a render's
samples over a Dask cluster.
"""

from __future__ import annotations

import difflib
import json
import os
import warnings as _warnings
from typing import Any, Callable, Dict, Iterable, List, Optional, Tuple, Union

import numpy as np

from . import _kalos
from ._kalos import SceneError

__version__ = _kalos.__version__

__all__ = [
    "Film",
    "KalosWarning",
    "RenderResult",
    "Scene",
    "SceneError",
    "compare",
    "defaults",
    "job",
    "load",
    "merge",
    "options",
    "read",
    "render",
    "scenes",
    "write",
]

_OPTIONS: List[Dict[str, Any]] = json.loads(_kalos.options())
_BY_NAME: Dict[str, Dict[str, Any]] = {o["name"]: o for o in _OPTIONS}


class KalosWarning(UserWarning):
    """Something the user should know about a render (a scene's unsupported material,
    capped threads, an all-black image): the CLI's ``kalos: warning:`` lines."""


def options() -> List[Dict[str, Any]]:
    """The options of ``kalos render`` as a list of dicts, read from the CLI's own
    definition: ``name`` (the keyword), ``flag`` (``--name``), ``takes_value`` (False for
    on/off flags), ``default`` (as the CLI spells it, or None), ``choices``, ``help``."""
    return [dict(o) for o in _OPTIONS]


def _scalar(value: Any) -> str:
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        return repr(float(value))
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    return str(value)


def _argv(opts: Dict[str, Any]) -> List[str]:
    """Keyword arguments -> the ``kalos render`` argument vector they stand for."""
    argv: List[str] = []
    for name, value in opts.items():
        o = _BY_NAME.get(name)
        if o is None:
            close = difflib.get_close_matches(name, list(_BY_NAME), n=1)
            tip = f" (did you mean {close[0]}?)" if close else ""
            raise TypeError(f"unexpected keyword argument {name!r}{tip}")
        if value is None:
            continue
        if not o["takes_value"]:
            if not isinstance(value, (bool, np.bool_)):
                raise TypeError(f"{name}: an on/off flag ({o['flag']}) takes True or False, not {value!r}")
            if value:
                argv.append(o["flag"])
            continue
        if isinstance(value, (tuple, list, np.ndarray)):
            sep = "x" if name == "res" else ","
            text = sep.join(_scalar(v) for v in value)
        else:
            text = _scalar(value)
        # --name=value: values that start with '-' (max_depth=-1) stay values
        argv.append(f"{o['flag']}={text}")
    return argv


def job(scene: Union[str, os.PathLike, "Scene"] = "", **options: Any) -> Dict[str, Any]:
    """The render job the options describe (what ``--stats`` and film files record), as a
    dict, without rendering. Raises ValueError with the CLI's message for a bad option."""
    spec = scene.spec if isinstance(scene, Scene) else os.fspath(scene)
    return json.loads(_kalos.parse(spec, _argv(options)))


def defaults() -> Dict[str, Any]:
    """Every option at its default: the job of an empty ``kalos render`` command line."""
    return job("")


class Scene:
    """A loaded scene (``kalos.load``); immutable, and reusable by any number of renders."""

    def __init__(self, native: Any):
        """Wrap the native scene (use ``kalos.load``)."""
        self._native = native

    @property
    def spec(self) -> str:
        """What the scene was loaded from: a built-in name or a path."""
        return self._native.spec

    @property
    def warnings(self) -> List[str]:
        """The scene's warnings (unsupported materials, no emitter, skipped faces)."""
        return list(self._native.warnings)

    @property
    def default_spp(self) -> int:
        """Samples per pixel of a render that gives none (the scene file's, else 64)."""
        return self._native.default_spp

    def info(self) -> Dict[str, Any]:
        """``kalos info --json``: name, triangles, materials, emitters, bounds, load and
        BVH times, plus the scene's render defaults and warnings."""
        return json.loads(self._native.info_json())

    def __repr__(self) -> str:
        return f"kalos.Scene({self.spec!r})"


def scenes() -> Dict[str, str]:
    """The built-in scenes: name -> one-line description (``kalos scenes``)."""
    return dict(_kalos.scenes())


def load(scene: Union[str, os.PathLike], **defines: Any) -> Scene:
    """Load a scene: a built-in name (see ``scenes()``), an .obj, a .toml or a
    Mitsuba .xml file.

    Keyword arguments set a Mitsuba file's parameters as ``mi.load_file(path, spp=64)``
    and ``-D spp=64`` do: each replaces the file's ``<default name="spp">`` (a name the
    file does not use is a ``kalos.SceneError``).

    Raises FileNotFoundError for a missing file, ValueError for a name that is neither a
    built-in scene nor a scene file, and ``kalos.SceneError`` (with the loader's one-line
    ``file:line: what`` message) for a file kalos cannot read."""
    pairs = [(k, str(v).lower() if isinstance(v, bool) else str(v)) for k, v in defines.items()]
    return Scene(_kalos.load(os.fspath(scene), pairs))


def _scene(scene: Union[str, os.PathLike, Scene]) -> Scene:
    return scene if isinstance(scene, Scene) else load(scene)


class RenderResult(np.ndarray):
    """The image of a render: a float32 numpy array (H, W, 3), linear sRGB, with

    - ``variance``: (H, W, 3) float32, the variance of each pixel's value;
    - ``count``: (H, W) float32, samples per pixel;
    - ``stats``: the ``--stats`` dict (spp, seconds, paths, rays, ...);
    - ``film``: the ``Film`` part (plain renders; None for dtf and rw);
    - ``job``: the job dict; ``warnings``: the render's warnings.

    Slices and arithmetic give plain values of this class whose extra attributes are
    kept only while the shape is the image's."""

    _extra = ("variance", "count", "stats", "film", "job", "warnings")

    def __array_finalize__(self, obj: Any) -> None:
        same = obj is not None and getattr(obj, "shape", None) == self.shape
        for a in self._extra:
            setattr(self, a, getattr(obj, a, None) if same else None)

    def __reduce__(self):  # keep the attributes when pickled (Dask, multiprocessing)
        rebuild, args, state = super().__reduce__()
        extra = {a: getattr(self, a, None) for a in self._extra}
        return (rebuild, args, (state, extra))

    def __setstate__(self, state):
        base, extra = state
        super().__setstate__(base)
        for a, v in extra.items():
            setattr(self, a, v)


def _arrays(width: int, height: int, image: bytes, variance: bytes, count: bytes) -> RenderResult:
    img = np.frombuffer(image, dtype="<f4").reshape(height, width, 3).astype(np.float32)
    r = img.view(RenderResult)
    r.variance = np.frombuffer(variance, dtype="<f4").reshape(height, width, 3).astype(np.float32)
    r.count = np.frombuffer(count, dtype="<f4").reshape(height, width).astype(np.float32)
    return r


ProgressArg = Union[bool, None, Callable[[int, int], Any]]


def _progress(progress: ProgressArg, what: str) -> Tuple[Optional[Callable[[int, int], Any]], Any]:
    """The callback of ``progress=``: a tqdm bar for True (``tqdm.auto``: a widget in
    Jupyter, a text bar in a terminal), none for False or None, the user's own callable
    as given. Returns (callback, bar to close or None)."""
    if progress is None or progress is False:
        return None, None
    if callable(progress) and not isinstance(progress, bool):
        return progress, None
    if progress is not True:
        raise TypeError(f"progress: expected True, False or a callable(done, total), got {progress!r}")
    from tqdm.auto import tqdm

    bar = tqdm(total=0, desc=what, unit="sample", unit_scale=True, leave=False, dynamic_ncols=True)

    def update(done: int, total: int) -> None:
        if bar.total != total:
            bar.total = total
        bar.update(done - bar.n)

    return update, bar


def render(
    scene: Union[str, os.PathLike, Scene],
    *,
    progress: ProgressArg = True,
    **options: Any,
) -> RenderResult:
    """Render a scene (a ``Scene``, a built-in name or a scene file) with the options of
    ``kalos render`` as keywords (``spp=64, seed=0, res=(256, 256), rr="classic"``...;
    ``kalos.options()`` lists them with their defaults).

    Returns a ``RenderResult``: the (H, W, 3) float32 image with ``.variance``, ``.count``,
    ``.stats`` and ``.film``. The GIL is released while rendering. ``progress``: a tqdm
    progress bar by default (in a terminal and in Jupyter), ``False`` for none, or a
    callable ``progress(done, total)`` called every 100 ms with the samples done and
    planned.

    Raises ValueError for a bad option (the CLI's one-line message), TypeError for an
    unknown keyword, FileNotFoundError / SceneError for a missing / unreadable scene file,
    and KeyboardInterrupt on Ctrl-C (the render stops at the next row of pixels)."""
    argv = _argv(options)
    sc = _scene(scene)
    callback, bar = _progress(progress, f"kalos {os.path.basename(sc.spec)}")
    try:
        out = _kalos.render(sc._native, argv, callback)
    finally:
        if bar is not None:
            bar.close()
    for w in out.warnings:
        _warnings.warn(w, KalosWarning, stacklevel=2)
    r = _arrays(out.width, out.height, out.image, out.variance, out.count)
    r.stats = json.loads(out.stats)
    r.job = json.loads(out.job)
    r.warnings = list(out.warnings)
    r.film = Film(out.film) if out.film is not None else None
    return r


class Film:
    """A film part: the exact per-pixel sums of a range of samples of one render, with the
    job that made it (a ``.kfilm`` file). Parts of one render merge exactly (``merge``)."""

    def __init__(self, native: Any):
        """Wrap a native film (use ``Film.read``, ``Film.from_bytes`` or a render's
        ``.film``)."""
        self._native = native

    @classmethod
    def read(cls, path: Union[str, os.PathLike]) -> "Film":
        """Read a ``.kfilm`` file (``kalos render -o part.kfilm``). ValueError for a
        truncated or foreign file, FileNotFoundError for a missing one."""
        return cls(_kalos.NativeFilm.read(os.fspath(path)))

    @classmethod
    def from_bytes(cls, data: bytes, name: str = "film") -> "Film":
        """A part from ``to_bytes()``'s bytes; ``name`` starts the error messages."""
        return cls(_kalos.NativeFilm.from_bytes(bytes(data), name))

    def to_bytes(self) -> bytes:
        """The part's bytes: exactly what ``write`` puts in a ``.kfilm`` file."""
        return self._native.to_bytes()

    def write(self, path: Union[str, os.PathLike]) -> None:
        """Write a ``.kfilm`` file (for ``kalos merge``)."""
        self._native.write(os.fspath(path))

    @property
    def job(self) -> Dict[str, Any]:
        """The job that rendered the part."""
        return json.loads(self._native.job)

    @property
    def ranges(self) -> List[Tuple[int, int]]:
        """The sample index ranges [first, end) the part holds."""
        return [tuple(r) for r in self._native.ranges]

    @property
    def spp(self) -> int:
        """Samples per pixel the part holds."""
        return sum(b - a for a, b in self.ranges)

    @property
    def size(self) -> Tuple[int, int]:
        """(width, height)."""
        return tuple(self._native.size)

    def image(self) -> RenderResult:
        """The film's image (the mean of its samples) with ``.variance`` and ``.count``."""
        r = _arrays(*self._native.arrays())
        r.job = self.job
        r.film = self
        return r

    def __reduce__(self):
        return (Film.from_bytes, (self.to_bytes(),))

    def __repr__(self) -> str:
        w, h = self.size
        return f"kalos.Film({w}x{h}, samples {self.ranges})"


def merge(parts: Iterable[Union[Film, bytes, str, os.PathLike]]) -> Film:
    """Merge film parts of one render (``Film``s, their bytes or ``.kfilm`` paths) exactly:
    integer sums, so any order gives the same bits. ValueError for parts of different
    jobs or sizes, overlapping sample ranges, or a truncated part."""
    films = []
    for i, p in enumerate(parts):
        if isinstance(p, Film):
            films.append(p)
        elif isinstance(p, (bytes, bytearray, memoryview)):
            films.append(Film.from_bytes(bytes(p), f"part {i}"))
        else:
            films.append(Film.read(p))
    if not films:
        raise ValueError("merge: no film parts given")
    return Film(_kalos.NativeFilm.merge([f._native for f in films]))


def _image_arg(img: Any, what: str) -> np.ndarray:
    if isinstance(img, (str, os.PathLike)):
        return read(img)
    a = np.ascontiguousarray(img, dtype="<f4")
    if a.ndim != 3 or a.shape[2] != 3:
        raise ValueError(f"{what}: an (H, W, 3) RGB image is needed, not shape {a.shape}")
    return a


def write(path: Union[str, os.PathLike], img: Any, exposure: float = 0.0, aovs: bool = False) -> None:
    """Write an image by the path's extension: .exr or .pfm (linear float), .png (sRGB, 8
    bits, ``exposure`` in stops), or .kfilm (a render's film part). ``aovs=True`` adds a
    ``RenderResult``'s variance and count as extra EXR layers."""
    p = os.fspath(path)
    if p.lower().endswith(".kfilm"):
        film = getattr(img, "film", None)
        if film is None:
            raise ValueError(f"{p}: a .kfilm holds a plain render's film: pass the RenderResult of a plain render")
        film.write(p)
        return
    a = _image_arg(img, p)
    h, w, _ = a.shape
    var = cnt = None
    if aovs:
        v, c = getattr(img, "variance", None), getattr(img, "count", None)
        if v is None or c is None:
            raise ValueError(f"{p}: aovs=True needs a RenderResult (with .variance and .count)")
        var = np.ascontiguousarray(v, dtype="<f4").tobytes()
        cnt = np.ascontiguousarray(c, dtype="<f4").tobytes()
    _kalos.write(p, w, h, a.tobytes(), float(exposure), var, cnt)


def read(path: Union[str, os.PathLike]) -> np.ndarray:
    """Read an image (.exr, .pfm linear; .png decoded from sRGB) as (H, W, 3) float32."""
    w, h, data = _kalos.read_image(os.fspath(path))
    return np.frombuffer(data, dtype="<f4").reshape(h, w, 3).copy()


def _is_png(img: Any) -> bool:
    return isinstance(img, (str, os.PathLike)) and os.fspath(img).lower().endswith(".png")


def compare(image: Any, reference: Any) -> Dict[str, Any]:
    """``kalos compare``'s metrics of an image against a reference (arrays or image
    paths): rmse, relmse, mse, perceptual_count and perceptual_share (pixels over 5%
    relative colour error), luminance_ratio, flip (NVIDIA's FLIP: LDR-FLIP when both are
    PNG files, else HDR-FLIP of linear radiance; ``flip_range`` says which), width, height."""
    ldr = _is_png(image) and _is_png(reference)
    x = _image_arg(image, "image")
    y = _image_arg(reference, "reference")
    return json.loads(
        _kalos.compare(x.shape[1], x.shape[0], x.tobytes(), y.shape[1], y.shape[0], y.tobytes(), ldr)
    )

from . import distributed  # noqa: E402  (pure Python; imports Dask only when used)
