/* Instancing (scene_place.c, tracer.c, ao.c): a mesh placed many times is loaded and built once and
 * traced through Embree's instances, and shades as the same scene flattened does. Each test
 * prints its measured figures; bounds are derived next to each check; seeds are fixed. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "ao.h"
#include "load.h"
#include "mesh.h"
#include "render.h"
#include "render_image.h"
#include "scene.h"
#include "scene_load.h"
#include "tracer.h"

/* ------------------------------------------------------------------ files */

static char dir[64];

/* The path of name in the test's directory (a static buffer per call site is enough here). */
static const char *in_dir(const char *name, char *out, size_t size)
{
    snprintf(out, size, "%s/%s", dir, name);
    return out;
}

static void write_text(const char *name, const char *text)
{
    char path[128];
    FILE *f = fopen(in_dir(name, path, sizeof path), "w");
    assert_non_null(f);
    assert_true(fputs(text, f) >= 0);
    assert_int_equal(fclose(f), 0);
}

/* A growing byte buffer. */
struct bytes {
    unsigned char *data;
    size_t size;
};

static void put(struct bytes *b, const void *p, size_t n)
{
    b->data = realloc(b->data, b->size + n + 4);
    assert_non_null(b->data);
    memcpy(b->data + b->size, p, n);
    b->size += n;
    while (b->size % 4)
        b->data[b->size++] = 0;
}

/* A growing text (doubling, so that appends stay linear). */
struct text {
    char *s;
    size_t size, capacity;
};

static void say(struct text *t, const char *format, ...)
{
    va_list ap;
    va_start(ap, format);
    int n = vsnprintf(NULL, 0, format, ap);
    va_end(ap);
    if (t->size + (size_t)n + 1 > t->capacity) {
        t->capacity = 2 * (t->size + (size_t)n + 1);
        t->s = realloc(t->s, t->capacity);
    }
    assert_non_null(t->s);
    va_start(ap, format);
    vsnprintf(t->s + t->size, (size_t)n + 1, format, ap);
    va_end(ap);
    t->size += (size_t)n;
}

static void base64(const unsigned char *p, size_t n, struct text *t)
{
    static const char digits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    char quad[5] = {0};
    for (size_t i = 0; i < n; i += 3) {
        uint32_t bits = (uint32_t)p[i] << 16 | (i + 1 < n ? (uint32_t)p[i + 1] << 8 : 0) | (i + 2 < n ? p[i + 2] : 0);
        for (int k = 0; k < 4; k++)
            quad[k] = k <= (int)(n - i) ? digits[bits >> (18 - 6 * k) & 63] : '=';
        say(t, "%s", quad);
    }
}

/* Writes a glTF file of the meshes (float positions, normals when the mesh has them, uint32 indices)
 * whose "nodes" array is the JSON text nodes, into the test's directory. */
