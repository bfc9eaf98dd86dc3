/* Placing the scene read (struct ao_world) into its local frame: instances, bounds, the frame's
 * origin and range; see scene_place.h. What is read is gathered in scene_world.c. */
#include "scene_place.h"

#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* gamma(n) of ao.h in double, for the bounds computed here. */
static double gamma_n(int n)
{
    return n * 0x1p-24 / (1.0 - n * 0x1p-24);
}

/* The bound ao.c adds to the error of a point in an instanced mesh's own frame before it lifts an
 * occlusion ray's origin off the surface there: how far the origin o moves when ao.c maps it into
 * the local frame and Embree maps it back, for the instance's float map a (L, t), per axis, as
 * slack[0] max|o| + slack[1]. Those two maps:
 * - ao.c: o_local = L o + t in double, rounded once to float: off by e1, |e1| <= gamma1 |o_local|,
 *   and |o_local| <= (|L| |o| + |t|) (1 + gamma1).
 * - Embree (3.13, instance_intersector): W = L's inverse in float, as the adjoint over the
 *   determinant (each cofactor a b - c d off by gamma2 of |a b| + |c d|, the determinant a dot
 *   product with those, off by gamma5 of the same in absolute values, its reciprocal from rcpss and
 *   one Newton step, 5 ulps, and the product one more), c = -(W t) (off by gamma3 |W| |t|), and the
 *   origin W o_local + c by three multiply-adds (gamma4 (|W| |o_local| + |c|)).
 * With L* the exact inverse, o'' - o = (W - L*) L o + (W t + c) + W e1 + e3, so per axis
 *   |o'' - o| <= (E |L| + gamma6 |W| |L|) |o| + gamma14 |W| |t|,
 * where E = gamma16 (Cabs + |C| Dabs / |D|) / |D| bounds |W - L*| entry by entry (C the cofactors
 * and D the determinant, Cabs and Dabs computed with absolute values) and |W| <= |L*| + E. With
 * |o| <= max|o| on every axis, slack[0] is the largest row sum of the first matrix and slack[1]
 * the largest entry of the second vector; both are raised by 2^-20 of themselves for the rounding
 * of this arithmetic and of ao.c's float evaluation. False, when slack[0] exceeds 2^-8, slack[1]
 * exceeds 2^-8 of the largest float (so that ao.c's sums with it stay finite) or L is singular:
 * too ill-conditioned to instance (ao.c's lift assumes slack[0] <= 1/4); the mesh is flattened
 * instead. */
static bool round_trip(const float a[12], float slack[2])
{
    double l[9], cof[9], cabs[9];
    for (int k = 0; k < 9; k++)
        l[k] = a[k];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            int r1 = (r + 1) % 3, r2 = (r + 2) % 3, c1 = (c + 1) % 3, c2 = (c + 2) % 3;
            double x = l[3 * c1 + r1] * l[3 * c2 + r2], y = l[3 * c2 + r1] * l[3 * c1 + r2];
            cof[3 * c + r] = x - y;
            cabs[3 * c + r] = fabs(x) + fabs(y);
        }
    double det = l[0] * cof[0] + l[3] * cof[3] + l[6] * cof[6];
    double dabs = fabs(l[0]) * cabs[0] + fabs(l[3]) * cabs[3] + fabs(l[6]) * cabs[6];
    if (!(fabs(det) > 0.0) || !isfinite(det) || !isfinite(dabs))
        return false;
    /* W(r, c) = C(c, r) / D; E and |W| entry by entry, row r, column c at [3 c + r]. */
    double e[9], wabs[9];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            double cc = cof[3 * r + c], ca = cabs[3 * r + c];
            e[3 * c + r] = gamma_n(16) * (ca + fabs(cc) * dabs / fabs(det)) / fabs(det);
            wabs[3 * c + r] = fabs(cc) / fabs(det) + e[3 * c + r];
        }
    double alpha = 0.0, beta = 0.0;
    for (int r = 0; r < 3; r++) {
        double row = 0.0, wt = 0.0;
        for (int j = 0; j < 3; j++) {
            for (int k = 0; k < 3; k++)
                row += (e[3 * k + r] + gamma_n(6) * wabs[3 * k + r]) * fabs(l[3 * j + k]);
            wt += wabs[3 * j + r] * fabs((double)a[9 + j]);
        }
        alpha = fmax(alpha, row);
        beta = fmax(beta, gamma_n(14) * wt);
    }
    alpha *= 1.0 + 0x1p-20, beta *= 1.0 + 0x1p-20;
    if (!(alpha <= 0x1p-8) || !(beta <= 0x1p-8 * FLT_MAX))
        return false;
    slack[0] = nextafterf((float)alpha, INFINITY);
    slack[1] = nextafterf((float)beta, INFINITY);
    return true;
}

