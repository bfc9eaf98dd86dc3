"""aoview for Python: Monte Carlo ambient occlusion with the renderer of the aoview program.

Scenes come from files (Scene.load) or numpy arrays (Scene.from_arrays); render() returns the
linear running average as a float32 array, bit for bit the PFM that the aoview command writes with
the same settings; passes() steps through the passes, progressive() through the course's;
exact() is aoview-exact's closed form; ray_mesh_intersect() traces a batch of rays against a
triangle mesh with Embree, as gpytoolbox.ray_mesh_intersect does (ray_mesh_intersect_precompute()
builds the mesh's BVH once); view() opens aoview's window. Settings are the command line's options
as keyword arguments (--target-error is target_error=...), with the same defaults, checks and
messages. See docs/python.md.
"""
import numbers
import os

import numpy as np

from . import _core

__version__ = _core.__version__

__all__ = ['Scene', 'Pass', 'render', 'passes', 'progressive', 'exact', 'ray_mesh_intersect',
           'ray_mesh_intersect_precompute', 'RayMeshIntersector', 'view', 'UNIFORM_SAMPLING', 'HEMISPHERE_SAMPLING',
           'COSINE_SAMPLING', 'TNEAR']

# Keyword arguments that are aoview options taking a value, and the two on/off switches; `size` is
# (width, height).
_VALUED = ('spp', 'spppp', 'sampling', 'sampler', 'seed', 'threads', 'target_error', 'time', 'ao_distance',
           'shading', 'below_surface')
_SCENE = ('crease_angle', 'ground', 'scene_budget', 'bvh')


def _argv(settings, allowed, where):
    """The command line that settings (keyword arguments) say; TypeError for an unknown name or a
    value of the wrong type. The values' ranges are the command line's to check."""
    argv = ['aoview']
    for key, value in settings.items():
        if key not in allowed:
            raise TypeError(f"{where}() got an unexpected keyword argument '{key}'")
        if value is None:
            continue
        option = '--' + key.replace('_', '-')
        if key in ('aa', 'adaptive', 'ground'):
            if not isinstance(value, (bool, np.bool_)):
                raise TypeError(f'{key}: expected True or False, got {value!r}')
            argv += [('--aa' if value else '--no-aa')] if key == 'aa' else [option, 'on' if value else 'off']
        elif key == 'size':
            if (not isinstance(value, (tuple, list)) or len(value) != 2 or
                    not all(isinstance(v, numbers.Integral) and not isinstance(v, bool) for v in value)):
                raise TypeError(f'size: expected (width, height), two integers, got {value!r}')
            argv += [option, f'{int(value[0])}x{int(value[1])}']
        elif isinstance(value, str):
            argv += [option, value]
        elif isinstance(value, numbers.Real) and not isinstance(value, bool):
            argv += [option, repr(int(value)) if isinstance(value, numbers.Integral) else repr(float(value))]
        else:
            raise TypeError(f'{key}: expected a number or a word, got {value!r}')
    return argv


def _real_array(a, name, columns, allow_empty=False, limit=None):
    """a copied into a C-contiguous native float32 array of shape (n, columns), n >= 1 (or 0 where
    allowed), every value finite and, with a limit, within it in magnitude (TypeError for a
    non-numeric dtype, ValueError naming the row for a shape, an empty array, a value that is not
    finite, or not one once single precision, or one past the limit). The copy is checked, not the
    caller's array, which another thread may change meanwhile."""
    a = np.asarray(a)
    if a.dtype.kind not in 'fiu':
        raise TypeError(f'{name}: expected an array of real numbers, got dtype {a.dtype}')
    if a.ndim != 2 or a.shape[1] != columns:
        raise ValueError(f'{name}: expected shape (n, {columns}), got {a.shape}')
    if a.shape[0] == 0 and not allow_empty:
        raise ValueError(f'{name}: empty')
    with np.errstate(over='ignore', invalid='ignore'):
        f = np.array(a, dtype=np.float32, order='C', copy=True)
    bound = np.finfo(np.float32).max if limit is None else limit
    if f.size and not (-bound <= f.min() and f.max() <= bound):   # NaN fails both
        finite = np.isfinite(f).all(axis=1)
        if not finite.all():
            row = int(np.argmin(finite))
            raise ValueError(f'{name}: row {row} is not finite in single precision: {a[row].tolist()}')
        row = int(np.argmax((np.abs(f) > bound).any(axis=1)))
        raise ValueError(f'{name}: row {row} holds {f[row].tolist()}, beyond the {bound:.4g} that '
                         'ray_mesh_intersect takes (docs/python.md)')
    return f