static void write_gltf(const char *name, const struct ao_mesh *meshes, int count, const char *nodes)
{
    struct bytes bin = {0};
    struct text json = {0}, accessors = {0}, views = {0}, list = {0};
    int accessor = 0;
    for (int m = 0; m < count; m++) {
        const struct ao_mesh *mesh = &meshes[m];
        float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (size_t v = 0; v < mesh->vertex_count; v++)
            for (int k = 0; k < 3; k++) {
                float x = (&mesh->positions[v].x)[k];
                lo[k] = fminf(lo[k], x), hi[k] = fmaxf(hi[k], x);
            }
        size_t at = bin.size;
        put(&bin, mesh->positions, mesh->vertex_count * sizeof *mesh->positions);
        say(&views, "%s{\"buffer\": 0, \"byteOffset\": %zu, \"byteLength\": %zu}", accessor ? ", " : "", at,
            mesh->vertex_count * sizeof *mesh->positions);
        say(&accessors, "%s{\"bufferView\": %d, \"componentType\": 5126, \"count\": %zu, \"type\": \"VEC3\", "
                        "\"min\": [%.9g, %.9g, %.9g], \"max\": [%.9g, %.9g, %.9g]}",
            accessor ? ", " : "", accessor, mesh->vertex_count, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
        int position = accessor++, normal = -1;
        if (mesh->normals) {
            at = bin.size;
            put(&bin, mesh->normals, mesh->vertex_count * sizeof *mesh->normals);
            say(&views, ", {\"buffer\": 0, \"byteOffset\": %zu, \"byteLength\": %zu}", at,
                mesh->vertex_count * sizeof *mesh->normals);
            say(&accessors, ", {\"bufferView\": %d, \"componentType\": 5126, \"count\": %zu, \"type\": \"VEC3\"}",
                accessor, mesh->vertex_count);
            normal = accessor++;
        }
        at = bin.size;
        put(&bin, mesh->indices, 3 * mesh->triangle_count * sizeof *mesh->indices);
        say(&views, ", {\"buffer\": 0, \"byteOffset\": %zu, \"byteLength\": %zu}", at,
            3 * mesh->triangle_count * sizeof *mesh->indices);
        say(&accessors, ", {\"bufferView\": %d, \"componentType\": 5125, \"count\": %zu, \"type\": \"SCALAR\"}",
            accessor, 3 * mesh->triangle_count);
        int indices = accessor++;
        if (normal >= 0)
            say(&list, "%s{\"primitives\": [{\"attributes\": {\"POSITION\": %d, \"NORMAL\": %d}, \"indices\": %d}]}",
                m ? ", " : "", position, normal, indices);
        else
            say(&list, "%s{\"primitives\": [{\"attributes\": {\"POSITION\": %d}, \"indices\": %d}]}", m ? ", " : "",
                position, indices);
    }
    say(&json, "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": %s,\n \"meshes\": [%s],\n \"accessors\": [%s],\n"
               " \"bufferViews\": [%s],\n \"buffers\": [{\"byteLength\": %zu, \"uri\": \"data:application/octet-stream;base64,",
        nodes, list.s, accessors.s, views.s, bin.size);
    base64(bin.data, bin.size, &json);
    say(&json, "\"}]}\n");
    write_text(name, json.s);
    free(bin.data), free(json.s), free(accessors.s), free(views.s), free(list.s);
}

/* ------------------------------------------------------------------ meshes */

/* A closed polyhedron inscribed in the unit sphere about the origin: `rings` rings of `segments`
 * vertices between two poles, with unit radial normals when `normals`. */
static void sphere_mesh(struct ao_mesh *m, int rings, int segments, bool normals)
{
    const double pi = 3.14159265358979323846;
    *m = (struct ao_mesh){.vertex_count = (size_t)rings * (size_t)segments + 2,
                          .triangle_count = 2 * (size_t)segments * (size_t)rings};
    m->positions = malloc(m->vertex_count * sizeof *m->positions);
    m->normals = normals ? malloc(m->vertex_count * sizeof *m->normals) : NULL;
    m->indices = malloc(3 * m->triangle_count * sizeof *m->indices);
    assert_true(m->positions && m->indices && (m->normals || !normals));
    m->positions[0] = ao_vec3_make(0, -1, 0);
    m->positions[1] = ao_vec3_make(0, 1, 0);
    for (int j = 0; j < rings; j++)
        for (int i = 0; i < segments; i++) {
            double theta = pi * (j + 1) / (rings + 1), phi = 2 * pi * i / segments;
            m->positions[2 + j * segments + i] =
                ao_vec3_make((float)(sin(theta) * cos(phi)), (float)-cos(theta), (float)(sin(theta) * sin(phi)));
        }
    uint32_t *t = m->indices;
    for (int i = 0; i < segments; i++) {
        uint32_t a = (uint32_t)(2 + i), b = (uint32_t)(2 + (i + 1) % segments);
        *t++ = 0, *t++ = a, *t++ = b;   /* the bottom cap, facing out (down) */
        uint32_t c = (uint32_t)(2 + (rings - 1) * segments + i), d = (uint32_t)(2 + (rings - 1) * segments + (i + 1) % segments);
        *t++ = 1, *t++ = d, *t++ = c;   /* the top cap */
    }
    for (int j = 0; j + 1 < rings; j++)
        for (int i = 0; i < segments; i++) {
            uint32_t a = (uint32_t)(2 + j * segments + i), b = (uint32_t)(2 + j * segments + (i + 1) % segments);
            uint32_t c = a + (uint32_t)segments, d = b + (uint32_t)segments;
            *t++ = a, *t++ = c, *t++ = b, *t++ = b, *t++ = c, *t++ = d;
        }
    m->triangle_count = (size_t)(t - m->indices) / 3;
    for (size_t v = 0; normals && v < m->vertex_count; v++)
        m->normals[v] = ao_vec3_normalize(m->positions[v]);
}

/* The bunny as shipped (assets/bunny.obj), about 10 units across, normals computed. */
static void bunny_mesh(struct ao_mesh *m)
{
    const char *root = getenv("AO_SOURCE_ROOT");
    char path[4096];
    assert_non_null(root);
    snprintf(path, sizeof path, "%s/assets/bunny.obj", root);
    assert_true(ao_load_mesh(m, path, NULL));
}

/* ------------------------------------------------------------------ scenes */

/* A scene and its tracer. */
struct fixture {
    struct ao_scene scene;
    struct ao_tracer *tracer;
    struct ao_tracer *upgrade;   /* the tracer when it is progressive (render.h's config.upgrade) */
};

/* Loads name with that BVH and builds its Embree tracer. */
static void setup_bvh(struct fixture *f, const char *name, enum ao_instancing instancing, bool ground, enum ao_bvh bvh)
{
    char path[128];
    struct ao_scene_options options = {.budget = AO_BUDGET_LEAST, .no_ground = !ground, .instancing = instancing,
                                       .bvh = bvh};
    assert_true(ao_scene_load(&f->scene, in_dir(name, path, sizeof path), &options));
    f->tracer = ao_tracer_create_with(&f->scene, AO_BACKEND_EMBREE);
    f->upgrade = NULL;
    assert_non_null(f->tracer);
}

static void setup(struct fixture *f, const char *name, enum ao_instancing instancing, bool ground)
{
    setup_bvh(f, name, instancing, ground, AO_BVH_AUTO);
}

static void teardown(struct fixture *f)
{
    ao_tracer_destroy(f->tracer);
    ao_scene_finish(&f->scene);
}

/* Renders the fixture's scene (random numbers, two threads, seed 9) and returns a malloc'd copy of
 * the final linear image. */
static float *render(const struct fixture *f, int width, int height, uint32_t spp, enum ao_output output, bool aa)
{
    struct ao_render_config config = {.scene = &f->scene, .tracer = f->tracer, .upgrade = f->upgrade, .threads = 2,
                                      .seed = 9, .target_spp = spp, .ao_distance = f->scene.ao_distance,
                                      .sequence = AO_SEQUENCE_RANDOM};
    struct ao_settings settings = {.width = width, .height = height, .sampling = AO_SAMPLING_COSINE, .aa = aa,
                                   .spppp = spp < 16 ? spp : 16, .camera = f->scene.camera, .output = output};
    float *copy = render_image(&config, &settings);
    return copy;
}

/* The hit of one eye ray from `from` along the unit d, and the surface there (when hit). */
static bool shade(const struct fixture *f, struct ao_vec3 from, struct ao_vec3 d, struct ao_hit *hit,
                  struct ao_surface *s)
{
    struct ao_packet eye = {.org_x = {from.x}, .org_y = {from.y}, .org_z = {from.z}, .dir_x = {d.x},
                            .dir_y = {d.y}, .dir_z = {d.z}, .tfar = {INFINITY}, .count = 1};
    ao_tracer_intersect(f->tracer, &eye, hit);
    if (hit->t == INFINITY)
        return false;
    ao_surface_from_hit(&f->scene, AO_SHADING_PHONG, from, d, hit, s);
    return true;
}

static float distance(struct ao_vec3 a, struct ao_vec3 b)
{
    return ao_vec3_length(ao_vec3_sub(a, b));
}

/* ------------------------------------------------------------------ tests */

/* Four placements of the bunny by glTF nodes: the identity, a translation, a rotation with a
 * non-uniform scale, a mirror (scale -1 in x) with a rotation; 1.5 units of AO distance, which no
 * ray from one copy can cross to another (they lie 14 or more apart). */
static const char BUNNY_NODES[] =
    "[{\"mesh\": 0}, {\"mesh\": 0, \"translation\": [14, 0, 0]},"
    " {\"mesh\": 0, \"translation\": [-15, 1, 0], \"rotation\": [0, 0.3420201, 0, 0.9396926], \"scale\": [1.5, 0.7, 1.2]},"
    " {\"mesh\": 0, \"translation\": [0, 0, -16], \"rotation\": [0.2588190, 0, 0, 0.9659258], \"scale\": [-1, 1, 1]}]";

static void write_bunnies(void)
{
    struct ao_mesh bunny;
    bunny_mesh(&bunny);
    write_gltf("bunnies.gltf", &bunny, 1, BUNNY_NODES);
    ao_mesh_finish(&bunny);
    write_text("bunnies.scene", "camera eye 2 22 30 target 0 0 -4 fov 50\nbackground 1\nao-distance 1.5\nmesh bunnies.gltf\n");
}

/* AUTO's rule (scene.h): four bunnies, 20k triangles placed, are below AO_SCENE_FLATTEN_TRIANGLES
 * and flattened, as copies in one BVH (the 100,000 spheres below are above it and instanced). */
static void test_auto_flattens_a_mesh_placed_a_few_times(void **state)
{
    (void)state;
    write_bunnies();
    struct fixture f;
    setup(&f, "bunnies.scene", AO_INSTANCING_AUTO, false);
    assert_true(f.scene.triangle_count <= AO_SCENE_FLATTEN_TRIANGLES);
    assert_int_equal(f.scene.mesh_count, 4);
    assert_int_equal(f.scene.instance_count, 4);
    for (int i = 0; i < 4; i++)
        assert_true(f.scene.instances[i].flat);
    struct ao_tracer_stats stats;
    ao_tracer_describe(f.tracer, &stats);
    assert_int_equal(stats.bvhs, 1);
    assert_int_equal(stats.instances, 0);
    teardown(&f);
}

/* A placement that shrinks a mesh to 1e-42 (a subnormal scale) a million units out: its inverse is
 * about 1e42, so mapping a ray origin into the local frame and back could move it by more than a
 * float holds (slack[1] would be infinite). Instancing every mesh file's mesh still loads the
 * scene, with that mesh flattened (both placements), and every instance's slack finite. */
static void test_a_map_too_small_to_invert_is_flattened(void **state)
{
    (void)state;
    write_text("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n");
    write_text("subnormal.scene", "camera eye 0 1 4 target 0 0 0\nmesh tri.obj scale 1e-42 translate 1e6 0 0\n"
                                  "mesh tri.obj scale 0.1\n");
    struct fixture f;
    setup(&f, "subnormal.scene", AO_INSTANCING_ALWAYS, false);
    assert_int_equal(f.scene.instance_count, 2);
    for (size_t i = 0; i < f.scene.instance_count; i++) {
        assert_true(f.scene.instances[i].flat);
        assert_true(isfinite(f.scene.instances[i].slack[0]) && isfinite(f.scene.instances[i].slack[1]));
    }
    teardown(&f);
}

/* One mesh under four nodes loads once and builds one BVH: the scene holds 1 mesh and 4 instances,
 * the tracer 2 BVHs (the top level, the bunny's) and 4 Embree instances, and Embree holds less than
 * the same scene flattened (4 copies in one BVH) by more than 2 copies' worth. */
static void test_one_mesh_under_many_nodes_is_built_once(void **state)
{
    (void)state;
    write_bunnies();
    struct fixture inst, flat;
    setup(&inst, "bunnies.scene", AO_INSTANCING_ALWAYS, false);
    setup(&flat, "bunnies.scene", AO_INSTANCING_NEVER, false);
    assert_int_equal(inst.scene.mesh_count, 1);
    assert_int_equal(inst.scene.instance_count, 4);
    assert_int_equal(flat.scene.mesh_count, 4);
    assert_int_equal(inst.scene.triangle_count, flat.scene.triangle_count);
    for (int i = 0; i < 4; i++)
        assert_false(inst.scene.instances[i].flat);
    struct ao_tracer_stats a, b;
    ao_tracer_describe(inst.tracer, &a);
    ao_tracer_describe(flat.tracer, &b);
    print_message("4 bunnies instanced: %zu BVHs, %zu instances, %zu flat geometries, Embree %.2f MB (peak %.2f); "
                  "flattened: %zu BVHs, %zu flat geometries, Embree %.2f MB (peak %.2f)\n",
                  a.bvhs, a.instances, a.triangle_geometries, a.embree_bytes / 1e6, a.embree_peak_bytes / 1e6, b.bvhs,
                  b.triangle_geometries, b.embree_bytes / 1e6, b.embree_peak_bytes / 1e6);
    assert_int_equal(a.bvhs, 2);
    assert_int_equal(a.instances, 4);
    assert_int_equal(a.triangle_geometries, 0);
    assert_int_equal(b.bvhs, 1);
    assert_int_equal(b.instances, 0);
    assert_int_equal(b.triangle_geometries, 4);
    assert_true(a.embree_bytes < b.embree_bytes / 2);
    teardown(&inst);
    teardown(&flat);
}

/* Eye rays through every pixel centre of a 160x120 view, traced in the instanced and in the
 * flattened scene. Where both meet the same triangle of the same placement (the flattened copy of a
 * mirroring placement has corners 1 and 2 swapped, and so its barycentrics):
 * - on the identity placement the arithmetic is the same: t, u, v, the point and the geometric
 *   normal are equal bit for bit;
 * - elsewhere the instance's point is its own-frame point mapped, the flattened one computed from
 *   mapped vertices: they differ by at most the sum of the two error bounds (ao_triangle_point's,
 *   gamma2 |p| + gamma8 (|e1| + |e2|) each, taken here as 8 gamma8 |p| plus the edges); the shading
 *   normals by where the two points lie on the triangle (their barycentrics differ by du, dv, which
 *   move the interpolated normal by du (n1 - n0) + dv (n2 - n0), over the length of the
 *   interpolated normal, at least 0.5 on these meshes) and by float rounding: the normal matrix
 *   narrowed (2^-24 of each entry), a matrix product (gamma5), normalization (gamma3) per vertex,
 *   interpolation and normalization again: below gamma32 = 1.9e-6 over that length.
 *   The geometric normals differ by the flattened triangle's own: its edges are differences of
 *   vertices rounded at their distance P from the local origin, each coordinate off by 2^-24 P
 *   twice and once more by the subtraction, so e1 x e2 is off by gamma4 2 P (|e1| + |e2|) (to first
 *   order), its direction by that over |e1 x e2|; gamma32 more for the instance's.
 * Where they meet different triangles the ray passes within rounding of an edge: one of the hits
 * has a barycentric coordinate within 1e-4 of 0 (the ray's origin in the mesh's frame is rounded
 * to 2^-24 of 30 units, 2e-6, over triangles 0.1 units across). */
static void test_instances_shade_as_flattened(void **state)
{
    (void)state;
    write_bunnies();
    struct fixture inst, flat;
    setup(&inst, "bunnies.scene", AO_INSTANCING_ALWAYS, false);
    setup(&flat, "bunnies.scene", AO_INSTANCING_NEVER, false);
    enum { W = 160, H = 120 };
    struct ao_view view;
    assert_true(ao_camera_view(&inst.scene.camera, W, H, &view));
    int same[4] = {0}, edges = 0, misses = 0;
    float worst_normal = 0.0f, worst_point = 0.0f, worst_ng = 0.0f;
    for (int j = 0; j < H; j++)
        for (int i = 0; i < W; i++) {
            struct ao_vec3 d = ao_camera_ray(&view, (float)i + 0.5f, (float)j + 0.5f);
            struct ao_hit a, b;
            struct ao_surface sa, sb;
            bool ha = shade(&inst, view.eye, d, &a, &sa), hb = shade(&flat, view.eye, d, &b, &sb);
            if (!ha && !hb) {
                misses++;
                continue;
            }
            bool mirror = ha && a.instance == 3;
            float bu = mirror ? b.v : b.u, bv = mirror ? b.u : b.v;
            if (ha && hb && a.instance == b.instance && a.prim == b.prim) {
                same[a.instance]++;
                if (a.instance == 0) {
                    assert_true(a.t == b.t && a.u == b.u && a.v == b.v);
                    assert_memory_equal(&sa.position, &sb.position, sizeof sa.position);
                    assert_memory_equal(&sa.ng, &sb.ng, sizeof sa.ng);
                }
                const struct ao_mesh *m = &flat.scene.meshes[flat.scene.instances[b.instance].mesh];
                const uint32_t *t = &m->indices[3 * b.prim];
                struct ao_vec3 p0 = m->positions[t[0]], e1 = ao_vec3_sub(m->positions[t[1]], p0);
                struct ao_vec3 e2 = ao_vec3_sub(m->positions[t[2]], p0);
                float bound = 8 * ao_gamma(8) * (ao_vec3_max_abs(sb.position) + ao_vec3_length(e1) + ao_vec3_length(e2));
                float far = ao_vec3_max_abs(sb.position) + ao_vec3_length(e1) + ao_vec3_length(e2);
                float ng_bound = ao_gamma(4) * 2 * far * (ao_vec3_length(e1) + ao_vec3_length(e2)) /
                                     ao_vec3_length(ao_vec3_cross(e1, e2)) + ao_gamma(32);
                /* Barycentrics of both points on the flattened triangle (normal equations, double). */
                double bary[2][2];
                for (int k = 0; k < 2; k++) {
                    struct ao_vec3 x = ao_vec3_sub(k ? sb.position : sa.position, p0);
                    double a11 = ao_vec3_dot(e1, e1), a12 = ao_vec3_dot(e1, e2), a22 = ao_vec3_dot(e2, e2);
                    double r1 = ao_vec3_dot(e1, x), r2 = ao_vec3_dot(e2, x), det = a11 * a22 - a12 * a12;
                    bary[k][0] = (a22 * r1 - a12 * r2) / det, bary[k][1] = (a11 * r2 - a12 * r1) / det;
                }
                struct ao_vec3 n0 = m->normals[t[0]];
                float moved = (float)(fabs(bary[0][0] - bary[1][0]) * distance(m->normals[t[1]], n0) +
                                      fabs(bary[0][1] - bary[1][1]) * distance(m->normals[t[2]], n0));
                float ns_bound = (moved * 1.01f + ao_gamma(32)) / 0.5f;
                float n = distance(sa.ns, sb.ns);
                worst_point = fmaxf(worst_point, distance(sa.position, sb.position) / bound);
                worst_normal = fmaxf(worst_normal, n / ns_bound);
                worst_ng = fmaxf(worst_ng, distance(sa.ng, sb.ng) / ng_bound);
                if (!(n <= ns_bound && distance(sa.ng, sb.ng) <= ng_bound))
                    print_error("pixel (%d, %d) instance %u: ns %.9g %.9g %.9g vs %.9g %.9g %.9g, ng %.9g %.9g %.9g vs %.9g %.9g %.9g\n",
                                i, j, a.instance, sa.ns.x, sa.ns.y, sa.ns.z, sb.ns.x, sb.ns.y, sb.ns.z, sa.ng.x, sa.ng.y,
                                sa.ng.z, sb.ng.x, sb.ng.y, sb.ng.z);
                assert_true(distance(sa.position, sb.position) <= bound);
                assert_true(n <= ns_bound && distance(sa.ng, sb.ng) <= ng_bound);
                (void)bu, (void)bv;
                continue;
            }
            edges++;
            float near = 1e-4f;
            bool a_edge = ha && (a.u < near || a.v < near || 1.0f - a.u - a.v < near);
            bool b_edge = hb && (bu < near || bv < near || 1.0f - bu - bv < near);
            if (!a_edge && !b_edge)
                print_error("pixel (%d, %d): instance %u triangle %u (%g, %g) against %u %u (%g, %g)\n", i, j,
                            ha ? a.instance : 99, ha ? a.prim : 0, ha ? a.u : 0, ha ? a.v : 0, hb ? b.instance : 99,
                            hb ? b.prim : 0, bu, bv);
            assert_true(a_edge || b_edge);
        }
    print_message("%d x %d eye rays: same triangle on placements 0-3: %d, %d, %d, %d; neighbouring triangles at an "
                  "edge: %d; both missed: %d; largest point difference %.3f of its bound, shading normal difference %.3f of its bound, "
                  "geometric normal difference %.3f of its bound\n",
                  W, H, same[0], same[1], same[2], same[3], edges, misses, worst_point, worst_normal, worst_ng);
    for (int k = 0; k < 4; k++)
        assert_true(same[k] > 200);
    teardown(&inst);
    teardown(&flat);
}

/* The AO images of the same scene instanced and flattened, 160x120, 64 samples a pixel, cosine
 * sampling, random numbers, same seed: each pixel estimates the same value, so the mean difference
 * over the n pixels that the bunnies cover is 0 in expectation. Each pixel's value is rho K / N, K
 * binomial, of variance at most rho^2 / (4 N); the difference of two such values at most
 * rho^2 / N (the variances of a difference add at worst as (s1 + s2)^2). Pixels are independent
 * (their random streams are), so the mean difference has standard deviation at most rho / sqrt(N n);
 * bound: 4 of those. Measured alongside: how many pixel values agree bit for bit. */
static void test_instanced_image_matches_flattened(void **state)
{
    (void)state;
    write_bunnies();
    struct fixture inst, flat;
    setup(&inst, "bunnies.scene", AO_INSTANCING_ALWAYS, false);
    setup(&flat, "bunnies.scene", AO_INSTANCING_NEVER, false);
    enum { W = 160, H = 120, N = 64 };
    float *a = render(&inst, W, H, N, AO_OUTPUT_AO, true), *b = render(&flat, W, H, N, AO_OUTPUT_AO, true);
    double sum = 0.0;
    int n = 0, equal = 0;
    for (int p = 0; p < W * H; p++) {
        if (a[3 * p] == 1.0f && b[3 * p] == 1.0f)   /* the background (1) on both */
            continue;
        n++;
        sum += (double)a[3 * p] - b[3 * p];
        equal += a[3 * p] == b[3 * p];
    }
    double mean = sum / n, bound = 4.0 * 0.8 / sqrt((double)N * n);
    print_message("AO, instanced against flattened: %d pixels on the bunnies, mean difference %+.2e (bound %.2e), "
                  "%d values equal\n", n, mean, bound, equal);
    assert_true(n > 1000);
    assert_true(fabs(mean) <= bound);
    free(a);
    free(b);
    teardown(&inst);
    teardown(&flat);
}

/* The BVHs (modes.h: MEDIUM, COMPACT, LOW and LOW_COMPACT) trace the same rays to the same hits, so
 * the bunnies, instanced and flattened, render the same image bit for bit with each: Embree's robust triangle test is the
 * same arithmetic on the same vertices whatever the tree and its leaves (measured on four scenes
 * in docs/formats.md). */
static void test_every_bvh_renders_the_same_image(void **state)
{
    (void)state;
    write_bunnies();
    enum { W = 96, H = 72, N = 8 };
    for (int instanced = 0; instanced < 2; instanced++) {
        enum ao_instancing how = instanced ? AO_INSTANCING_ALWAYS : AO_INSTANCING_NEVER;
        struct fixture medium;
        setup_bvh(&medium, "bunnies.scene", how, false, AO_BVH_MEDIUM);
        float *want = render(&medium, W, H, N, AO_OUTPUT_AO, true);
        for (enum ao_bvh bvh = AO_BVH_COMPACT; bvh <= AO_BVH_LOW_COMPACT; bvh++) {
            struct fixture other;
            setup_bvh(&other, "bunnies.scene", how, false, bvh);
            assert_int_equal(other.scene.bvh, bvh);
            float *got = render(&other, W, H, N, AO_OUTPUT_AO, true);
            int differ = 0;
            for (int p = 0; p < 3 * W * H; p++)
                differ += got[p] != want[p];
            print_message("%s, BVH %d against MEDIUM: %d of %d values differ\n", instanced ? "instanced" : "flattened",
                          (int)bvh, differ, 3 * W * H);
            assert_int_equal(differ, 0);
            free(got);
            teardown(&other);
        }
        free(want);
        teardown(&medium);
    }
}

/* The progressive tracer (LOW first, MEDIUM built beside it, switched to between passes) renders
 * the same image as MEDIUM alone, bit for bit, whether the switch comes during a run or before it;
 * one destroyed while its second build runs cancels it. */
static void test_progressive_bvh_renders_the_same_image(void **state)
{
    (void)state;
    write_bunnies();
    enum { W = 96, H = 72, N = 64 };
    for (int instanced = 0; instanced < 2; instanced++) {
        enum ao_instancing how = instanced ? AO_INSTANCING_ALWAYS : AO_INSTANCING_NEVER;
        struct fixture medium, progressive;
        setup_bvh(&medium, "bunnies.scene", how, false, AO_BVH_MEDIUM);
        float *want = render(&medium, W, H, N, AO_OUTPUT_AO, true);
        setup_bvh(&progressive, "bunnies.scene", how, false, AO_BVH_MEDIUM);
        ao_tracer_destroy(progressive.tracer);
        progressive.tracer = progressive.upgrade = ao_tracer_create_progressive(&progressive.scene);
        assert_non_null(progressive.tracer);
        for (int run = 0; run < 2; run++) {
            float *got = render(&progressive, W, H, N, AO_OUTPUT_AO, true);
            int differ = 0;
            for (int p = 0; p < 3 * W * H; p++)
                differ += got[p] != want[p];
            print_message("%s, progressive run %d against MEDIUM: %d of %d values differ\n",
                          instanced ? "instanced" : "flattened", run, differ, 3 * W * H);
            assert_int_equal(differ, 0);
            free(got);
            /* Before the second run, wait (at most 20 s) for the second build, if it is not in yet. */
            for (int wait = 0; run == 0 && wait < 2000 && ao_tracer_upgrading(progressive.tracer) &&
                               !ao_tracer_switch(progressive.tracer); wait++)
                nanosleep(&(struct timespec){.tv_nsec = 10000000}, NULL);
        }
        assert_false(ao_tracer_upgrading(progressive.tracer)); /* switched */
        free(want);
        teardown(&progressive);
        teardown(&medium);
    }
    struct fixture gone;
    setup_bvh(&gone, "bunnies.scene", AO_INSTANCING_NEVER, false, AO_BVH_MEDIUM);
    ao_tracer_destroy(gone.tracer);
    gone.tracer = ao_tracer_create_progressive(&gone.scene);
    assert_non_null(gone.tracer);
    teardown(&gone);
}

/* A unit sphere mesh with radial file normals, mirrored three ways: a glTF node scaling x by -1,
 * another scaling y by -1 under a rotation, and a scene file's mesh line (an OBJ) scaling x by -1;
 * instanced and flattened. A mirror turns the triangles round, so that their winding keeps agreeing
 * with the normals: at every eye hit the shading normal, turned to the eye with the geometric one,
 * must point out of the sphere, within the polyhedron's deviation from the sphere (32 segments:
 * facets 11 degrees across, so the interpolated normal lies within 6 degrees of the radial
 * direction, cosine 0.994; bound 0.99). Were the winding left as it was, it would point in (-1). */
static void test_mirrored_placements_shade_outward(void **state)
{
    (void)state;
    struct ao_mesh sphere;
    sphere_mesh(&sphere, 15, 32, true);
    write_gltf("mirrored.gltf", &sphere, 1,
               "[{\"mesh\": 0, \"scale\": [-1, 1, 1]},"
               " {\"mesh\": 0, \"translation\": [3, 0, 0], \"rotation\": [0, 0, 0.3826834, 0.9238795], \"scale\": [1, -1, 1]}]");
    struct text obj = {0};
    for (size_t v = 0; v < sphere.vertex_count; v++)
        say(&obj, "v %.9g %.9g %.9g\nvn %.9g %.9g %.9g\n", sphere.positions[v].x, sphere.positions[v].y,
            sphere.positions[v].z, sphere.normals[v].x, sphere.normals[v].y, sphere.normals[v].z);
    for (size_t t = 0; t < sphere.triangle_count; t++) {
        const uint32_t *i = &sphere.indices[3 * t];
        say(&obj, "f %u//%u %u//%u %u//%u\n", i[0] + 1, i[0] + 1, i[1] + 1, i[1] + 1, i[2] + 1, i[2] + 1);
    }
    write_text("mirrored.obj", obj.s);
    free(obj.s);
    ao_mesh_finish(&sphere);
    write_text("mirrored.scene", "camera eye 0 2 9 target 0 0 0 fov 50\nmesh mirrored.gltf\n"
                                 "mesh mirrored.obj scale -1 1 1 translate -3 0 0\n");
    const double centers[3][3] = {{0, 0, 0}, {3, 0, 0}, {-3, 0, 0}};
    for (int mode = 0; mode < 2; mode++) {
        struct fixture f;
        setup(&f, "mirrored.scene", mode ? AO_INSTANCING_NEVER : AO_INSTANCING_ALWAYS, false);
        enum { W = 120, H = 60 };
        struct ao_view view;
        assert_true(ao_camera_view(&f.scene.camera, W, H, &view));
        int hits[3] = {0};
        float worst = 1.0f;
        for (int j = 0; j < H; j++)
            for (int i = 0; i < W; i++) {
                struct ao_vec3 d = ao_camera_ray(&view, (float)i + 0.5f, (float)j + 0.5f);
                struct ao_hit hit;
                struct ao_surface s;
                if (!shade(&f, view.eye, d, &hit, &s))
                    continue;
                assert_true(hit.instance < 3);
                const double *c = centers[hit.instance];
                struct ao_vec3 out = ao_vec3_normalize(ao_vec3_make((float)(s.position.x - (c[0] - f.scene.origin[0])),
                                                                    (float)(s.position.y - (c[1] - f.scene.origin[1])),
                                                                    (float)(s.position.z - (c[2] - f.scene.origin[2]))));
                float cosine = ao_vec3_dot(s.ns, out);
                worst = fminf(worst, cosine);
                hits[hit.instance]++;
                assert_true(cosine >= 0.99f);
                assert_true(ao_vec3_dot(s.ng, out) >= 0.99f);
            }
        print_message("mirrored spheres, %s: %d, %d, %d hits; least cosine of the shading normal with the outward "
                      "radius %.4f\n", mode ? "flattened" : "instanced", hits[0], hits[1], hits[2], worst);
        for (int k = 0; k < 3; k++)
            assert_true(hits[k] > 100);
        teardown(&f);
    }
}

/* A scene file naming one mesh file three times loads it once: the bunny OBJ under three mesh
 * lines is one mesh placed three times (3 x 3,674 triangles: instanced by AUTO's rule), with each
 * line's albedo; the triangles placed are three bunnies'. */
static void test_three_mesh_lines_load_one_mesh(void **state)
{
    (void)state;
    const char *root = getenv("AO_SOURCE_ROOT");
    assert_non_null(root);
    char text[8192];
    snprintf(text, sizeof text,
             "camera eye 0 12 30 target 0 0 0\nmesh %s/assets/bunny.obj albedo 0.5\n"
             "mesh %s/assets/bunny.obj translate 12 0 0 albedo 0.6\n"
             "mesh %s/assets/../assets/bunny.obj rotate 0 1 0 90 translate -12 0 0 albedo 0.7\n", root, root, root);
    write_text("three.scene", text);
    struct fixture f;
    setup(&f, "three.scene", AO_INSTANCING_ALWAYS, false);
    assert_int_equal(f.scene.mesh_count, 1);
    assert_int_equal(f.scene.instance_count, 3);
    assert_int_equal(f.scene.triangle_count, 3 * f.scene.meshes[0].triangle_count);
    for (int i = 0; i < 3; i++) {
        assert_false(f.scene.instances[i].flat);
        assert_float_equal(f.scene.albedos[f.scene.instances[i].albedo].x, 0.5f + 0.1f * (float)i, 1e-7f);
    }
    struct ao_tracer_stats stats;
    ao_tracer_describe(f.tracer, &stats);
    assert_int_equal(stats.bvhs, 2);
    assert_int_equal(stats.instances, 3);
    teardown(&f);
}

/* A mesh line's crease sets the angle for its file: the bunny OBJ (no normals; folds of 40 to 120
 * degrees at its ears and feet, docs/formats.md) keeps its 1839 vertices at crease 180 and splits
 * some at the default 40; two lines naming the file with one angle share one mesh, with two
 * angles load it twice. A crease outside [0, 180] is refused at its line. */
static void test_a_mesh_lines_crease_angle(void **state)
{
    (void)state;
    const char *root = getenv("AO_SOURCE_ROOT");
    assert_non_null(root);
    char text[8192];
    snprintf(text, sizeof text,
             "camera eye 0 12 30 target 0 0 0\nmesh %s/assets/bunny.obj crease 180\n"
             "mesh %s/assets/bunny.obj translate 12 0 0 crease 180\n"
             "mesh %s/assets/bunny.obj translate -12 0 0\n", root, root, root);
    write_text("creases.scene", text);
    struct fixture f;
    setup(&f, "creases.scene", AO_INSTANCING_ALWAYS, false);
    assert_int_equal(f.scene.mesh_count, 2);
    assert_int_equal(f.scene.instance_count, 3);
    assert_int_equal(f.scene.meshes[0].vertex_count, 1839);
    assert_true(f.scene.meshes[1].vertex_count > 1839);
    assert_int_equal(f.scene.meshes[1].triangle_count, f.scene.meshes[0].triangle_count);
    teardown(&f);

    snprintf(text, sizeof text, "mesh %s/assets/bunny.obj crease 181\n", root);
    write_text("crease_bad.scene", text);
    char path[128];
    struct ao_scene scene;
    struct ao_scene_options options = {.budget = AO_BUDGET_LEAST};
    assert_false(ao_scene_load(&scene, in_dir("crease_bad.scene", path, sizeof path), &options));
}

/* A small file placing a mesh 10^5 times loads, instanced: a 600-triangle sphere under 100,000
 * glTF nodes (a 4 MB file; 60 million triangles placed, 7 GB flattened) is one mesh and 100,000
 * instances, Embree holds less than AO_BUDGET_INSTANCE a placement, and it renders. Under a budget
 * that its placements do not fit in, it is refused. */
static void test_a_mesh_placed_100000_times_loads(void **state)
{
    (void)state;
    enum { COPIES = 100000 };
    struct ao_mesh sphere;
    sphere_mesh(&sphere, 10, 30, false);
    assert_int_equal(sphere.triangle_count, 600);
    struct text nodes = {0};
    say(&nodes, "[");
    for (int k = 0; k < COPIES; k++)
        say(&nodes, "%s{\"mesh\": 0, \"translation\": [%d, 0, %d]}", k ? ", " : "", 3 * (k % 400), 3 * (k / 400));
    say(&nodes, "]");
    write_gltf("many.gltf", &sphere, 1, nodes.s);
    free(nodes.s);
    ao_mesh_finish(&sphere);
    struct fixture f;
    setup(&f, "many.gltf", AO_INSTANCING_AUTO, true);
    assert_int_equal(f.scene.mesh_count, 2);   /* the sphere and the ground */
    assert_int_equal(f.scene.instance_count, COPIES + 1);
    assert_int_equal(f.scene.triangle_count, (size_t)COPIES * 600 + 2);
    struct ao_tracer_stats stats;
    ao_tracer_describe(f.tracer, &stats);
    print_message("100,000 placements: %zu instances, Embree %.1f MB (%.0f bytes a placement, peak %.1f MB)\n",
                  stats.instances, stats.embree_bytes / 1e6, (double)stats.embree_bytes / COPIES,
                  stats.embree_peak_bytes / 1e6);
    assert_int_equal(stats.instances, COPIES);
    assert_true(stats.embree_bytes < (int64_t)COPIES * AO_BUDGET_INSTANCE);
    float *rgb = render(&f, 32, 24, 4, AO_OUTPUT_AO, true);
    double sum = 0.0;
    for (int p = 0; p < 32 * 24; p++)
        sum += rgb[3 * p];
    assert_true(isfinite(sum) && sum > 0.0);
    free(rgb);
    teardown(&f);
    char path[128];
    struct ao_scene_options small = {.budget = (uint64_t)COPIES * AO_BUDGET_INSTANCE};
    assert_false(ao_scene_load(&f.scene, in_dir("many.gltf", path, sizeof path), &small));
}

/* ---- far from the origin: a sphere mesh resting on a plane, both instanced */

/* The projected solid angle over pi (the form factor) that a convex polygon of n vertices v,
 * relative to the point, subtends for a receiver of unit normal N, the polygon wholly on N's side:
 * Lambert's sum over its edges of the angle each subtends times N . the unit normal of the plane
 * through the point and the edge, over 2 pi (the sign of the result follows the winding). */
static double polygon_form_factor(const double (*v)[3], int n, const double N[3])
{
    double sum = 0.0;
    for (int i = 0; i < n; i++) {
        const double *a = v[i], *b = v[(i + 1) % n];
        double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
        double lc = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]), dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        if (lc == 0.0)
            continue;
        double angle = atan2(lc, dot);
        sum += angle * (N[0] * c[0] + N[1] * c[1] + N[2] * c[2]) / lc;
    }
    return sum / (2.0 * 3.14159265358979323846);
}

