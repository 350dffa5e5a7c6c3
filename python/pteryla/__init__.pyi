# Type stub of the pteryla package (python/module.cpp and python/pteryla/*.py).
import os
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

_Path = Union[str, os.PathLike]
_SetupLike = Union["Setup", Dict[str, Any], None]

__version__: str

class Error(Exception):
    file: str
    element: str
    detail: str
    def __init__(self, message: str, file: str = ..., element: str = ..., detail: Optional[str] = ...) -> None: ...

def version() -> str: ...
def data_directory() -> str: ...
def setup_from_dict(d: Dict[str, Any], base_dir: Optional[_Path] = ...) -> Setup: ...

class Tract:
    name: str
    groups: List[str]
    faces: npt.NDArray[np.uint32]
    count: int
    density: float
    feather_file: str
    feather_scale: float
    feather_spacings: float
    relax_iterations: int
    seed: Optional[int]
    moult: bool
    def __init__(self, name: str, *, groups: Sequence[str] = ..., faces: Optional[npt.ArrayLike] = ...,
                 count: int = ..., density: float = ..., feather_file: Optional[_Path] = ...,
                 feather_scale: float = ..., feather_spacings: float = ..., relax_iterations: int = ...,
                 seed: Optional[int] = ..., moult: bool = ...) -> None: ...

class Moult:
    enabled: bool
    start: float
    duration: float
    window: float
    sequence: str
    gap: float
    random: float
    seed: int
    def __init__(self, *, enabled: bool = ..., start: float = ..., duration: float = ..., window: float = ...,
                 sequence: str = ..., gap: float = ..., random: float = ..., seed: int = ...) -> None: ...

class Control:
    name: str
    at: Tuple[float, float, float]
    radius: float
    falloff: float
    tracts: List[str]
    interpolation: str  # "linear" | "smooth" | "step"
    seed: int
    twist_angle: float
    max_lift: float
    @property
    def key_count(self) -> int: ...
    def __init__(self, at: Tuple[float, float, float], radius: float, *, name: str = ..., falloff: float = ...,
                 tracts: Sequence[str] = ..., keys: Sequence[Dict[str, Any]] = ..., interpolation: str = ...,
                 seed: int = ..., twist_angle: float = ..., max_lift: float = ...) -> None: ...

class Setup:
    tracts: List[Tract]
    axis: List[Tuple[float, float, float]]
    ordering: str  # "axis" | "tracts" | "flow"
    tract_order: List[str]
    packing: str  # "drape" | "height_field"
    seed: int
    moult: Moult
    controls: List[Control]
    def __init__(self, *, tracts: Sequence[Tract] = ..., axis: Sequence[Tuple[float, float, float]] = ...,
                 ordering: str = ..., tract_order: Sequence[str] = ..., packing: str = ..., seed: int = ...,
                 moult: Optional[Moult] = ..., controls: Sequence[Control] = ...) -> None: ...

class Frame:
    feather_count: int
    follicle_keys: npt.NDArray[np.uint64]   # (n,)
    tracts: npt.NDArray[np.uint32]          # (n,)
    present: npt.NDArray[np.bool_]          # (n,)
    origins: npt.NDArray[np.float64]        # (n, 3)
    normals: npt.NDArray[np.float64]        # (n, 3)
    tangents: npt.NDArray[np.float64]       # (n, 3)
    binormals: npt.NDArray[np.float64]      # (n, 3)
    elevations: npt.NDArray[np.float64]     # (n,) radians
    positions: npt.NDArray[np.float32]      # (v, 3)
    vertex_normals: npt.NDArray[np.float32]  # (v, 3)
    uvs: npt.NDArray[np.float32]            # (v, 2)
    alphas: npt.NDArray[np.float32]         # (v,) or (0,)
    vertex_feathers: npt.NDArray[np.uint32]  # (v,)
    triangles: npt.NDArray[np.uint32]       # (t, 3)
    ranges: npt.NDArray[np.uint32]          # (r, 4): feather, first_index, index_count, material
    materials: List[Dict[str, Any]]         # name, texture, alpha_texture, pattern, base_color

class Session:
    def __init__(self, positions: npt.ArrayLike, triangles: npt.ArrayLike, setup: _SetupLike = ..., *,
                 face_groups: Optional[npt.ArrayLike] = ..., group_names: Optional[Sequence[str]] = ...,
                 repair: bool = ...) -> None: ...
    @staticmethod
    def from_scene_file(path: _Path) -> Session: ...
    @property
    def vertex_count(self) -> int: ...
    @property
    def face_count(self) -> int: ...
    @property
    def time(self) -> float: ...
    @property
    def lod(self) -> float: ...
    pose_mode: str  # "repack" | "follow"
    def set_fixed_elevations(self, follicle_keys: npt.ArrayLike, elevations: npt.ArrayLike) -> None: ...
    def set_pose(self, positions: npt.ArrayLike) -> None: ...
    def clear_pose(self) -> None: ...
    def set_time(self, t: float) -> None: ...
    def set_lod(self, fraction: float) -> None: ...
    def set_instance_tolerance(self, fraction: float) -> None: ...
    @property
    def instance_tolerance(self) -> float: ...
    def evaluate(self, progress: Optional[Callable[[str, float], Optional[bool]]] = ...) -> bool: ...
    def frame(self, copy: bool = ...) -> Frame: ...
    def check(self) -> Dict[str, Optional[Union[int, float]]]: ...
    def render(self, path: _Path, width: int = 0, height: int = 0, style: str = "") -> None: ...
    def export(self, path: _Path, times: Optional[Sequence[float]] = None, fps: float = 24.0,
               coat_as: str = "curves", meters_per_unit: float = 1.0) -> Optional[Dict[str, float]]: ...
