"""The course's base code on aoview: its progressive loop written as the base code writes it, with
only gpytoolbox's import swapped for aoview's, converges to aoview.exact's image; gpytoolbox's
signature (use_embree, C, W, CH, tri_ind, intersector) and its near-hit rule (tnear 1e-4) for rays
leaving surface points unmoved; the reusable intersector answers as the plain call; progressive()
renders exactly ceil(total_spp / spppp) passes of spppp, the CLI's image of that many samples bit for
bit. Run by `meson test --suite python`."""
import os
import sys

import numpy as np
import pytest

import aoview
from aoview import ray_mesh_intersect   # the base code's one changed line: from gpytoolbox import ...

ROOT = os.environ['AO_SOURCE_ROOT']
AOVIEW = os.environ['AO_BINARY']
SPHERE_ON_PLANE = os.path.join(ROOT, 'assets/scenes/sphere-on-plane.scene')
sys.path.insert(0, os.path.join(ROOT, 'tests', 'bench'))
from bench_python import camera_rays, read_obj  # noqa: E402 (the benchmark's camera and OBJ reader)
from test_aoview import cli  # noqa: E402 (aoview --headless's PFM)

BUNNY_OBJ = os.path.join(ROOT, 'assets/bunny.obj')
UNIFORM_SAMPLING, COSINE_SAMPLING = 0, 1