/* The form factor, from the point o with normal +y, of the convex polyhedron whose world triangles
 * are tri (3 corners each, outward winding), count of them: the sum over the triangles that face
 * the point (their silhouettes tile the polyhedron's without overlap), each clipped to the point's
 * upper half-space (y >= o.y), where the hemisphere is. */
static double polyhedron_form_factor(const double (*tri)[3][3], size_t count, const double o[3])
{
    const double N[3] = {0, 1, 0};
    double total = 0.0;
    for (size_t t = 0; t < count; t++) {
        double v[3][3], e1[3], e2[3], n[3];
        for (int k = 0; k < 3; k++)
            for (int c = 0; c < 3; c++)
                v[k][c] = tri[t][k][c] - o[c];
        for (int c = 0; c < 3; c++)
            e1[c] = v[1][c] - v[0][c], e2[c] = v[2][c] - v[0][c];
        n[0] = e1[1] * e2[2] - e1[2] * e2[1], n[1] = e1[2] * e2[0] - e1[0] * e2[2], n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        if (n[0] * v[0][0] + n[1] * v[0][1] + n[2] * v[0][2] >= 0.0)   /* the point is not outside this face */
            continue;
        /* Clip to y >= 0 (Sutherland-Hodgman on one plane: at most 4 corners). */
        double clipped[4][3];
        int m = 0;
        for (int k = 0; k < 3; k++) {
            const double *a = v[k], *b = v[(k + 1) % 3];
            if (a[1] >= 0.0)
                memcpy(clipped[m++], a, sizeof clipped[0]);
            if ((a[1] >= 0.0) != (b[1] >= 0.0)) {
                double s = a[1] / (a[1] - b[1]);
                for (int c = 0; c < 3; c++)
                    clipped[m][c] = a[c] + s * (b[c] - a[c]);
                clipped[m++][1] = 0.0;
            }
        }
        if (m >= 3)
            total += fabs(polygon_form_factor((const double (*)[3])clipped, m, N));
    }
    return total;
}

