# Type stub of the kalos package. The keyword options of render() and job() are those of
# `kalos render` (python/tests/test_module.py::test_stub_lists_exactly_the_options checks that this list is exactly RenderJob's, with
# the same choices, so the stub cannot drift from the CLI).
import os
from typing import Any, Callable, Dict, Iterable, List, Literal, Optional, Sequence, Tuple, Union

import numpy as np

from . import distributed as distributed

__version__: str

class SceneError(Exception):
    """A scene file kalos cannot read (file:line and what is wrong)."""

class KalosWarning(UserWarning): ...

class Scene:
    @property
    def spec(self) -> str: ...
    @property
    def warnings(self) -> List[str]: ...
    @property
    def default_spp(self) -> int: ...
    def info(self) -> Dict[str, Any]: ...

class Film:
    @classmethod
    def read(cls, path: Union[str, os.PathLike[str]]) -> Film: ...
    @classmethod
    def from_bytes(cls, data: bytes, name: str = ...) -> Film: ...
    def to_bytes(self) -> bytes: ...
    def write(self, path: Union[str, os.PathLike[str]]) -> None: ...
    @property
    def job(self) -> Dict[str, Any]: ...
    @property
    def ranges(self) -> List[Tuple[int, int]]: ...
    @property
    def spp(self) -> int: ...
    @property
    def size(self) -> Tuple[int, int]: ...
    def image(self) -> RenderResult: ...

class RenderResult(np.ndarray[Any, np.dtype[np.float32]]):
    variance: Optional[np.ndarray[Any, np.dtype[np.float32]]]
    count: Optional[np.ndarray[Any, np.dtype[np.float32]]]
    stats: Optional[Dict[str, Any]]
    film: Optional[Film]
    job: Optional[Dict[str, Any]]
    warnings: Optional[List[str]]

SceneLike = Union[str, os.PathLike[str], Scene]
ImageLike = Union[np.ndarray[Any, Any], str, os.PathLike[str]]