def icosphere(center, radius, levels):
    """A sphere of 20 4^levels triangles, wound outwards."""
    g = (1 + 5 ** 0.5) / 2
    v = [(-1, g, 0), (1, g, 0), (-1, -g, 0), (1, -g, 0), (0, -1, g), (0, 1, g), (0, -1, -g), (0, 1, -g),
         (g, 0, -1), (g, 0, 1), (-g, 0, -1), (-g, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
         (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
         (8, 6, 7), (9, 8, 1)]
    v = [np.array(p, float) / np.linalg.norm(p) for p in v]
    for _ in range(levels):
        middle, finer = {}, []

        def mid(a, b):
            if (b, a) in middle:
                return middle[(b, a)]
            p = v[a] + v[b]
            v.append(p / np.linalg.norm(p))
            middle[(a, b)] = len(v) - 1
            return len(v) - 1
        for a, b, c in f:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            finer += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = finer
    return np.array(center) + radius * np.array(v), np.array(f)


# ---------------------------------------------------------------- the base code's loop

class Mesh:
    """The base code's mesh: its vertices and faces, flat normals, an albedo; intersect() as the
    base code's Mesh.intersect calls gpytoolbox."""

    def __init__(self, v, f, brdf_params):
        self.v, self.f, self.brdf_params = v, f, brdf_params
        n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
        self.face_normals = n / np.linalg.norm(n, axis=1, keepdims=True)

    def intersect(self, Os, Ds):
        hit_distances, triangle_hit_ids, barys = ray_mesh_intersect(Os, Ds, self.v, self.f, use_embree=True)
        normals = self.face_normals[np.maximum(triangle_hit_ids, 0)]
        return hit_distances, normals


class Scene:
    """The base code's scene, reduced to what its progressive loop uses: a camera, one mesh (the
    ground quad and the sphere of sphere-on-plane.scene, tessellated), eye rays, a render of
    num_samples AO samples per pixel, the loop over passes."""

    def __init__(self, w, h, rng):
        self.w, self.h, self.rng = w, h, rng
        self.eye, self.target, self.up, self.fov = np.array([0, 1.6, 3.2]), np.array([0, 0.35, 0]), \
            np.array([0.0, 1.0, 0.0]), 40.0
        sv, sf = icosphere((0, 0.5, 0), 0.5, 4)
        ground = np.array([[-1e4, 0, -1e4], [-1e4, 0, 1e4], [1e4, 0, 1e4], [1e4, 0, -1e4]])
        self.mesh = Mesh(np.vstack([sv, ground]), np.vstack([sf, len(sv) + np.array([[0, 1, 2], [0, 2, 3]])]), 0.8)

    def generate_eye_rays(self, jitter=False):
        offsets = self.rng.random((self.h, self.w, 2)) if jitter else np.full((self.h, self.w, 2), 0.5)
        Ds = camera_rays(self.eye, self.target, self.up, self.fov, self.w, self.h, offsets).reshape(-1, 3)
        return np.broadcast_to(self.eye, Ds.shape), Ds

    def render(self, eye_rays, sampling_type=UNIFORM_SAMPLING, num_samples=1):
        Os, Ds = eye_rays
        t, n = self.mesh.intersect(Os, Ds)
        hit = np.isfinite(t)
        p = Os + np.where(hit, t, 0)[:, None] * Ds
        L = np.zeros(len(t))
        for _ in range(num_samples):
            z = 2 * self.rng.random(len(t)) - 1   # a uniform direction on the sphere
            r, phi = np.sqrt(1 - z * z), 2 * np.pi * self.rng.random(len(t))
            w = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)
            if sampling_type == COSINE_SAMPLING:   # the handout's trick: normal plus a sphere point
                w = n + w
                w /= np.linalg.norm(w, axis=1, keepdims=True)
                pdf = np.maximum(0, np.einsum('ij,ij->i', n, w)) / np.pi
            else:
                pdf = np.full(len(t), 1 / (4 * np.pi))
            # Shadow rays leave the hit points unmoved, as the base code's: gpytoolbox's near-hit
            # rule keeps them off their own triangle.
            ts, _ = self.mesh.intersect(p, w)
            cos = np.maximum(0, np.einsum('ij,ij->i', n, w))
            with np.errstate(divide='ignore', invalid='ignore'):
                L += np.where(pdf > 0, np.isinf(ts) * cos / pdf, 0)
        return np.where(hit, self.mesh.brdf_params / (np.pi * num_samples) * L, 1.0).reshape(self.h, self.w)

    def progressive_render_display(self, jitter=False, total_spp=20, spppp=1, sampling_type=UNIFORM_SAMPLING):
        image = np.zeros((self.h, self.w))
        passes = int(np.ceil(total_spp / spppp))
        for i in range(passes):
            image = (i * image + self.render(self.generate_eye_rays(jitter), sampling_type, spppp)) / (i + 1)
        return image, passes


@pytest.mark.parametrize('sampling_type', [UNIFORM_SAMPLING, COSINE_SAMPLING])
def test_the_base_code_loop_converges_to_the_exact_image(sampling_type):
    """The loop's image against aoview.exact on the same camera, 64 samples a pixel. Per pixel the
    uniform estimator 4 rho V max(0, cos) has a standard deviation of at most 4 rho sqrt(1/6) =
    1.31 a sample (0.16 after 64), the cosine one rho V at most rho / 2 = 0.4 (0.05): the image's
    RMSE against the exact one stays below those, and the mean difference over 3072 pixels within
    5 standard errors (0.015, 0.0045) plus the tessellation's bias (a 5120-triangle sphere: under
    0.003). Self-hits (no tnear) would darken it by tenths."""
    w, h = 64, 48
    image, passes = Scene(w, h, np.random.default_rng(3)).progressive_render_display(True, 60, 8, sampling_type)
    assert passes == 8   # ceil(60 / 8): the last pass passes total_spp, as the base code's
    exact = aoview.exact(aoview.Scene.load(SPHERE_ON_PLANE), size=(w, h))
    noise = 0.16 if sampling_type == UNIFORM_SAMPLING else 0.05
    rmse = np.sqrt(np.mean((image - exact) ** 2))
    assert rmse < noise, rmse
    assert abs(np.mean(image - exact)) < 5 * noise / np.sqrt(w * h) + 0.003


# ---------------------------------------------------------------- gpytoolbox's signature and rules

def surface_rays(n, seed):
    """n rays leaving points of the bunny's surface unmoved, in directions uniform over the sphere,
    and the bunny: the second half of the base code's render."""
    v, f = read_obj(BUNNY_OBJ)
    rng = np.random.default_rng(seed)
    lo, hi = v.min(axis=0), v.max(axis=0)
    c = (lo + hi) / 2
    u = rng.normal(size=(n, 3))
    eyes = c + 2 * np.linalg.norm(hi - lo) * u / np.linalg.norm(u, axis=1, keepdims=True)
    t, ids, barys = ray_mesh_intersect(eyes, rng.uniform(lo, hi, (n, 3)) - eyes, v, f, use_embree=True)
    hit = ids >= 0
    p = np.einsum('ij,ijk->ik', barys[hit], v[f[ids[hit]]])
    u = rng.normal(size=p.shape)
    return p, u / np.linalg.norm(u, axis=1, keepdims=True), v, f


def test_no_hit_nearer_than_tnear_from_surface_points():
    """10,000 rays leaving surface points with no offset: with gpytoolbox's tnear (the default) no
    hit is nearer than 1e-4; with tnear=0 many are their own triangle at t = 0, which is why."""
    p, d, v, f = surface_rays(25000, 5)
    p, d = p[:10000], d[:10000]
    assert len(p) == 10000
    t, ids, _ = ray_mesh_intersect(p, d, v, f, use_embree=True)
    assert (t[ids >= 0] >= 1e-4).all()
    occluded = (ids >= 0).mean()
    t0, ids0, _ = ray_mesh_intersect(p, d, v, f, tnear=0.0)
    selfhits = ((ids0 >= 0) & (t0 < 1e-4)).mean()
    print(f'occluded {occluded:.3f}; with tnear 0: {(ids0 >= 0).mean():.3f}, {selfhits:.3f} nearer than 1e-4')
    assert selfhits > 0.1 and (ids0 >= 0).mean() > occluded + 0.1
    # A larger tnear keeps the hits beyond it.
    t2, ids2, _ = ray_mesh_intersect(p, d, v, f, tnear=0.01)
    assert (t2[ids2 >= 0] >= 0.01).all() and (ids2 >= 0).mean() < occluded


def test_gpytoolbox_signature():
    v, f = read_obj(BUNNY_OBJ)
    rng = np.random.default_rng(2)
    o = rng.uniform(-0.2, 0.2, (300, 3)) + (0, 0.1, 0.5)
    d = np.tile([0.0, 0.0, -1.0], (300, 1))
    base = ray_mesh_intersect(o, d, v, f)
    assert [a.dtype for a in base] == [np.float64, np.int32, np.float64]
    assert [a.shape for a in base] == [(300,), (300,), (300, 3)]
    assert 0 < (base[1] >= 0).sum() < 300
    calls = [
        ray_mesh_intersect(o, d, v, f, True),
        ray_mesh_intersect(o, d, v, f, True, None, None, None, None, None),
        ray_mesh_intersect(cam_pos=o, cam_dir=d, V=v, F=f, use_embree=True, C=None, W=None, CH=None, tri_ind=None,
                           intersector=None),
        ray_mesh_intersect(o, d, v, f, use_embree=False, C=np.zeros((1, 3)), W=np.ones((1, 3)), CH=[[-1, -1]],
                           tri_ind=[0]),
    ]
    for got in calls:
        assert all(np.array_equal(a, b) for a, b in zip(got, base))
    with pytest.raises(TypeError, match='intersector'):
        ray_mesh_intersect(o, d, v, f, intersector=object())
    with pytest.raises(ValueError, match='tnear'):
        ray_mesh_intersect(o, d, v, f, tnear=-1.0)


def test_the_precomputed_intersector_answers_as_the_plain_call():
    v, f = read_obj(BUNNY_OBJ)
    rmi = aoview.ray_mesh_intersect_precompute(v, f)
    assert rmi.V.dtype == np.float64 and rmi.F.dtype == np.int32 and np.array_equal(rmi.F, f)
    rng = np.random.default_rng(9)
    for n in (1, 1000, 20000):
        o = rng.uniform(-0.3, 0.3, (n, 3))
        d = rng.normal(size=(n, 3))
        plain = ray_mesh_intersect(o, d, v, f)
        for got in (rmi.intersect(o, d), ray_mesh_intersect(o, d, v, f, intersector=rmi),
                    ray_mesh_intersect(o, d, None, None, intersector=rmi)):   # V, F not read, as gpytoolbox
            assert all(np.array_equal(a, b) for a, b in zip(got, plain))
    empty = rmi.intersect(np.zeros((0, 3)), np.zeros((0, 3)))
    assert [a.shape for a in empty] == [(0,), (0,), (0, 3)]


# ---------------------------------------------------------------- progressive(): the course's passes

@pytest.mark.parametrize('total_spp,spppp', [(10, 4), (12, 4), (5, 1)])
def test_progressive_renders_the_course_passes(tmp_path, total_spp, spppp):
    scene = aoview.Scene.load(SPHERE_ON_PLANE)
    got = list(aoview.progressive(scene, True, total_spp, spppp, aoview.UNIFORM_SAMPLING, size=(48, 36)))
    count = -(-total_spp // spppp)
    assert len(got) == count and got[-1].done
    assert [p.spp for p in got] == [spppp * (k + 1) for k in range(count)]
    assert all(p.mean_spp == p.spp and p.spppp == spppp and p.target_spp == count * spppp for p in got)
    expected, _ = cli(tmp_path, SPHERE_ON_PLANE, '--size', '48x36', '--spp', str(count * spppp), '--spppp',
                      str(spppp), '--sampler', 'random', '--adaptive', 'off', '--sampling', 'uniform')
    assert np.array_equal(np.repeat(got[-1].image[:, :, None], 3, axis=2), expected)
    # Without jitter, every eye ray through its pixel's centre: as --no-aa.
    flat = list(aoview.progressive(scene, False, total_spp, spppp, 'cosine', size=(48, 36)))
    expected, _ = cli(tmp_path, SPHERE_ON_PLANE, '--size', '48x36', '--spp', str(count * spppp), '--spppp',
                      str(spppp), '--sampler', 'random', '--adaptive', 'off', '--no-aa')
    assert np.array_equal(np.repeat(flat[-1].image[:, :, None], 3, axis=2), expected)


def test_progressive_refuses_what_the_course_cannot_mean():
    scene = aoview.Scene.load(SPHERE_ON_PLANE)
    for kwargs, kind in [(dict(total_spp=0), ValueError), (dict(spppp=2.5), TypeError),
                         (dict(jitter='yes'), TypeError), (dict(sampling_type='gaussian'), ValueError)]:
        with pytest.raises(kind):
            list(aoview.progressive(scene, **kwargs))


def test_pass_says_spp_x_of_y_while_adaptive_sampling_runs():
    """With the adaptive defaults spp stops at the target in the busiest tiles while mean_spp goes
    on rising to it: the display's X is mean_spp, its Y target_spp."""
    got = list(aoview.passes(aoview.Scene.load(SPHERE_ON_PLANE), size=(80, 60), spp=100))
    assert all(p.target_spp == 100 for p in got)
    means = [p.mean_spp for p in got]
    assert means == sorted(means) and means[-1] <= 100
    frozen = [p for p in got if p.spp == 100]
    assert len(frozen) >= 2 and frozen[0].mean_spp < frozen[-1].mean_spp
    # ... and Pass says it as the window's title and the headless line do: "mean X spp, up to Y",
    # X rounded down; the share done never falls and reaches 1 only on the last pass; the time
    # left is 0 there and a number of seconds before it once a pass has been timed.
    assert all(p.samples == f'mean {int(p.mean_spp)} spp, up to 100' for p in got)
    shares = [p.progress for p in got]
    assert shares == sorted(shares) and shares[-1] == 1 and all(s < 1 for s in shares[:-1])
    assert got[-1].seconds_left == 0 and all(p.seconds_left > 0 for p in got[1:-1])