/* test_ao_stability.c's contact test inside instances, far from the origin: a unit sphere mesh (a
 * polyhedron of 180 rings of 360 vertices, radial normals) rotated and scaled to radius r, resting
 * on a ground quad of +-20 r, both placed at (T, T, T) by glTF node transforms and both instanced
 * (their own frames around (0, 0, 0), the node maps carrying them out to T); r = 1 at T = 0 (the
 * control), 1e4 and 1e6. Ground points at x from the contact (the lowest vertex), found and shaded
 * as the renderer does (a grazing eye ray from the side away from the sphere), 10^6 cosine samples
 * each. The exact AO of the point that the occlusion rays leave (the lifted origin o, normal +y) is
 * rho (1 - F(o)), F the polyhedron's form factor from o (Lambert's formula on its faces that face o,
 * clipped to o's hemisphere; computed in double from the same float vertices and double node maps
 * the scene uses). With cosine sampling each sample is rho with probability q = 1 - F and 0
 * otherwise, so the mean of N samples has standard error rho sqrt(q (1-q) / N): bound 4 of those.
 * And geometrically: the origin lies above the ground and outside the polyhedron, and the lift is
 * at most 1e-5 r (against the facets' rise of 8.7e-3 x beside the contact, x >= 0.001 r). */
static void test_contact_holds_inside_instances_far_from_the_origin(void **state)
{
    (void)state;
    enum { N = 1000000, RINGS = 180, SEGMENTS = 360 };
    struct ao_mesh sphere, quad = {.vertex_count = 4, .triangle_count = 2};
    sphere_mesh(&sphere, RINGS, SEGMENTS, true);
    struct ao_vec3 qp[4] = {{-20, 0, -20}, {-20, 0, 20}, {20, 0, 20}, {20, 0, -20}}, qn[4] = {{0, 1, 0}, {0, 1, 0}, {0, 1, 0}, {0, 1, 0}};
    uint32_t qi[6] = {0, 1, 2, 0, 2, 3};
    quad.positions = qp, quad.normals = qn, quad.indices = qi;
    /* The sphere's node: rotation q (unit), scale r, translation putting its lowest vertex at y = T.
     * The world matrix as the loader forms it (glTF's quaternion to matrix, times the scale). */
    const double q[4] = {0.2, 0.3, -0.1, 0.9273618495495703}, r = 1.0;   /* x, y, z, w: |q| = 1 */
    double x = q[0], y = q[1], z = q[2], w = q[3], rot[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w),
                                                             2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                                                             2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)};
    double lowest = INFINITY, low[3] = {0};
    for (size_t v = 0; v < sphere.vertex_count; v++) {
        struct ao_vec3 p = sphere.positions[v];
        double wy = rot[1] * r * p.x + rot[4] * r * p.y + rot[7] * r * p.z;
        if (wy < lowest) {
            lowest = wy;
            low[0] = rot[0] * r * p.x + rot[3] * r * p.y + rot[6] * r * p.z, low[2] = rot[2] * r * p.x + rot[5] * r * p.y + rot[8] * r * p.z;
        }
    }
    const double shifts[3] = {0.0, 1e4, 1e6}, fractions[] = {0.001, 0.003, 0.01, 0.03, 0.1, 0.3, 1.0}, rho = 0.8;
    for (int c = 0; c < 3; c++) {
        double T = shifts[c];
        char nodes[512];
        snprintf(nodes, sizeof nodes,
                 "[{\"mesh\": 0, \"translation\": [%.17g, %.17g, %.17g], \"rotation\": [%.17g, %.17g, %.17g, %.17g],"
                 " \"scale\": [%.17g, %.17g, %.17g]}, {\"mesh\": 1, \"translation\": [%.17g, %.17g, %.17g]}]",
                 T, T - lowest, T, q[0], q[1], q[2], q[3], r, r, r, T, T, T);
        struct ao_mesh meshes[2] = {sphere, quad};
        write_gltf("contact.gltf", meshes, 2, nodes);
        char scene[256];
        snprintf(scene, sizeof scene, "camera eye %.17g %.17g %.17g target %.17g %.17g %.17g\nmesh contact.gltf albedo 0.8\n",
                 T, T + 6 * r, T + 6 * r, T, T, T);
        write_text("contact.scene", scene);
        struct fixture f;
        setup(&f, "contact.scene", AO_INSTANCING_ALWAYS, false);
        assert_int_equal(f.scene.instance_count, 2);
        assert_false(f.scene.instances[0].flat || f.scene.instances[1].flat);
        /* The polyhedron's triangles in the local frame, in double, from the node map the scene
         * composed (world minus the origin). */
        double (*tri)[3][3] = malloc(sphere.triangle_count * sizeof *tri);
        assert_non_null(tri);
        const double *o0 = f.scene.origin;
        for (size_t t = 0; t < sphere.triangle_count; t++)
            for (int k = 0; k < 3; k++) {
                struct ao_vec3 p = sphere.positions[sphere.indices[3 * t + (size_t)k]];
                double world[3] = {T, T - lowest, T};
                for (int a = 0; a < 3; a++)
                    tri[t][k][a] = rot[a] * r * p.x + rot[3 + a] * r * p.y + rot[6 + a] * r * p.z + world[a] - o0[a];
            }
        struct ao_context ctx = {.scene = &f.scene, .tracer = f.tracer, .sampling = AO_SAMPLING_COSINE,
                                 .ao_distance = INFINITY, .seed = 17};
        double contact[3] = {T + low[0] - o0[0], T - o0[1], T + low[2] - o0[2]};
        for (int k = 0; k < 7; k++) {
            double x0 = fractions[k] * r;
            struct ao_vec3 to = ao_vec3_make((float)(contact[0] + x0), (float)contact[1], (float)contact[2]);
            struct ao_vec3 from = ao_vec3_add(to, ao_vec3_make((float)(2 * r), (float)(2 * x0), 0));
            struct ao_vec3 d = ao_vec3_normalize(ao_vec3_sub(to, from));
            struct ao_hit hit;
            struct ao_surface surface;
            assert_true(shade(&f, from, d, &hit, &surface));
            assert_int_equal(hit.instance, 1);   /* the ground */
            surface.albedo = ao_vec3_make((float)rho, (float)rho, (float)rho);
            uint64_t rays = 0;
            double mean = ao_estimate_surface(&ctx, &surface, (uint64_t)k, 0, N, &rays).x / N;
            double o[3] = {surface.origin.x, surface.origin.y, surface.origin.z};
            double F = polyhedron_form_factor((const double (*)[3][3])tri, sphere.triangle_count, o);
            double qq = 1.0 - F, expected = rho * qq, se = rho * sqrt(qq * (1.0 - qq) / N);
            bool outside = false;
            for (size_t t = 0; t < sphere.triangle_count && !outside; t++) {
                double e1[3], e2[3], n[3], v[3];
                for (int a = 0; a < 3; a++)
                    e1[a] = tri[t][1][a] - tri[t][0][a], e2[a] = tri[t][2][a] - tri[t][0][a], v[a] = o[a] - tri[t][0][a];
                n[0] = e1[1] * e2[2] - e1[2] * e2[1], n[1] = e1[2] * e2[0] - e1[0] * e2[2], n[2] = e1[0] * e2[1] - e1[1] * e2[0];
                outside = n[0] * v[0] + n[1] * v[1] + n[2] * v[2] > 0.0;
            }
            double lift = o[1] - contact[1];
            print_message("instanced contact at %g, x/r = %.3f: AO %.7f, exact %.7f (%+.1f se); lift %.2g r%s\n", T,
                          hypot(o[0] - contact[0], o[2] - contact[2]) / r, mean, expected,
                          se > 0 ? (mean - expected) / se : 0.0, lift / r, outside ? "" : ": origin in the sphere");
            assert_true(outside);
            assert_true(lift > 0.0 && lift <= 1e-5 * r);
            assert_true(fabs(mean - expected) <= 4.0 * se + 1e-12);
        }
        free(tri);
        teardown(&f);
    }
    ao_mesh_finish(&sphere);
}