/* The map m narrowed to float, as an instance keeps it. */
static void narrow_affine(const struct ao_affine *m, float out[12])
{
    for (int k = 0; k < 12; k++)
        out[k] = (float)m->m[k];
}

/* The box lo..hi of mesh's positions, in its own frame (float comparisons: the loop stays in
 * registers, and a float's minimum is exact). */
static void box_of(const struct ao_mesh *mesh, struct ao_dvec3 *lo, struct ao_dvec3 *hi)
{
    float l[3] = {INFINITY, INFINITY, INFINITY}, h[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < mesh->vertex_count; v++) {
        const float p[3] = {mesh->positions[v].x, mesh->positions[v].y, mesh->positions[v].z};
        for (int k = 0; k < 3; k++) {
            l[k] = p[k] < l[k] ? p[k] : l[k];
            h[k] = p[k] > h[k] ? p[k] : h[k];
        }
    }
    *lo = ao_dvec3_make(l[0], l[1], l[2]);
    *hi = ao_dvec3_make(h[0], h[1], h[2]);
}

/* The largest translation per axis that the placement of a mesh with box info->lo..hi and linear
 * part a can have in the local frame, where the local frame is not chosen yet: a vertex p lies
 * within AO_SCENE_MAX_EXTENT there (check_range: the box is at most that across and either holds
 * (0, 0, 0) or is centred on it), so t = p_local - L p is within that plus |L| max|p| per axis,
 * raised by 2^-10 of itself for rounding. Infinite for a mesh without vertices. */
static void largest_translation(const float a[12], const struct ao_world_mesh *info, float t[3])
{
    double most = fmax(fmax(fmax(fabs(info->lo.x), fabs(info->hi.x)), fmax(fabs(info->lo.y), fabs(info->hi.y))),
                       fmax(fabs(info->lo.z), fabs(info->hi.z)));
    for (int r = 0; r < 3; r++)
        t[r] = (float)((AO_SCENE_MAX_EXTENT + (fabs(a[r]) + fabs(a[3 + r]) + fabs(a[6 + r])) * most) * (1.0 + 0x1p-10));
}

/* What a flattened copy of mesh is charged (build_instance): its triangles and vertices and
 * AO_BUDGET_COPY; UINT64_MAX where that overflows. */
static uint64_t copy_charge(const struct ao_world *w, const struct ao_mesh *mesh)
{
    uint64_t charge = ao_budget_charge(w->budget, mesh->triangle_count, mesh->vertex_count, 0);
    return charge <= UINT64_MAX - AO_BUDGET_COPY ? charge + AO_BUDGET_COPY : UINT64_MAX;
}

/* Never instanced where round_trip finds a placement's map too ill-conditioned for the largest
 * translation it can have in the local frame. */
bool ao_world_survey(struct ao_scene *s, struct ao_world *w)
{
    free(w->info);
    if (!(w->info = calloc(s->mesh_count ? s->mesh_count : 1, sizeof *w->info)))
        return false;
    uint64_t reserved = 0;   /* the budget AUTO's flattened copies will take (build_instance) */
    for (size_t i = 0; i < w->placement_count; i++)
        w->info[w->placements[i].mesh].placements++;
    for (size_t m = 0; m < s->mesh_count; m++) {
        struct ao_world_mesh *info = &w->info[m];
        const struct ao_mesh *mesh = &s->meshes[m];
        box_of(mesh, &info->lo, &info->hi);
        info->left = info->placements;
        size_t placed = info->placements * mesh->triangle_count;
        uint64_t copy = copy_charge(w, mesh), copies = UINT64_MAX;
        if (info->placements > 1 && copy <= (UINT64_MAX - reserved) / (info->placements - 1))
            copies = copy * (info->placements - 1);
        bool flat = info->placements < 2 || (placed / info->placements == mesh->triangle_count &&
                                              placed <= AO_SCENE_FLATTEN_TRIANGLES &&
                                              ao_budget_fits(w->budget, reserved + copies));
        info->instanced = w->instancing == AO_INSTANCING_ALWAYS ? info->placements > 0
                          : w->instancing == AO_INSTANCING_NEVER ? false
                          : !flat;
        if (w->instancing != AO_INSTANCING_ALWAYS && !info->instanced && info->placements > 1)
            reserved += copies;
    }
    for (size_t i = 0; i < w->placement_count; i++) {
        struct ao_world_mesh *info = &w->info[w->placements[i].mesh];
        float a[12], slack[2];
        narrow_affine(&w->placements[i].to_world, a);
        largest_translation(a, info, a + 9);
        if (info->instanced && !round_trip(a, slack))
            info->instanced = false;
    }
    return true;
}