def _index_array(a, name, vertices):
    """a copied into a C-contiguous uint32 array of shape (m, 3), m >= 1, every index in [0,
    vertices); the copy is checked, as _real_array's."""
    a = np.asarray(a)
    if a.dtype.kind not in 'iu':
        raise TypeError(f'{name}: expected an array of integers, got dtype {a.dtype}')
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f'{name}: expected shape (m, 3), got {a.shape}')
    if a.shape[0] == 0:
        raise ValueError(f'{name}: empty')
    a = np.array(a, order='C', copy=True)
    bad = ((a < 0) | (a >= vertices)).any(axis=1)
    if bad.any():
        row = int(np.argmax(bad))
        raise ValueError(f'{name}: row {row} holds a vertex index out of range ({vertices} vertices): '
                         f'{a[row].tolist()}')
    return a.astype(np.uint32)


def _triple(value, name):
    """A number or three, as three floats."""
    v = np.asarray(value, dtype=np.float64) if not isinstance(value, str) else None
    if v is None or v.shape not in ((), (3,)):
        raise TypeError(f'{name}: expected a number or three, got {value!r}')
    return tuple(float(x) for x in np.broadcast_to(v, (3,)))


def _albedo(value, name):
    rho = _triple(value, name)
    if not all(0.0 <= x <= 1.0 for x in rho):
        raise ValueError(f"{name}: albedo must lie in [0,1], got {value!r}")
    return rho