int main(void)
{
    snprintf(dir, sizeof dir, "/tmp/aoview-instances-XXXXXX");
    if (!mkdtemp(dir))
        return 1;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_auto_flattens_a_mesh_placed_a_few_times),
        cmocka_unit_test(test_a_map_too_small_to_invert_is_flattened),
        cmocka_unit_test(test_one_mesh_under_many_nodes_is_built_once),
        cmocka_unit_test(test_instances_shade_as_flattened),
        cmocka_unit_test(test_instanced_image_matches_flattened),
        cmocka_unit_test(test_every_bvh_renders_the_same_image),
        cmocka_unit_test(test_progressive_bvh_renders_the_same_image),
        cmocka_unit_test(test_mirrored_placements_shade_outward),
        cmocka_unit_test(test_three_mesh_lines_load_one_mesh),
        cmocka_unit_test(test_a_mesh_lines_crease_angle),
        cmocka_unit_test(test_a_mesh_placed_100000_times_loads),
        cmocka_unit_test(test_contact_holds_inside_instances_far_from_the_origin),
    };
    int failed = cmocka_run_group_tests(tests, NULL, NULL);
    char command[128];
    snprintf(command, sizeof command, "rm -rf %s", dir);
    if (system(command) != 0)
        return 1;
    return failed;
}