/* The box lo..hi grown to hold p. */
static void grow(struct ao_dvec3 *lo, struct ao_dvec3 *hi, struct ao_dvec3 p)
{
    *lo = ao_dvec3_make(fmin(lo->x, p.x), fmin(lo->y, p.y), fmin(lo->z, p.z));
    *hi = ao_dvec3_make(fmax(hi->x, p.x), fmax(hi->y, p.y), fmax(hi->z, p.z));
}

/* True when m's linear part is diagonal: each world coordinate is then a product and a sum of one
 * mesh coordinate, monotonic in it after rounding too, so the box of the mapped vertices is
 * exactly the box of the mapped corners of the mesh's box. */
static bool diagonal(const struct ao_affine *m)
{
    return m->m[1] == 0.0 && m->m[2] == 0.0 && m->m[3] == 0.0 && m->m[5] == 0.0 && m->m[6] == 0.0 &&
           m->m[7] == 0.0;
}

/* The box lo..hi grown to hold the world positions of placement p: of the corners of its mesh's box
 * when instanced (a box holding the instance) or mapped by a diagonal map (exact); else of its
 * mesh's every vertex (exact). */
static void grow_by_placement(const struct ao_scene *s, const struct ao_world *w, const struct ao_world_placement *p,
                              struct ao_dvec3 *lo, struct ao_dvec3 *hi)
{
    const struct ao_world_mesh *info = &w->info[p->mesh];
    if (info->instanced || diagonal(&p->to_world)) {
        for (int k = 0; k < 8; k++)
            grow(lo, hi, ao_affine_point(&p->to_world, k & 1 ? info->hi.x : info->lo.x, k & 2 ? info->hi.y : info->lo.y,
                                         k & 4 ? info->hi.z : info->lo.z));
        return;
    }
    const struct ao_mesh *m = &s->meshes[p->mesh];
    for (size_t v = 0; v < m->vertex_count; v++)
        grow(lo, hi, ao_affine_point(&p->to_world, m->positions[v].x, m->positions[v].y, m->positions[v].z));
}

bool ao_world_bounds(const struct ao_scene *s, const struct ao_world *w, struct ao_dvec3 *lo, struct ao_dvec3 *hi)
{
    *lo = ao_dvec3_make(INFINITY, INFINITY, INFINITY);
    *hi = ao_dvec3_make(-INFINITY, -INFINITY, -INFINITY);
    for (size_t i = 0; i < s->sphere_count; i++) {
        struct ao_dvec3 c = w->sphere_centers[i];
        double r = s->spheres[i].radius;
        grow(lo, hi, ao_dvec3_make(c.x - r, c.y - r, c.z - r));
        grow(lo, hi, ao_dvec3_make(c.x + r, c.y + r, c.z + r));
    }
    for (size_t i = 0; i < w->quad_count; i++)
        for (int k = 0; k < 4; k++)
            grow(lo, hi, w->quads[i].p[k]);
    for (size_t i = 0; i < w->placement_count; i++)
        grow_by_placement(s, w, &w->placements[i], lo, hi);
    return s->sphere_count + w->quad_count + w->placement_count > 0;
}