class Scene:
    """A scene as the aoview program renders it: a camera, spheres, triangle meshes, albedos."""

    def __init__(self):
        raise TypeError('make a Scene with Scene.load(path) or Scene.from_arrays(vertices, faces)')

    @classmethod
    def _empty(cls):
        self = object.__new__(cls)
        self._scene = _core.Scene()
        return self

    @classmethod
    def load(cls, path, *, crease_angle=None, ground=None, scene_budget=None, bvh=None):
        """Any scene (.scene) or mesh file (.obj .ply .stl .gltf .glb) the aoview command opens, with
        its defaults (a bare mesh on a ground quad, a camera framed on it) and options."""
        argv = _argv(dict(crease_angle=crease_angle, ground=ground, scene_budget=scene_budget, bvh=bvh), _SCENE,
                     'load')
        path = os.fspath(path)
        if not isinstance(path, str):
            path = os.fsdecode(path)
        if not os.path.exists(path):
            raise FileNotFoundError(f'{path}: no such file')
        self = cls._empty()
        _core.load(self._scene, path, argv)
        return self

    @classmethod
    def from_arrays(cls, vertices, faces, *, normals=None, spheres=None, albedo=0.8, camera=None, ground=None,
                    crease_angle=None, scene_budget=None, bvh=None, name='arrays'):
        """A scene from arrays: vertices (n, 3) real, faces (m, 3) integer indices into them, normals
        (n, 3) or None (then made as for a mesh file without normals); spheres: (center, radius) or
        (center, radius, albedo) tuples; camera: a dict of eye, target, up (0, 1, 0), fov (40,
        vertical, degrees), or None (framed as for a bare mesh); ground: the ground quad under
        it. With the defaults it is exactly the scene the aoview command makes of an OBJ file
        holding the same arrays."""
        argv = _argv(dict(crease_angle=crease_angle, ground=ground, scene_budget=scene_budget, bvh=bvh), _SCENE,
                     'from_arrays')
        v = _real_array(vertices, 'vertices', 3)
        f = _index_array(faces, 'faces', len(v))
        n = None
        if normals is not None:
            n = np.asarray(normals)
            if n.dtype.kind not in 'fiu':
                raise TypeError(f'normals: expected an array of real numbers, got dtype {n.dtype}')
            if n.shape != v.shape:
                raise ValueError(f'normals: expected shape {v.shape} (one per vertex), got {n.shape}')
            with np.errstate(over='ignore', invalid='ignore'):
                n = np.array(n, dtype=np.float32, order='C', copy=True)
        rows = []
        for i, sphere in enumerate(spheres or ()):
            if not isinstance(sphere, (tuple, list)) or len(sphere) not in (2, 3):
                raise TypeError(f'spheres[{i}]: expected (center, radius) or (center, radius, albedo)')
            center = np.asarray(sphere[0], dtype=np.float64)
            if center.shape != (3,) or not np.isfinite(center).all():
                raise ValueError(f'spheres[{i}]: the centre must be three finite numbers, got {sphere[0]!r}')
            if not isinstance(sphere[1], numbers.Real) or not (0.0 < float(sphere[1]) < np.inf):
                raise ValueError(f"spheres[{i}]: 'radius' must be positive, got {sphere[1]!r}")
            rho = _albedo(sphere[2] if len(sphere) == 3 else 0.8, f'spheres[{i}]')
            rows.append([*center, float(sphere[1]), *rho])
        s = np.ascontiguousarray(np.array(rows, dtype=np.float32).reshape(-1, 7))
        cam = None
        if camera is not None:
            if not isinstance(camera, dict) or not {'eye', 'target'} <= camera.keys() or \
                    not camera.keys() <= {'eye', 'target', 'up', 'fov'}:
                raise TypeError("camera: expected a dict of 'eye', 'target' and optionally 'up', 'fov'")
            parts = [np.asarray(camera.get(k, d), dtype=np.float64).reshape(-1)
                     for k, d in (('eye', None), ('target', None), ('up', (0, 1, 0)), ('fov', 40))]
            if [len(p) for p in parts] != [3, 3, 3, 1] or not all(np.isfinite(p).all() for p in parts):
                raise ValueError('camera: eye, target and up must be three finite numbers, fov one')
            cam = np.ascontiguousarray(np.concatenate(parts), dtype=np.float32)
        self = cls._empty()
        _core.from_arrays(self._scene, str(name), v, len(v), f, len(f), n, _albedo(albedo, 'albedo'), s, len(s),
                          cam, argv)
        return self

    @property
    def name(self):
        return self._scene._facts()[0]

    @property
    def triangles(self):
        """Triangles placed (the ground's two included)."""
        return self._scene._facts()[1]

    @property
    def size(self):
        """The default image size (width, height): the scene's `image` line, else 640x480."""
        w, h = self._scene._facts()[3:]
        return (w, h) if w else (640, 480)

    def __repr__(self):
        name, triangles, spheres, _, _ = self._scene._facts()
        return f'<aoview.Scene {name!r}: {triangles} triangles, {spheres} spheres>'


class Pass:
    """One pass of a render: image (the running average after it), number (1 for the first), spp
    (the most samples a pixel has, as --stats' spp), mean_spp (the samples a pixel has on average),
    target_spp (the planned total: what spp reaches at the end unless the render stops sooner),
    spppp, seconds (render time so far), error (the estimated relative RMSE, nan until known), rmse
    (against the reference, nan without), eye_rays, shadow_rays, mrays_per_s, converged, done (the
    last pass); and how far the render is, as the window's title and the headless line say it:
    samples ("mean 173 spp, up to 256": with adaptive sampling spp reaches target_spp in the busiest
    tiles while the others still take samples), progress (the share done, 0 to 1: never less than
    before, 1 only on the last pass) and seconds_left (an estimate that errs long, nan until known,
    0 on the last pass)."""

    __slots__ = ('image', 'number', 'spp', 'target_spp', 'mean_spp', 'spppp', 'seconds', 'error', 'rmse',
                 'eye_rays', 'shadow_rays', 'mrays_per_s', 'converged', 'done', 'samples', 'progress',
                 'seconds_left')

    def __init__(self, image, info):
        self.image = image
        self.number = info['pass']
        for key in self.__slots__[2:]:
            setattr(self, key, info[key])

    def __repr__(self):
        return (f'<aoview.Pass {self.number}: {self.samples}, {self.seconds:.3f} s, error {self.error:.4g}, '
                f'rmse {self.rmse:.4g}>')


