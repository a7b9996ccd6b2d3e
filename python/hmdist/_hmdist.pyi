"""Type stubs of the Rust half of the package (python/src/lib.rs). The checked, documented API
is `hmdist` itself (__init__.py); these are the arrays it hands over: C-contiguous float64
[n, 3] vectors and uint64 indices."""

from typing import Any, Optional, Sequence

import numpy as np
import numpy.typing as npt

__version__: str
BUILTIN_SCENES: list[str]
DEFAULT_RAYS: int
DEFAULT_SEED: int
DEFAULT_SIZE: tuple[int, int]

class DeviceError(Exception): ...

class Camera:
    def __init__(
        self,
        eye: npt.ArrayLike,
        target: npt.ArrayLike,
        up: Optional[npt.ArrayLike] = None,
        fov_y_deg: float = 60.0,
        size: Optional[npt.ArrayLike] = None,
        mirrored: bool = False,
    ) -> None: ...
    @property
    def eye(self) -> list[float]: ...
    @property
    def target(self) -> list[float]: ...
    @property
    def up(self) -> list[float]: ...
    @property
    def fov_y_deg(self) -> float: ...
    @property
    def size(self) -> tuple[int, int]: ...
    @property
    def mirrored(self) -> bool: ...
    def __reduce__(self) -> tuple[Any, ...]: ...

class Scene:
    @staticmethod
    def load(name_or_path: str) -> Scene: ...
    @staticmethod
    def from_arrays(
        vertices: npt.NDArray[np.float64], faces: npt.NDArray[np.uint64], name: str
    ) -> Scene: ...
    @property
    def info(self) -> dict[str, Any]: ...
    def render(
        self,
        camera: Optional[Camera],
        method: str,
        params: dict[str, Any],
        progress: bool,
        aov: list[str],
    ) -> tuple[npt.NDArray[np.float32], dict[str, Any], dict[str, npt.NDArray[np.float32]]]: ...
    def cache(
        self,
        camera: Optional[Camera],
        params: dict[str, Any],
        progress: bool,
        oracle: Optional[npt.NDArray[np.float32]] = None,
        reference: Optional[npt.NDArray[np.float32]] = None,
    ) -> tuple[npt.NDArray[np.float32], dict[str, Any], dict[str, npt.NDArray[Any]]]: ...
    def primary_hits(
        self, camera: Optional[Camera], size: tuple[int, int]
    ) -> dict[str, npt.NDArray[Any]]: ...
    def hmd_at(
        self,
        points: npt.NDArray[np.float64],
        normals: npt.NDArray[np.float64],
        rays: int,
        seed: int,
        keys: Optional[npt.NDArray[np.uint64]],
        weighting: str,
        max_distance: Optional[float],
        triangles: Optional[npt.NDArray[np.uint64]] = None,
        errors: Optional[npt.NDArray[np.float64]] = None,
        backend: str = "auto",
        sampler: str = "sobol",
    ) -> npt.NDArray[np.float32]: ...
    def cast(
        self, origins: npt.NDArray[np.float64], directions: npt.NDArray[np.float64]
    ) -> npt.NDArray[np.float32]: ...
    def __reduce__(self) -> tuple[Any, ...]: ...

def f_diff(
    reference: npt.NDArray[np.float64], test: npt.NDArray[np.float64], l_diag: float
) -> float: ...
def read_exr(path: str, channel: str = "Y") -> npt.NDArray[np.float32]: ...