/* The sizes of scene that the renderer draws as it would the same scene at size 1 (scene.h's
 * AO_SCENE_MIN_EXTENT and AO_SCENE_MAX_EXTENT; measured in docs/stability.md). It traces in single
 * precision with flush-to-zero on, so each product it forms must stay between 2^-126 (below, it
 * becomes 0) and 2^128 (above, infinite). With E the largest side of the box around the geometry,
 * eye and target, every local coordinate is at most E (ao_world_place()'s origin is in the box), and:
 * - Above. A triangle in the box has edges of at most sqrt(3) E, so the unnormalized normal
 *   Ng = e1 x e2 that either tracer returns is at most 3 E^2 long, and ao.c normalizes it through
 *   |Ng|^2 <= 9 E^4 < 2^128: E < 2^32 / sqrt(3) = 2.48e9. The tracers' distance tests multiply Ng
 *   by one more length (Embree's Pluecker depth 2 (v0 - o).Ng, the direct loops' w.N, at most
 *   2 sqrt(3) E 3 E^2), which needs only E < 3.2e12; Embree's ray validity check (its assertion
 *   `ray.valid()`: |org| and |dir| at most FLT_LARGE = 1.844e18, a tenth of sqrt(2^128)) only
 *   E < 1.8e18. AO_SCENE_MAX_EXTENT = 2^31 = 2.15e9.
 * - Below. Occlusion rays leave a surface lifted past the point's error bound, with a floor of
 *   2^-100 where that bound is 0 (ao.h): on a facet in a coordinate plane through the local
 *   origin, such as the ground y = 0 of most scenes. The same distance tests multiply that lift by
 *   |Ng|; below 2^-126 the product flushes to 0, the ray meets its own facet at t = 0 and the
 *   facet turns black. So |Ng| >= 2^-26, which a facet spanning the scene (|Ng| = E^2 for a
 *   square) reaches at E = 2^-13 = 1.22e-4; AO_SCENE_MIN_EXTENT = 2^-12 = 2.44e-4 keeps a factor 2.
 * A camera line's eye and target are ray origins and directions: they belong to the box (Embree's
 * check, and the depth test's o; the camera framing a scene without one stands outside it, within
 * 3.3 E of the origin, which those bounds allow), and ao_camera_view squares their distance,
 * which must therefore stay above 2^-63 (MIN_CAMERA_DISTANCE = 2^-60). Detail finer than the scene is not checked: a
 * triangle whose |Ng| is below 2^-63 (edges of about 3e-10) is shaded with the eye-facing normal
 * that stands in for degenerate ones, and a facet in a coordinate plane through the origin with
 * |Ng| below 2^-26 occludes itself, whatever the scene's size. */
static const double MIN_CAMERA_DISTANCE = 0x1p-60;

double ao_world_largest_side(struct ao_dvec3 lo, struct ao_dvec3 hi)
{
    return fmax(hi.x - lo.x, fmax(hi.y - lo.y, hi.z - lo.z));
}

/* Refuses a scene whose geometry (the box lo..hi, when any) or camera leaves the range derived
 * above, with one line naming the size; false after reporting. */
static bool check_range(const struct ao_world *w, struct ao_cursor *c, bool any, struct ao_dvec3 lo, struct ao_dvec3 hi)
{
    static const char range[] = "aoview renders scenes from %.3g to %.3g across (docs/stability.md)";
    char message[256];
    double size = any ? ao_world_largest_side(lo, hi) : 0.0;
    c->line = 0;
    snprintf(message, sizeof message, range, AO_SCENE_MIN_EXTENT, AO_SCENE_MAX_EXTENT);
    if (any && !(size >= AO_SCENE_MIN_EXTENT && size <= AO_SCENE_MAX_EXTENT))
        return ao_cursor_fail(c, "the scene is %.3g across%s; %s", size, w->extent_note, message);
    if (!w->has_camera)
        return true;
    c->line = w->camera_line;
    if (!any)
        lo = hi = w->eye;
    grow(&lo, &hi, w->eye);
    grow(&lo, &hi, w->target);
    if (!(ao_world_largest_side(lo, hi) <= AO_SCENE_MAX_EXTENT))
        return ao_cursor_fail(c, "camera: with it the scene is %.3g across; %s", ao_world_largest_side(lo, hi),
                              message);
    struct ao_dvec3 d = ao_dvec3_sub(w->target, w->eye), along;
    double distance = ao_dvec3_unit(d, &along) ? ao_dvec3_dot(d, along) : 0.0;   /* |d|, no square to vanish */
    if (distance > 0.0 && distance < MIN_CAMERA_DISTANCE)
        return ao_cursor_fail(c, "camera: eye and target are %.3g apart, closer than the %.3g aoview can aim by",
                              distance, MIN_CAMERA_DISTANCE);
    return true;
}

/* Writes src (a mesh in its own frame) moved by to_local into dst (the same mesh, moved in place, or
 * an empty one that receives a copy) by ao_mesh_place. False when memory is short. */