def options() -> List[Dict[str, Any]]: ...
def defaults() -> Dict[str, Any]: ...
def scenes() -> Dict[str, str]: ...
def load(scene: Union[str, os.PathLike[str]], **defines: Any) -> Scene: ...
def render(
    scene: SceneLike,
    *,
    progress: Union[bool, None, Callable[[int, int], Any]] = ...,
    spp: Optional[int] = ...,
    time: Optional[float] = ...,
    res: Optional[Union[Tuple[int, int], str]] = ...,
    camera: Optional[Union[Sequence[float], str]] = ...,
    method: Optional[Literal['auto', 'plain', 'dtf', 'rw']] = ...,
    integrator: Optional[Literal['path', 'bdpt', 'radiosity']] = ...,
    define: Optional[str] = ...,
    bdpt_mis: Optional[Literal['balance', 'power']] = ...,
    gather: Optional[Literal['off', 'radiosity']] = ...,
    gather_depth: Optional[int] = ...,
    gather_rays: Optional[int] = ...,
    rr_estimate: Optional[Literal['scene', 'radiosity']] = ...,
    radiosity_max_area: Optional[float] = ...,
    radiosity_tolerance: Optional[float] = ...,
    radiosity_source_level: Optional[int] = ...,
    radiosity_max_elements: Optional[int] = ...,
    radiosity_max_shots: Optional[int] = ...,
    max_depth: Optional[int] = ...,
    spectral: Optional[Literal['rgb', '8', '16']] = ...,
    sampler: Optional[Literal['random', 'sobol']] = ...,
    dependent: Optional[bool] = ...,
    rr: Optional[Literal['off', 'classic', 'spectral', 'estimate', 'spectral-estimate', 'throughput']] = ...,
    rr_weight: Optional[Literal['flat', 'luminance']] = ...,
    bsdf_select: Optional[Literal['mixture', 'decompose', 'static', 'mis']] = ...,
    rr_min_depth: Optional[int] = ...,
    seed: Optional[int] = ...,
    first_sample: Optional[int] = ...,
    threads: Optional[int] = ...,
    dtf_n: Optional[int] = ...,
    dtf_eps: Optional[float] = ...,
    dtf_categories: Optional[Sequence[int]] = ...,
    dtf_mmax: Optional[int] = ...,
    dtf_df0: Optional[float] = ...,
    dtf_kernel: Optional[Literal['pyramid', 'gaussian']] = ...,
    dtf_clamp: Optional[Literal['paper', 'active-set']] = ...,
    dtf_floor: Optional[float] = ...,
    dtf_rel_floor: Optional[float] = ...,
    dtf_keep_converged: Optional[float] = ...,
    dtf_max_ratio: Optional[float] = ...,
    dtf_alloc: Optional[Literal['paper', 'mse', 'rel-mse']] = ...,
    dtf_no_cost: Optional[bool] = ...,
    dtf_rounds: Optional[int] = ...,
    dtf_topup: Optional[float] = ...,
    dtf_topup_own: Optional[bool] = ...,
    dtf_stop_ratio: Optional[float] = ...,
    dtf_guard: Optional[float] = ...,
    dtf_paper_display: Optional[bool] = ...,
    dtf_cd: Optional[Literal['scaled', 'filtered', 'none', 'mse']] = ...,
    dtf_dep_noise: Optional[float] = ...,
    dtf_z: Optional[float] = ...,
    dtf_light: Optional[Literal['auto', 'off']] = ...,
    dtf_light_share: Optional[float] = ...,
    dtf_direct: Optional[Literal['split', 'filter']] = ...,
    rw_d: Optional[float] = ...,
    rw_t: Optional[float] = ...,
    rw_pilot_res: Optional[int] = ...,
    rw_no_filter: Optional[bool] = ...,
    rw_no_correction: Optional[bool] = ...,
    rw_filter_emitters: Optional[bool] = ...,
    rw_pixel_test: Optional[bool] = ...,
    rw_target: Optional[Literal['linear', 'display']] = ...,
    filter: Optional[Literal['energy']] = ...,
) -> RenderResult: ...
def job(
    scene: SceneLike = ...,
    *,
    spp: Optional[int] = ...,
    time: Optional[float] = ...,
    res: Optional[Union[Tuple[int, int], str]] = ...,
    camera: Optional[Union[Sequence[float], str]] = ...,
    method: Optional[Literal['auto', 'plain', 'dtf', 'rw']] = ...,
    integrator: Optional[Literal['path', 'bdpt', 'radiosity']] = ...,
    define: Optional[str] = ...,
    bdpt_mis: Optional[Literal['balance', 'power']] = ...,
    gather: Optional[Literal['off', 'radiosity']] = ...,
    gather_depth: Optional[int] = ...,
    gather_rays: Optional[int] = ...,
    rr_estimate: Optional[Literal['scene', 'radiosity']] = ...,
    radiosity_max_area: Optional[float] = ...,
    radiosity_tolerance: Optional[float] = ...,
    radiosity_source_level: Optional[int] = ...,
    radiosity_max_elements: Optional[int] = ...,
    radiosity_max_shots: Optional[int] = ...,
    max_depth: Optional[int] = ...,
    spectral: Optional[Literal['rgb', '8', '16']] = ...,
    sampler: Optional[Literal['random', 'sobol']] = ...,
    dependent: Optional[bool] = ...,
    rr: Optional[Literal['off', 'classic', 'spectral', 'estimate', 'spectral-estimate', 'throughput']] = ...,
    rr_weight: Optional[Literal['flat', 'luminance']] = ...,
    bsdf_select: Optional[Literal['mixture', 'decompose', 'static', 'mis']] = ...,
    rr_min_depth: Optional[int] = ...,
    seed: Optional[int] = ...,
    first_sample: Optional[int] = ...,
    threads: Optional[int] = ...,
    dtf_n: Optional[int] = ...,
    dtf_eps: Optional[float] = ...,
    dtf_categories: Optional[Sequence[int]] = ...,
    dtf_mmax: Optional[int] = ...,
    dtf_df0: Optional[float] = ...,
    dtf_kernel: Optional[Literal['pyramid', 'gaussian']] = ...,
    dtf_clamp: Optional[Literal['paper', 'active-set']] = ...,
    dtf_floor: Optional[float] = ...,
    dtf_rel_floor: Optional[float] = ...,
    dtf_keep_converged: Optional[float] = ...,
    dtf_max_ratio: Optional[float] = ...,
    dtf_alloc: Optional[Literal['paper', 'mse', 'rel-mse']] = ...,
    dtf_no_cost: Optional[bool] = ...,
    dtf_rounds: Optional[int] = ...,
    dtf_topup: Optional[float] = ...,
    dtf_topup_own: Optional[bool] = ...,
    dtf_stop_ratio: Optional[float] = ...,
    dtf_guard: Optional[float] = ...,
    dtf_paper_display: Optional[bool] = ...,
    dtf_cd: Optional[Literal['scaled', 'filtered', 'none', 'mse']] = ...,
    dtf_dep_noise: Optional[float] = ...,
    dtf_z: Optional[float] = ...,
    dtf_light: Optional[Literal['auto', 'off']] = ...,
    dtf_light_share: Optional[float] = ...,
    dtf_direct: Optional[Literal['split', 'filter']] = ...,
    rw_d: Optional[float] = ...,
    rw_t: Optional[float] = ...,
    rw_pilot_res: Optional[int] = ...,
    rw_no_filter: Optional[bool] = ...,
    rw_no_correction: Optional[bool] = ...,
    rw_filter_emitters: Optional[bool] = ...,
    rw_pixel_test: Optional[bool] = ...,
    rw_target: Optional[Literal['linear', 'display']] = ...,
    filter: Optional[Literal['energy']] = ...,
) -> Dict[str, Any]: ...
def merge(parts: Iterable[Union[Film, bytes, str, os.PathLike[str]]]) -> Film: ...
def write(path: Union[str, os.PathLike[str]], img: Any, exposure: float = ..., aovs: bool = ...) -> None: ...
def read(path: Union[str, os.PathLike[str]]) -> np.ndarray[Any, np.dtype[np.float32]]: ...
def compare(image: ImageLike, reference: ImageLike) -> Dict[str, Any]: ...