def _check_scene(scene):
    if not isinstance(scene, Scene):
        raise TypeError(f'expected an aoview.Scene, got {type(scene).__name__}')


def _reference(reference):
    """None, a path (str), or the image as a float32 (h, w, 3) C array."""
    if reference is None:
        return None
    if isinstance(reference, (str, bytes, os.PathLike)):
        return os.fsdecode(os.fspath(reference))
    r = np.asarray(reference)
    if r.dtype.kind not in 'fiu':
        raise TypeError(f'reference: expected an array of real numbers, got dtype {r.dtype}')
    if r.ndim == 2:
        r = np.repeat(r[:, :, None], 3, axis=2)
    if r.ndim != 3 or r.shape[2] != 3:
        raise ValueError(f'reference: expected shape (h, w) or (h, w, 3), got {r.shape}')
    r = np.ascontiguousarray(r, dtype=np.float32)
    if not np.isfinite(r).all():
        raise ValueError('reference: holds values that are not finite')
    return r


def _start(scene, settings, reference, every_pass, where):
    _check_scene(scene)
    argv = _argv(settings, _VALUED + ('size', 'aa', 'adaptive'), where)
    ref = _reference(reference)
    _core.parse(argv)
    w, h = settings.get('size') or scene.size
    if isinstance(ref, np.ndarray) and ref.shape != (h, w, 3):
        raise ValueError(f'reference: expected the image size {w}x{h}, got {ref.shape[1]}x{ref.shape[0]}')
    run = _core.start(scene._scene, argv, ref, every_pass)
    return (run, *run.size())


def _image(rgb, scene):
    """(h, w) where the scene is grey (its albedos and background), else (h, w, 3)."""
    return np.ascontiguousarray(rgb[:, :, 0]) if scene._scene._is_grey() else rgb


def render(scene, *, reference=None, **settings):
    """The linear running average once the render ends (spp reached, target_error, time): float32
    (h, w), row 0 at the top (h, w, 3 where the scene has colour), bit for bit the PFM that `aoview
    --headless -o X.pfm` writes with the same settings. Settings: size=(w, h), spp=256,
    spppp='auto', sampling='cosine', sampler='sobol', aa=True, adaptive=True, seed=1, threads=None
    (every core), target_error=None, time=None, ao_distance=None, shading='phong',
    below_surface='reflect'; reference: a path or an array, for the passes' RMSE."""
    run, w, h = _start(scene, settings, reference, False, 'render')
    out = np.empty((h, w, 3), np.float32)
    try:
        while True:
            info = run.step(out, False)
            if info is None or info['done']:
                break
    finally:
        run.close()
    return _image(out, scene)


def _iterate(run, w, h, scene):
    try:
        while True:
            out = np.empty((h, w, 3), np.float32)
            info = run.step(out, True)
            if info is None:
                return
            yield Pass(_image(out, scene), info)
            if info['done']:
                return
    finally:
        run.close()


def passes(scene, *, reference=None, **settings):
    """An iterator over the passes of a render with render()'s settings: a Pass for each (its
    image, number, spp, seconds, error, rmse, ...). The renderer waits for the loop between passes;
    leaving the loop (break, an exception, the iterator dropped) stops it."""
    run, w, h = _start(scene, settings, reference, True, 'passes')
    return _iterate(run, w, h, scene)


# The course's names for the sampling of directions (its sampling_type): aoview's --sampling words.
UNIFORM_SAMPLING = 'uniform'
HEMISPHERE_SAMPLING = 'hemisphere'
COSINE_SAMPLING = 'cosine'