static bool flatten(struct ao_mesh *dst, const struct ao_mesh *src, const struct ao_affine *to_local)
{
    if (dst != src) {
        *dst = (struct ao_mesh){.vertex_count = src->vertex_count, .triangle_count = src->triangle_count};
        dst->positions = malloc((src->vertex_count ? src->vertex_count : 1) * sizeof *dst->positions);
        dst->normals = malloc((src->vertex_count ? src->vertex_count : 1) * sizeof *dst->normals);
        dst->indices = malloc((src->triangle_count ? 3 * src->triangle_count : 1) * sizeof *dst->indices);
        if (!dst->positions || !dst->normals || !dst->indices) {
            ao_mesh_finish(dst);
            return false;
        }
    }
    ao_mesh_place(dst, 0, 0, src, to_local);   /* check_range keeps every position finite */
    return true;
}

/* Builds the instance of placement p, whose map into the local frame is to_local: an instanced
 * mesh's map and slack, or the mesh flattened (moved in place at its last placement, copied before:
 * each copy a mesh of its own, charged to the budget). False after reporting. */
static bool build_instance(struct ao_scene *s, struct ao_world *w, struct ao_cursor *c,
                           const struct ao_world_placement *p, const struct ao_affine *to_local)
{
    struct ao_world_mesh *info = &w->info[p->mesh];
    struct ao_instance *in = &s->instances[s->instance_count];
    *in = (struct ao_instance){.mesh = p->mesh, .albedo = p->albedo, .flat = !info->instanced};
    if (info->instanced) {
        struct ao_affine narrowed;
        double n[9];
        narrow_affine(to_local, in->to_local);
        for (int k = 0; k < 12; k++)
            narrowed.m[k] = in->to_local[k];
        ao_affine_normals(&narrowed, n);
        for (int k = 0; k < 9; k++)
            in->normals[k] = (float)n[k];
        if (!round_trip(in->to_local, in->slack))   /* ao_world_survey() checked L with a larger t */
            return ao_cursor_fail(c, "an instance's transform is too ill-conditioned to trace");
        s->instance_count++;
        return true;
    }
    narrow_affine(&(struct ao_affine){{1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0}}, in->to_local);
    in->normals[0] = in->normals[4] = in->normals[8] = 1.0f;
    size_t dst = p->mesh;
    if (--info->left > 0) {   /* a copy: the mesh itself is still needed in its own frame */
        const struct ao_mesh *m = &s->meshes[p->mesh];
        if (!ao_world_charge(c, w, m->triangle_count, m->vertex_count, "a flattened copy") ||
            !ao_world_take(c, w, AO_BUDGET_COPY, "a flattened copy's structures"))
            return false;
        if (s->mesh_count >= UINT32_MAX ||
            !ao_scene_grow(&s->meshes, s->mesh_count, s->mesh_count + 1, sizeof *s->meshes))
            return ao_cursor_fail(c, "out of memory");
        dst = s->mesh_count;
        s->meshes[dst] = (struct ao_mesh){0};
    }
    if (!flatten(&s->meshes[dst], &s->meshes[p->mesh], to_local))
        return ao_cursor_fail(c, "out of memory");
    s->mesh_count += dst != p->mesh;
    s->instances[s->instance_count].mesh = (uint32_t)dst;
    s->instance_count++;
    return true;
}

/* The quads from w->quads[*next] on that share its albedo, as one flat mesh in the local frame. */
static bool build_quads(struct ao_scene *s, struct ao_world *w, size_t *next, struct ao_dvec3 origin)
{
    size_t first = *next, n = 1;
    while (first + n < w->quad_count && memcmp(&w->quads[first + n].rho, &w->quads[first].rho,
                                               sizeof w->quads[first].rho) == 0)
        n++;
    *next = first + n;
    uint32_t a;
    if (!ao_scene_add_albedo(s, w->quads[first].rho, &a) || s->mesh_count >= UINT32_MAX ||
        !ao_scene_grow(&s->meshes, s->mesh_count, s->mesh_count + 1, sizeof *s->meshes))
        return false;
    struct ao_mesh *m = &s->meshes[s->mesh_count];
    *m = (struct ao_mesh){.vertex_count = 4 * n, .triangle_count = 2 * n};
    m->positions = malloc(4 * n * sizeof *m->positions);
    m->normals = malloc(4 * n * sizeof *m->normals);
    m->indices = malloc(6 * n * sizeof *m->indices);
    if (!m->positions || !m->normals || !m->indices) {
        ao_mesh_finish(m);
        return false;
    }
    static const uint32_t tris[6] = {0, 1, 2, 0, 2, 3};
    for (size_t q = 0; q < n; q++) {
        for (int k = 0; k < 4; k++) {
            m->positions[4 * q + (size_t)k] = ao_dvec3_narrow(ao_dvec3_sub(w->quads[first + q].p[k], origin));
            m->normals[4 * q + (size_t)k] = w->quads[first + q].n;
        }
        for (int k = 0; k < 6; k++)
            m->indices[6 * q + (size_t)k] = (uint32_t)(4 * q) + tris[k];
    }
    s->instances[s->instance_count++] = (struct ao_instance){
        .mesh = (uint32_t)s->mesh_count++, .albedo = a, .flat = true,
        .to_local = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0}, .normals = {1, 0, 0, 0, 1, 0, 0, 0, 1}};
    return true;
}

