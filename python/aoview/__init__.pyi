# The types of the package aoview (docs/python.md): every setting of render(), passes() and view()
# as an explicit keyword, as the command line's options they stand for (None: the option's default).
import os
from typing import Iterator, Literal, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

Sampling = Literal['uniform', 'hemisphere', 'cosine']
Sampler = Literal['random', 'sobol']
Shading = Literal['flat', 'phong']
BelowSurface = Literal['reflect', 'trace']
Bvh = Literal['auto', 'medium', 'compact', 'low']
Path = Union[str, bytes, 'os.PathLike[str]', 'os.PathLike[bytes]']
Triple = Union[float, Sequence[float]]
Image = npt.NDArray[np.float32]
Reference = Union[None, str, 'os.PathLike[str]', npt.ArrayLike]

UNIFORM_SAMPLING: Literal['uniform']
HEMISPHERE_SAMPLING: Literal['hemisphere']
COSINE_SAMPLING: Literal['cosine']
TNEAR: float


class Scene:
    @classmethod
    def load(cls, path: Path, *, crease_angle: Optional[float] = ..., ground: Optional[bool] = ...,
             scene_budget: Union[None, int, str] = ..., bvh: Optional[Bvh] = ...) -> 'Scene': ...

    @classmethod
    def from_arrays(cls, vertices: npt.ArrayLike, faces: npt.ArrayLike, *, normals: Optional[npt.ArrayLike] = ...,
                    spheres: Optional[Sequence[Union[Tuple[Sequence[float], float],
                                                     Tuple[Sequence[float], float, Triple]]]] = ...,
                    albedo: Triple = ..., camera: Optional[dict] = ..., ground: Optional[bool] = ...,
                    crease_angle: Optional[float] = ..., scene_budget: Union[None, int, str] = ..., bvh: Optional[Bvh] = ...,
                    name: str = ...) -> 'Scene': ...

    @property
    def name(self) -> str: ...

    @property
    def triangles(self) -> int: ...

    @property
    def size(self) -> Tuple[int, int]: ...


class Pass:
    image: Image
    number: int
    spp: int
    target_spp: int
    mean_spp: float
    spppp: int
    seconds: float
    error: float
    rmse: float
    eye_rays: int
    shadow_rays: int
    mrays_per_s: float
    converged: float
    done: bool
    samples: str
    progress: float
    seconds_left: float


def render(scene: Scene, *, reference: Reference = ..., size: Optional[Tuple[int, int]] = ...,
           spp: Optional[int] = ..., spppp: Union[None, int, Literal['auto']] = ...,
           sampling: Optional[Sampling] = ..., sampler: Optional[Sampler] = ..., aa: Optional[bool] = ...,
           adaptive: Optional[bool] = ..., seed: Optional[int] = ..., threads: Optional[int] = ...,
           target_error: Optional[float] = ..., time: Optional[float] = ..., ao_distance: Optional[float] = ...,
           shading: Optional[Shading] = ..., below_surface: Optional[BelowSurface] = ...) -> Image: ...


def passes(scene: Scene, *, reference: Reference = ..., size: Optional[Tuple[int, int]] = ...,
           spp: Optional[int] = ..., spppp: Union[None, int, Literal['auto']] = ...,
           sampling: Optional[Sampling] = ..., sampler: Optional[Sampler] = ..., aa: Optional[bool] = ...,
           adaptive: Optional[bool] = ..., seed: Optional[int] = ..., threads: Optional[int] = ...,
           target_error: Optional[float] = ..., time: Optional[float] = ..., ao_distance: Optional[float] = ...,
           shading: Optional[Shading] = ..., below_surface: Optional[BelowSurface] = ...) -> Iterator[Pass]: ...


def progressive(scene: Scene, jitter: bool = ..., total_spp: int = ..., spppp: int = ...,
                sampling_type: Sampling = ..., *, size: Optional[Tuple[int, int]] = ..., seed: Optional[int] = ...,
                threads: Optional[int] = ..., ao_distance: Optional[float] = ..., shading: Optional[Shading] = ...,
                below_surface: Optional[BelowSurface] = ..., reference: Reference = ...) -> Iterator[Pass]: ...


def exact(scene: Scene, *, size: Optional[Tuple[int, int]] = ..., aa: Optional[bool] = ...,
          spp: Optional[int] = ...) -> Image: ...


Hits = Tuple[npt.NDArray[np.float64], npt.NDArray[np.int32], npt.NDArray[np.float64]]


class RayMeshIntersector:
    def __init__(self, V: npt.ArrayLike, F: npt.ArrayLike) -> None: ...

    @property
    def V(self) -> npt.NDArray[np.float64]: ...

    @property
    def F(self) -> npt.NDArray[np.int32]: ...

    def intersect(self, origins: npt.ArrayLike, directions: npt.ArrayLike, *, tnear: float = ...,
                  threads: Optional[int] = ...) -> Hits: ...


def ray_mesh_intersect_precompute(V: npt.ArrayLike, F: npt.ArrayLike) -> RayMeshIntersector: ...


def ray_mesh_intersect(cam_pos: npt.ArrayLike, cam_dir: npt.ArrayLike, V: Optional[npt.ArrayLike],
                       F: Optional[npt.ArrayLike], use_embree: bool = ..., C: object = ..., W: object = ...,
                       CH: object = ..., tri_ind: object = ..., intersector: Optional[RayMeshIntersector] = ..., *,
                       tnear: float = ..., threads: Optional[int] = ...) -> Hits: ...


def view(scene: Scene, *, size: Optional[Tuple[int, int]] = ..., spp: Optional[int] = ...,
         spppp: Union[None, int, Literal['auto']] = ..., sampling: Optional[Sampling] = ...,
         sampler: Optional[Sampler] = ..., aa: Optional[bool] = ..., adaptive: Optional[bool] = ...,
         seed: Optional[int] = ..., threads: Optional[int] = ..., target_error: Optional[float] = ...,
         time: Optional[float] = ..., ao_distance: Optional[float] = ..., shading: Optional[Shading] = ...,
         below_surface: Optional[BelowSurface] = ...,
         pixel_size: Union[None, int, Literal['auto']] = ...) -> None: ...