def progressive(scene, jitter=True, total_spp=100, spppp=1, sampling_type=COSINE_SAMPLING, *, size=None, seed=None,
                threads=None, ao_distance=None, shading=None, below_surface=None, reference=None):
    """The course's progressive loop (progressive_render_display(jitter, total_spp, spppp,
    sampling_type)) as an iterator of Pass: exactly ceil(total_spp / spppp) passes of spppp samples
    per pixel each (the last may pass total_spp: 10 and 4 give 3 passes, 12 spp), each pass one eye
    ray per pixel (jittered over the pixel when jitter is true, else through its centre) with
    spppp directions drawn at random (the textbook estimator: sampler='random', adaptive=False).
    sampling_type: UNIFORM_SAMPLING ('uniform', over the sphere), HEMISPHERE_SAMPLING or
    COSINE_SAMPLING. The other settings are render()'s."""
    for name, value in (('total_spp', total_spp), ('spppp', spppp)):
        if isinstance(value, bool) or not isinstance(value, numbers.Integral):
            raise TypeError(f'{name}: expected a whole number, got {value!r}')
        if value < 1:
            raise ValueError(f'{name}: expected a whole number from 1, got {value!r}')
    if not isinstance(jitter, (bool, np.bool_)):
        raise TypeError(f'jitter: expected True or False, got {jitter!r}')
    count = -(-int(total_spp) // int(spppp))
    return passes(scene, reference=reference, aa=bool(jitter), spp=count * int(spppp), spppp=int(spppp),
                  sampling=sampling_type, sampler='random', adaptive=False, size=size, seed=seed, threads=threads,
                  ao_distance=ao_distance, shading=shading, below_surface=below_surface)


def exact(scene, *, size=None, aa=None, spp=None):
    """The exact AO image where the scene has a closed form (a plane with at most one sphere over
    it, or a closed box around the camera), as aoview-exact writes it: with AA each pixel the mean
    over a k x k sub-pixel grid, k = round(sqrt(spp)); ValueError where the scene has none."""
    _check_scene(scene)
    argv = _argv(dict(size=size, aa=aa, spp=spp), ('size', 'aa', 'spp'), 'exact')
    _core.parse(argv)
    w, h = size if size is not None else scene.size
    out = np.empty((h, w, 3), np.float32)
    _core.exact(scene._scene, argv, out)
    return _image(out, scene)


# What ray_mesh_intersect takes (tracer_arrays.h/.c derive both): every coordinate of the
# vertices, origins and directions within 2^60 = 1.153e18 in magnitude (Embree aborts the process on
# a ray past 1.844e18), a mesh from 2^-12 to 2^31 across (the range of aoview's scenes, within
# which Embree's triangle test neither overflows nor flushes to zero).
_RAY_LIMIT = _core.ARRAYS_LIMIT
_MESH_EXTENT = (_core.MIN_EXTENT, _core.MAX_EXTENT)

# gpytoolbox's Embree path reports no hit nearer than this along a ray (in the units of its direction).
TNEAR = 1e-4


class RayMeshIntersector:
    """A triangle mesh's Embree BVH, built once for many batches of rays: as gpytoolbox's
    ray_mesh_intersect_precompute(V, F). intersect(origins, directions) is
    ray_mesh_intersect(origins, directions, V, F) without the build; the object is passed as
    ray_mesh_intersect(..., intersector=it) too. V and F are the mesh's copies (float64, int32)."""

    def __init__(self, V, F):
        v = _real_array(V, 'vertices', 3, limit=_RAY_LIMIT)
        f = _index_array(F, 'faces', len(v))
        lo, hi = v.min(axis=0), v.max(axis=0)
        axis = int(np.argmax(hi.astype(np.float64) - lo))
        side = float(hi[axis]) - float(lo[axis])
        if not _MESH_EXTENT[0] <= side <= _MESH_EXTENT[1]:
            raise ValueError(f'vertices: the mesh is {side:.3g} across (rows {int(np.argmin(v[:, axis]))} and '
                             f'{int(np.argmax(v[:, axis]))}); ray_mesh_intersect takes meshes from '
                             f'{_MESH_EXTENT[0]:.3g} to {_MESH_EXTENT[1]:.3g} across (docs/python.md)')
        self._mesh = _core.Mesh(v, len(v), f, len(f))
        self._V = v.astype(np.float64)
        self._F = f.astype(np.int32)

    @property
    def V(self):
        """The vertices (n, 3) float64, as the mesh holds them (single precision)."""
        return self._V

    @property
    def F(self):
        """The faces (m, 3) int32."""
        return self._F

    def intersect(self, origins, directions, *, tnear=TNEAR, threads=None):
        """The closest hits of the rays origins[i] + t directions[i], t >= tnear, as
        ray_mesh_intersect returns them."""
        o = _real_array(origins, 'origins', 3, allow_empty=True, limit=_RAY_LIMIT)
        d = _real_array(directions, 'directions', 3, allow_empty=True, limit=_RAY_LIMIT)
        if len(o) != len(d):
            raise ValueError(f'origins and directions: {len(o)} and {len(d)} rays')
        if isinstance(tnear, bool) or not isinstance(tnear, numbers.Real) or not 0.0 <= float(tnear) < np.inf:
            raise ValueError(f'tnear: expected a finite number from 0, got {tnear!r}')
        chosen = _core.parse(_argv(dict(threads=threads), ('threads',), 'ray_mesh_intersect'))
        k = len(o)
        t = np.empty(k, np.float64)
        ids = np.empty(k, np.int32)
        barys = np.empty((k, 3), np.float64)
        if k:
            self._mesh.intersect(o, d, k, float(tnear), chosen or _core.cores(), t, ids, barys)
        return t, ids, barys


def ray_mesh_intersect_precompute(V, F):
    """gpytoolbox's ray_mesh_intersect_precompute: the mesh's BVH built once (a RayMeshIntersector),
    for its intersect(origins, directions) or ray_mesh_intersect(..., intersector=it)."""
    return RayMeshIntersector(V, F)


def ray_mesh_intersect(cam_pos, cam_dir, V, F, use_embree=True, C=None, W=None, CH=None, tri_ind=None,
                       intersector=None, *, tnear=TNEAR, threads=None):
    """Closest hits of the rays cam_pos[i] + t cam_dir[i], t >= tnear (1e-4, as gpytoolbox's Embree
    path), on the triangle mesh (V (n, 3), F (m, 3)), traced by Embree on every core (or
    `threads`), as gpytoolbox.ray_mesh_intersect returns them: hit_distances (k,) float64 (t in the
    units of the directions; inf on a miss), triangle_hit_ids (k,) int32 (-1 on a miss), barys (k,
    3) float64 (the weights of the triangle's three corners at the hit; zeros on a miss). Computed
    in single precision. gpytoolbox's signature: use_embree, C, W, CH and tri_ind are accepted and
    change nothing (aoview always traces with Embree; C, W, CH, tri_ind are gpytoolbox's own tree for
    its Python path); intersector, a RayMeshIntersector (ray_mesh_intersect_precompute), traces on
    its BVH, and V and F are then not read."""
    if intersector is None:
        intersector = RayMeshIntersector(V, F)
    elif not isinstance(intersector, RayMeshIntersector):
        raise TypeError(f'intersector: expected aoview.ray_mesh_intersect_precompute(V, F), got '
                        f'{type(intersector).__name__}')
    return intersector.intersect(cam_pos, cam_dir, tnear=tnear, threads=threads)


def view(scene, **settings):
    """aoview's window on the scene, with the command line's keys (docs/contract.md), render()'s
    settings and pixel_size; blocks until the window is closed (Esc or Q). RuntimeError where no
    window can be opened (no display) or where the module was built without the front ends."""
    _check_scene(scene)
    argv = _argv(settings, _VALUED + ('size', 'aa', 'adaptive', 'pixel_size'), 'view')
    _core.parse(argv)
    try:
        from . import _window
    except ImportError as error:
        raise RuntimeError(f'aoview: view() needs the window, built with the front ends ({error})') from None
    _window.view(scene._scene, argv)