/* Moves the scene from world space into its local frame and narrows it to float: every mesh
 * placement (moved into the frame, or instanced with its map into it), quad, sphere centre and the
 * camera become world - origin, with the origin at the bounding box's centre (a scene without
 * geometry: the box of its camera's eye and target), so that float
 * precision follows the scene's size rather than its distance from (0, 0, 0). Where the box holds
 * (0, 0, 0) its coordinates are at most its size already (one bit worse than from the centre) and
 * the origin stays there, leaving such scenes exactly as written. A scene without a camera line
 * gets one framed on its box. False after reporting (the camera's line) or on short memory. */
bool ao_world_place(struct ao_scene *s, struct ao_world *w, struct ao_cursor *c)
{
    struct ao_dvec3 lo, hi, origin = {0};
    c->line = 0;
    if (!ao_world_survey(s, w))
        return ao_cursor_fail(c, "out of memory");
    bool any = ao_world_bounds(s, w, &lo, &hi);
    if (!check_range(w, c, any, lo, hi))
        return false;
    if (!any && w->has_camera) { /* nothing to frame: the frame is the camera's, as far as it stands */
        lo = hi = w->eye;
        grow(&lo, &hi, w->target);
    }
    if ((any || w->has_camera) && !(lo.x <= 0.0 && hi.x >= 0.0 && lo.y <= 0.0 && hi.y >= 0.0 && lo.z <= 0.0 && hi.z >= 0.0))
        origin = ao_dvec3_scale(ao_dvec3_add(lo, hi), 0.5);
    s->origin[0] = origin.x, s->origin[1] = origin.y, s->origin[2] = origin.z;
    c->line = 0;
    if (!ao_scene_grow(&s->instances, s->instance_count, w->placement_count + w->quad_count, sizeof *s->instances))
        return ao_cursor_fail(c, "out of memory");
    struct ao_affine shift = ao_affine_identity();
    shift.m[9] = -origin.x, shift.m[10] = -origin.y, shift.m[11] = -origin.z;
    for (size_t i = 0; i < w->placement_count; i++) {
        struct ao_affine to_local = ao_affine_compose(&shift, &w->placements[i].to_world);
        if (!build_instance(s, w, c, &w->placements[i], &to_local))
            return false;
    }
    for (size_t next = 0; next < w->quad_count;)
        if (!build_quads(s, w, &next, origin))
            return ao_cursor_fail(c, "out of memory");
    for (size_t i = 0; i < s->mesh_count; i++)
        if (!ao_scene_pad(&s->meshes[i]))
            return ao_cursor_fail(c, "out of memory");
    for (size_t i = 0; i < s->instance_count; i++)
        s->triangle_count += s->meshes[s->instances[i].mesh].triangle_count;
    for (size_t i = 0; i < s->sphere_count; i++)
        s->spheres[i].center = ao_dvec3_narrow(ao_dvec3_sub(w->sphere_centers[i], origin));
    if (w->has_camera) {
        s->camera.eye = ao_dvec3_narrow(ao_dvec3_sub(w->eye, origin));
        s->camera.target = ao_dvec3_narrow(ao_dvec3_sub(w->target, origin));
        struct ao_view view;
        c->line = w->camera_line;
        if (!ao_camera_view(&s->camera, 1, 1, &view))
            return ao_cursor_fail(c, "camera: eye equals target or up is parallel to the view direction");
        return true;
    }
    c->line = 0;
    if (!any)
        return ao_cursor_fail(c, "no camera and nothing to frame: add a 'camera' line or some geometry");
    ao_camera_frame_box(&s->camera, ao_dvec3_narrow(ao_dvec3_sub(lo, origin)),
                        ao_dvec3_narrow(ao_dvec3_sub(hi, origin)));
    return true;
}
