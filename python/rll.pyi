# Type stub of the rll module (python/rll_module.cpp).
import os
from typing import Any, Callable, Literal, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

_Path = Union[str, bytes, os.PathLike[str], os.PathLike[bytes]]
_Res = Union[None, str, Tuple[int, int]]
_ImageLike = npt.ArrayLike

class Error(RuntimeError): ...
class ArgumentTypeError(Error, TypeError): ...
class ArgumentValueError(Error, ValueError): ...

class Scene:
    @property
    def source(self) -> str: ...
    @property
    def lights(self) -> int: ...
    @property
    def triangles(self) -> int: ...
    @property
    def bounds(self) -> Tuple[Tuple[float, float, float], Tuple[float, float, float]]: ...
    @property
    def resolution(self) -> Tuple[int, int]: ...

class State:
    @property
    def sampler(self) -> str: ...
    @property
    def passes(self) -> int: ...
    @property
    def capacity(self) -> int: ...
    @property
    def lights(self) -> int: ...
    @property
    def cells(self) -> dict[str, npt.NDArray[Any]]: ...
    def cut(self, cell: int) -> dict[str, Any]: ...
    @property
    def initial_cut(self) -> npt.NDArray[np.uint32]: ...
    @property
    def tree(self) -> dict[str, npt.NDArray[Any]]: ...
    @overload
    def pmf(
        self, cell: int, light: int, point: Optional[Sequence[float]] = None,
        normal: Optional[Sequence[float]] = None,
    ) -> float: ...
    @overload
    def pmf(
        self, cell: int, light: None = None, point: Optional[Sequence[float]] = None,
        normal: Optional[Sequence[float]] = None,
    ) -> npt.NDArray[np.float32]: ...
    def save(self, path: _Path) -> None: ...

class Render:
    @property
    def image(self) -> npt.NDArray[np.float32]: ...
    @property
    def counts(self) -> npt.NDArray[np.uint32]: ...
    @property
    def aov(self) -> dict[str, npt.NDArray[np.float32]]: ...
    @property
    def state(self) -> Optional[State]: ...
    @property
    def spp(self) -> int: ...
    @property
    def seconds(self) -> float: ...
    @property
    def interrupted(self) -> bool: ...
    @property
    def stats(self) -> dict[str, Any]: ...

def scenes() -> dict[str, str]: ...
def samplers() -> list[str]: ...
def load(path: _Path, res: _Res = None) -> Scene: ...
def render(
    scene: Scene,
    sampler: str = "rll",
    integrator: str = "path",
    max_depth: int = 5,
    spp: int = 16,
    time: Optional[float] = None,
    res: _Res = None,
    seed: int = 1,
    params: dict[str, Any] = {},
    threads: int = 0,
    progress: Optional[Callable[[dict[str, Any]], None]] = None,
    aov: Union[None, str, Sequence[str]] = None,
    wavefront: bool = False,
    device: str = "cpu",
    pass_spp: int = 1,
    max_pass_spp: int = 8,
    filter: str = "none",
) -> Render: ...
def load_state(
    path: _Path, scene: Scene, sampler: str = "rll", params: dict[str, Any] = {}
) -> Optional[State]: ...
def aov_names() -> dict[str, str]: ...
def cell_colours(cells: _ImageLike) -> npt.NDArray[np.float32]: ...
def reference(
    scene: Scene,
    spp: int = 1024,
    sampler: str = "tree",
    seed: int = 1000003,
    integrator: str = "path",
    max_depth: int = 5,
    params: dict[str, Any] = {},
    cache_dir: Optional[_Path] = None,
    force: bool = False,
    threads: int = 0,
) -> dict[str, Any]: ...
def compare(
    scene: Scene,
    samplers: Sequence[str],
    spp: Optional[int] = None,
    time: Optional[float] = None,
    repeats: int = 1,
    seed: int = 1,
    reference: Union[None, _Path, _ImageLike] = None,
    reference_spp: int = 1024,
    reference_sampler: str = "tree",
    integrator: str = "path",
    max_depth: int = 5,
    params: dict[str, Any] = {},
    cache_dir: Optional[_Path] = None,
    threads: int = 0,
    progress: Optional[Callable[[dict[str, Any]], None]] = None,
) -> dict[str, Any]: ...
def error(
    img: _ImageLike, ref: _ImageLike, reference_variance: Optional[_ImageLike] = None
) -> dict[str, Union[float, bool]]: ...
@overload
def read_exr(path: _Path, metadata: Literal[False] = False) -> npt.NDArray[np.float32]: ...
@overload
def read_exr(
    path: _Path, metadata: Literal[True]
) -> Tuple[npt.NDArray[np.float32], dict[str, Any]]: ...
def write_exr(
    path: _Path,
    image: _ImageLike,
    count: Optional[_ImageLike] = None,
    attributes: dict[str, str] = {},
    share: Optional[dict[str, Any]] = None,
) -> None: ...
