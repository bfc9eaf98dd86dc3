/* The exact ambient-occlusion image of a scene that has a closed form (exact_image.h), what
 * aoview-exact writes as a PFM to use as aoview's --reference. Eye rays go through the project's camera and tracer, so
 * what each pixel sees is exactly what aoview sees; only the AO integral is replaced by its
 * closed form. Scenes with a closed form (anything else is refused with the reason):
 *
 * - coplanar triangles (a plane: every vertex within 1e-6 of the largest coordinate of the plane
 *   of the largest triangle, about the float resolution of the plane's far corners) and at most
 *   one sphere wholly on one side of it (centre at height h >= r). A plane point at distance d from the centre, on the sphere's side, sees the sphere as
 *   a disc of projected solid angle pi r^2 h / d^3 (the form factor of a sphere above a
 *   differential area whose horizon it does not cross), so AO = rho (1 - r^2 h / d^3); on the
 *   far side AO = rho. A sphere point whose unit normal n makes angle alpha with the plane's
 *   normal N (towards the sphere) is occluded by the plane exactly in the directions below its
 *   horizontal, whose cosine-weighted share of n's hemisphere is (1 - cos alpha)/2, so
 *   AO = rho (1 + n.N)/2 for an infinite plane. Seen from inside, the sphere is closed: AO = 0.
 *   With no sphere, AO = rho everywhere (an open plane); with no plane, a sphere point sees
 *   nothing: AO = rho.
 *   Finite ground. A downward direction at depression angle beta from a point at height z meets
 *   the plane at horizontal distance s = z / tan(beta); it escapes where that is off the ground.
 *   With D the distance from the point's foot to the nearest boundary edge of the triangles, only
 *   beta < eps = atan(z / D) can escape, and for such small angles the escaping share is, to
 *   first order in eps, (z / pi) Int max(0, n.h(phi)) E(phi) dphi, h(phi) the horizontal
 *   direction of azimuth phi and E(phi) = sum (1/s_in - 1/s_out) over the stretches [s_in, s_out)
 *   of the ray from the foot along h(phi) that lie off the ground (s_out infinite for the last):
 *   the depression angles atan(z/s) that land there, per unit z. The integral depends on n only
 *   through its horizontal part: |n_h| G(phi_n) with G(psi) = Int max(0, cos(phi - psi)) E(phi)
 *   dphi, tabulated once per scene from the sphere's foot (ESCAPE_STEPS azimuths) and added to
 *   the infinite-plane form. What is left is second order: the cosine weight and the solid angle
 *   at angle beta (eps^2), atan against its argument (eps^3), and a sphere point's foot lying up
 *   to r from the centre's (eps r / D <= eps^2): at most 2 eps^2 with rho = 1. The tool bounds z
 *   by h + r and D by (distance from the centre's foot to the boundary) - r, and refuses a ground
 *   whose bound exceeds MAX_GROUND_ERROR: a quad of +-1e4 under a sphere of radius 0.5 resting on
 *   it (top at height 1) gives eps = 1e-4 and a residual below 2e-8 rho, against the 6.4e-5 rho
 *   (2 eps / pi) that the escaping share itself reaches. Plane points are exact.
 * - a closed box around the eye: watertight triangles (every edge shared by exactly two) all on
 *   the faces of their bounding box, with the eye strictly inside it. Every occlusion ray from an
 *   inner wall meets another wall: AO = 0.
 *
 * An infinite AO distance is required (the forms above assume it).
 *
 * Pixel values: with --no-aa the closed form at the pixel centre's hit, as aoview without AA
 * computes it. With AA (aoview's default) the box-filtered pixel: the mean of the closed form over
 * a k x k grid of sub-pixel cell centres, k = round(sqrt(--spp)) (default 16). Where the image is
 * smooth the midpoint rule's error is O(1/k^2) of the second derivative; a pixel crossed by a
 * silhouette or the horizon is off by at most (jump) x (cells the edge crosses, <= 2k) / k^2 <=
 * 2 jump / k, and in practice by much less, since the cells' errors have both signs.
 * Measured against k = 256 at 160x120: k = 16 is off by 1.1e-4 RMSE (7e-3 in the worst pixel) on
 * sphere-on-plane.scene and 3.1e-4 (1.4e-2) on hovering-sphere.scene, whose view has a horizon;
 * k = 64 by 9e-6 (5e-4) and 7e-5 (9e-4). docs/ uses k = 64 (--spp 4096). */
#include "exact_image.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ao.h"
#include "camera.h"

/* Largest accepted residual of the sphere formula's finite-ground term (albedo 1), and the
 * azimuths its table is integrated over. */
static const float MAX_GROUND_ERROR = 1e-6f;
enum { ESCAPE_STEPS = 4096, MAX_CROSSINGS = 64 };
static const float PI = 3.14159265358979323846f;

/* What the scene's closed form needs. */
enum kind { KIND_PLANE_SPHERE, KIND_CLOSED_BOX };
struct closed_form {
    enum kind kind;
    const struct ao_sphere *sphere;   /* NULL: no sphere */
    bool plane;                        /* some triangles (all in one plane) */
    struct ao_vec3 up;                 /* the plane's unit normal, towards the sphere's side */
    struct ao_vec3 plane_point;        /* a vertex of the plane */
    struct ao_basis axes;              /* axes.t, axes.b: the plane's azimuth 0 and pi/2 */
    float ground_error;                /* bound on the residual of the sphere formula's ground term */
    double escape[ESCAPE_STEPS];       /* G(psi) at psi = 2 pi k / ESCAPE_STEPS, see above */
};

/* An edge with its end points in lexicographic order, so that shared edges compare equal. */
struct edge {
    struct ao_vec3 a, b;
};

static int compare_points(struct ao_vec3 p, struct ao_vec3 q)
{
    if (p.x != q.x)
        return p.x < q.x ? -1 : 1;
    if (p.y != q.y)
        return p.y < q.y ? -1 : 1;
    return p.z < q.z ? -1 : p.z > q.z;
}

static int compare_edges(const void *pa, const void *pb)
{
    const struct edge *a = pa, *b = pb;
    int c = compare_points(a->a, b->a);
    return c ? c : compare_points(a->b, b->b);
}

/* The scene's triangles in the local frame, three corners each: the classifier's view of it (an
 * instanced mesh's triangles mapped into the frame, ao_scene_triangle). */
struct soup {
    struct ao_vec3 *corners;
    size_t triangle_count;
};

/* The most placed triangles the classifier looks at (its edges take 72 bytes a triangle). */
enum { MAX_TRIANGLES = 1 << 24 };

static struct ao_vec3 vertex(const struct soup *s, size_t triangle, int corner)
{
    return s->corners[3 * triangle + (size_t)corner];
}

/* Every triangle edge, sorted so that an edge shared by m triangles forms a run of m; NULL when
 * memory runs out. */
static struct edge *sorted_edges(const struct soup *s)
{
    struct edge *e = malloc(3 * s->triangle_count * sizeof *e);
    if (!e)
        return NULL;
    for (size_t t = 0; t < s->triangle_count; t++)
        for (int k = 0; k < 3; k++) {
            struct ao_vec3 p = vertex(s, t, k), q = vertex(s, t, (k + 1) % 3);
            bool in_order = compare_points(p, q) < 0;
            e[3 * t + (size_t)k] = (struct edge){in_order ? p : q, in_order ? q : p};
        }
    qsort(e, 3 * s->triangle_count, sizeof *e, compare_edges);
    return e;
}

/* Length of the run of equal edges starting at e[i]. */
static size_t run_length(const struct edge *e, size_t count, size_t i)
{
    size_t j = i + 1;
    while (j < count && compare_edges(&e[i], &e[j]) == 0)
        j++;
    return j - i;
}

static float distance_to_segment(struct ao_vec3 p, struct ao_vec3 a, struct ao_vec3 b)
{
    struct ao_vec3 ab = ao_vec3_sub(b, a);
    float len2 = ao_vec3_dot(ab, ab);
    float t = len2 > 0.0f ? fmaxf(0.0f, fminf(1.0f, ao_vec3_dot(ao_vec3_sub(p, a), ab) / len2)) : 0.0f;
    return ao_vec3_length(ao_vec3_sub(p, ao_vec3_add(a, ao_vec3_scale(ab, t))));
}

/* True when p, a point of the plane with normal n, lies in some triangle. */
static bool plane_contains(const struct soup *s, struct ao_vec3 n, struct ao_vec3 p)
{
    for (size_t t = 0; t < s->triangle_count; t++) {
        struct ao_vec3 v[3] = {vertex(s, t, 0), vertex(s, t, 1), vertex(s, t, 2)};
        float side[3];
        for (int k = 0; k < 3; k++)
            side[k] = ao_vec3_dot(n, ao_vec3_cross(ao_vec3_sub(v[(k + 1) % 3], v[k]), ao_vec3_sub(p, v[k])));
        if ((side[0] >= 0 && side[1] >= 0 && side[2] >= 0) || (side[0] <= 0 && side[1] <= 0 && side[2] <= 0))
            return true;
    }
    return false;
}

/* Distance from p to the nearest edge used by one triangle only (the plane's outline). */
static float distance_to_outline(const struct edge *e, size_t count, struct ao_vec3 p)
{
    float d = INFINITY;
    for (size_t i = 0; i < count; i += run_length(e, count, i))
        if (run_length(e, count, i) == 1)
            d = fminf(d, distance_to_segment(p, e[i].a, e[i].b));
    return d;
}

/* Sets *n to the unit normal of the largest triangle and returns true when every vertex lies
 * within 1e-6 of the largest coordinate of that plane (a few ulps of its far corners). */
static bool coplanar(const struct soup *s, struct ao_vec3 *n)
{
    float best = 0.0f, extent = 0.0f;
    for (size_t t = 0; t < s->triangle_count; t++) {
        struct ao_vec3 c = ao_vec3_cross(ao_vec3_sub(vertex(s, t, 1), vertex(s, t, 0)),
                                         ao_vec3_sub(vertex(s, t, 2), vertex(s, t, 0)));
        if (ao_vec3_length(c) > best) {
            best = ao_vec3_length(c);
            *n = ao_vec3_scale(c, 1.0f / best);
        }
    }
    for (size_t v = 0; v < 3 * s->triangle_count; v++)
        extent = fmaxf(extent, ao_vec3_max_abs(s->corners[v]));
    struct ao_vec3 origin = s->corners[0];
    for (size_t v = 0; v < 3 * s->triangle_count; v++)
        if (fabsf(ao_vec3_dot(*n, ao_vec3_sub(s->corners[v], origin))) > 1e-6f * extent)
            return false;
    return true;
}

/* True when every triangle lies on a face of the triangles' bounding box and eye is inside it. */
static bool on_box_faces(const struct soup *s, struct ao_vec3 eye)
{
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < 3 * s->triangle_count; v++) {
        const float *p = &s->corners[v].x;
        for (int a = 0; a < 3; a++) {
            lo[a] = fminf(lo[a], p[a]);
            hi[a] = fmaxf(hi[a], p[a]);
        }
    }
    const float *e = &eye.x;
    for (int a = 0; a < 3; a++)
        if (!(e[a] > lo[a] && e[a] < hi[a]))
            return false;
    for (size_t t = 0; t < s->triangle_count; t++) {
        struct ao_vec3 v0 = vertex(s, t, 0), v1 = vertex(s, t, 1), v2 = vertex(s, t, 2);
        const float *p0 = &v0.x, *p1 = &v1.x, *p2 = &v2.x;
        bool on_face = false;
        for (int a = 0; a < 3; a++)
            on_face |= p0[a] == p1[a] && p0[a] == p2[a] && (p0[a] == lo[a] || p0[a] == hi[a]);
        if (!on_face)
            return false;
    }
    return true;
}

/* Distance along the in-plane ray foot + s dir to segment [a, b] of the plane, or -1 when the ray
 * misses it (2D, in the plane's axes t and b). */
static double ray_segment(const struct closed_form *cf, struct ao_vec3 foot, double dx, double dy, struct ao_vec3 a,
                          struct ao_vec3 b)
{
    struct ao_vec3 pa = ao_vec3_sub(a, foot), pb = ao_vec3_sub(b, foot);
    double ax = ao_vec3_dot(pa, cf->axes.t), ay = ao_vec3_dot(pa, cf->axes.b);
    double ex = ao_vec3_dot(pb, cf->axes.t) - ax, ey = ao_vec3_dot(pb, cf->axes.b) - ay;
    double det = ex * dy - ey * dx; /* solves s dir = a + u e */
    if (det == 0.0)
        return -1.0;
    double along = (ex * ay - ey * ax) / det, u = (dx * ay - dy * ax) / det;
    return along > 0.0 && u >= 0.0 && u < 1.0 ? along : -1.0;
}

/* Fills cf->escape, G(psi) = Int max(0, cos(phi - psi)) E(phi) dphi, from the boundary edges (runs
 * of one) as seen from foot, which the ground contains: E(phi) sums 1/s_in - 1/s_out over the
 * stretches of the ray along phi that lie off the ground. Midpoint azimuths keep the rays off the
 * outline's vertices, where one crossing would count twice. False when a ray crosses the outline
 * more than MAX_CROSSINGS times. */
static bool tabulate_escape(struct closed_form *cf, const struct edge *e, size_t count, struct ao_vec3 foot)
{
    double across[ESCAPE_STEPS];
    const double step = 2.0 * (double)PI / ESCAPE_STEPS;
    for (int k = 0; k < ESCAPE_STEPS; k++) {
        double phi = (k + 0.5) * step, dx = cos(phi), dy = sin(phi), crossings[MAX_CROSSINGS];
        int n = 0;
        for (size_t i = 0; i < count; i += run_length(e, count, i)) {
            double at = run_length(e, count, i) == 1 ? ray_segment(cf, foot, dx, dy, e[i].a, e[i].b) : -1.0;
            if (at > 0.0 && n == MAX_CROSSINGS)
                return false;
            if (at > 0.0) { /* kept in increasing order */
                int j = n++;
                for (; j > 0 && crossings[j - 1] > at; j--)
                    crossings[j] = crossings[j - 1];
                crossings[j] = at;
            }
        }
        /* The ray starts on the ground: it is off it from crossing 0 to 1, 2 to 3, ... */
        across[k] = 0.0;
        for (int j = 0; j < n; j += 2)
            across[k] += 1.0 / crossings[j] - (j + 1 < n ? 1.0 / crossings[j + 1] : 0.0);
    }
    for (int m = 0; m < ESCAPE_STEPS; m++) {
        double sum = 0.0, psi = m * step;
        for (int k = 0; k < ESCAPE_STEPS; k++)
            sum += fmax(0.0, cos((k + 0.5) * step - psi)) * across[k];
        cf->escape[m] = sum * step;
    }
    return true;
}

/* Finds the closed form of scene, whose triangles are s; false with the reason in why when it has
 * none. */
static bool classify_soup(const struct ao_scene *scene, const struct soup *s, float ao_distance, struct closed_form *cf,
                          char *why, size_t why_size)
{
    *cf = (struct closed_form){.kind = KIND_PLANE_SPHERE, .sphere = scene->sphere_count ? scene->spheres : NULL,
                               .plane = s->triangle_count > 0};
    if (ao_distance != INFINITY) {
        snprintf(why, why_size, "the closed forms need an infinite AO distance, not %g", (double)ao_distance);
        return false;
    }
    if (scene->sphere_count > 1) {
        snprintf(why, why_size, "%zu spheres (at most one: several spheres occlude one another)", scene->sphere_count);
        return false;
    }
    if (!cf->plane)
        return true;
    struct edge *edges = sorted_edges(s);
    if (!edges) {
        snprintf(why, why_size, "out of memory");
        return false;
    }
    size_t count = 3 * s->triangle_count;
    bool ok = true;
    if (!coplanar(s, &cf->up)) {
        /* Not a plane: a closed box around the eye is the one other case. */
        cf->kind = KIND_CLOSED_BOX;
        for (size_t i = 0; i < count && ok; i += run_length(edges, count, i))
            ok = run_length(edges, count, i) == 2;
        ok = ok && !cf->sphere && on_box_faces(s, scene->camera.eye);
        if (!ok)
            snprintf(why, why_size, "the triangles are neither one plane nor a closed box (watertight, "
                                    "on the faces of its bounding box, no sphere) around the camera");
    } else if (cf->sphere) {
        /* The sphere must not cross the plane, and the plane must reach far enough around it. */
        const struct ao_sphere *sp = cf->sphere;
        float h = ao_vec3_dot(cf->up, ao_vec3_sub(sp->center, s->corners[0]));
        if (h < 0.0f) {
            cf->up = ao_vec3_scale(cf->up, -1.0f);
            h = -h;
        }
        struct ao_vec3 foot = ao_vec3_sub(sp->center, ao_vec3_scale(cf->up, h));
        float reach = distance_to_outline(edges, count, foot) - sp->radius;
        float eps = reach > 0.0f ? atanf((h + sp->radius) / reach) : 0.5f * PI;
        cf->ground_error = fminf(1.0f, 2.0f * eps * eps);   /* AO lies in [0, rho] */
        cf->plane_point = s->corners[0];
        cf->axes = ao_basis_from_normal(cf->up);
        if (h < sp->radius * (1.0f - 1e-6f)) {
            snprintf(why, why_size, "the sphere cuts the plane (centre height %g < radius %g)", (double)h,
                     (double)sp->radius);
            ok = false;
        } else if (!plane_contains(s, cf->up, foot)) {
            snprintf(why, why_size, "the plane does not extend under the sphere");
            ok = false;
        } else if (!(cf->ground_error <= MAX_GROUND_ERROR)) {
            snprintf(why, why_size, "the ground is too small for the closed form's ground term under the sphere "
                                    "(sphere points would be off by up to %.2g, limit %.0e)",
                     (double)cf->ground_error, (double)MAX_GROUND_ERROR);
            ok = false;
        } else if (!tabulate_escape(cf, edges, count, foot)) {
            snprintf(why, why_size, "the ground's outline has more than %d edges along some direction from under "
                                    "the sphere", MAX_CROSSINGS);
            ok = false;
        }
    }
    free(edges);
    return ok;
}

/* Finds the scene's closed form from its placed triangles; false with the reason in why when it has
 * none. */
static bool classify(const struct ao_scene *scene, float ao_distance, struct closed_form *cf, char *why,
                     size_t why_size)
{
    if (scene->triangle_count > MAX_TRIANGLES) {
        snprintf(why, why_size, "%zu triangles placed (aoview-exact looks at %d at most)", scene->triangle_count,
                 MAX_TRIANGLES);
        return false;
    }
    struct soup soup = {malloc((3 * scene->triangle_count + 1) * sizeof *soup.corners), 0};
    if (!soup.corners) {
        snprintf(why, why_size, "out of memory");
        return false;
    }
    for (size_t i = 0; i < scene->instance_count; i++) {
        size_t count = scene->meshes[scene->instances[i].mesh].triangle_count;
        for (size_t t = 0; t < count; t++)
            ao_scene_triangle(scene, i, t, &soup.corners[3 * soup.triangle_count++]);
    }
    bool ok = classify_soup(scene, &soup, ao_distance, cf, why, why_size);
    free(soup.corners);
    return ok;
}

/* The share of a sphere point's cosine-weighted hemisphere that passes below the plane's horizon
 * off the finite ground: (z / pi) |n_h| G(phi_n), G interpolated in its table (see above). */
static double ground_escape(const struct closed_form *cf, const struct ao_surface *s)
{
    double z = ao_vec3_dot(ao_vec3_sub(s->position, cf->plane_point), cf->up);
    double nx = ao_vec3_dot(s->ns, cf->axes.t), ny = ao_vec3_dot(s->ns, cf->axes.b), len = hypot(nx, ny);
    if (!(len > 0.0 && z > 0.0))
        return 0.0;
    double at = atan2(ny, nx) / (2.0 * (double)PI) * ESCAPE_STEPS;
    at = at < 0.0 ? at + ESCAPE_STEPS : at;
    int k = (int)at % ESCAPE_STEPS;
    double w = at - floor(at), g = (1.0 - w) * cf->escape[k] + w * cf->escape[(k + 1) % ESCAPE_STEPS];
    return z / (double)PI * len * g;
}

/* The exact AO of the surface an eye ray found. */
static struct ao_vec3 exact_value(const struct closed_form *cf, const struct ao_surface *s, bool sphere_hit)
{
    if (cf->kind == KIND_CLOSED_BOX)
        return ao_vec3_make(0, 0, 0);
    const struct ao_sphere *sp = cf->sphere;
    double factor = 1.0;
    if (sphere_hit) {
        /* The sphere seen from inside is closed; from outside, the plane hides (1 - n.N)/2. */
        if (ao_vec3_dot(s->ng, ao_vec3_sub(s->position, sp->center)) < 0.0f)
            factor = 0.0;
        else if (cf->plane)
            factor = 0.5 * (1.0 + (double)ao_vec3_dot(s->ns, cf->up)) + ground_escape(cf, s);
    } else if (sp) {
        /* A plane point on the sphere's side sees the sphere's disc: r^2 h / d^3. */
        struct ao_vec3 to_center = ao_vec3_sub(sp->center, s->position);
        double h = ao_vec3_dot(to_center, s->ng), d = ao_vec3_length(to_center), r = sp->radius;
        if (h > 0.0)
            factor = 1.0 - r * r * h / (d * d * d);
    }
    return ao_vec3_scale(s->albedo, (float)factor);
}

/* Fills rgb (top row first) with the mean closed form over grid x grid sub-pixel cell centres of
 * each pixel (the centre alone when grid is 0), tracing eye rays 16 at a time. */
static void render(const struct ao_scene *scene, const struct ao_tracer *tracer, const struct closed_form *cf,
                   const struct ao_view *view, int grid, float *rgb)
{
    int cells = grid ? grid * grid : 1;
    for (int j = 0; j < view->height; j++)
        for (int i = 0; i < view->width; i++) {
            double sum[3] = {0, 0, 0};
            for (int first = 0; first < cells; first += AO_PACKET_SIZE) {
                struct ao_packet eye = {.count = cells - first < AO_PACKET_SIZE ? cells - first : AO_PACKET_SIZE};
                struct ao_hit hits[AO_PACKET_SIZE];
                for (int k = 0; k < eye.count; k++) {
                    int c = first + k;
                    float u = grid ? ((float)(c % grid) + 0.5f) / (float)grid : 0.5f;
                    float v = grid ? ((float)(c / grid) + 0.5f) / (float)grid : 0.5f;
                    struct ao_vec3 d = ao_camera_ray(view, (float)i + u, (float)j + v);
                    eye.org_x[k] = view->eye.x;
                    eye.org_y[k] = view->eye.y;
                    eye.org_z[k] = view->eye.z;
                    eye.dir_x[k] = d.x;
                    eye.dir_y[k] = d.y;
                    eye.dir_z[k] = d.z;
                    eye.tfar[k] = INFINITY;
                }
                ao_tracer_intersect(tracer, &eye, hits);
                for (int k = 0; k < eye.count; k++) {
                    struct ao_vec3 value = scene->background;
                    if (hits[k].t != INFINITY) {
                        struct ao_surface s;
                        struct ao_vec3 d = ao_vec3_make(eye.dir_x[k], eye.dir_y[k], eye.dir_z[k]);
                        ao_surface_from_hit(scene, AO_SHADING_PHONG, view->eye, d, &hits[k], &s);
                        value = exact_value(cf, &s, hits[k].sphere);
                    }
                    sum[0] += value.x;
                    sum[1] += value.y;
                    sum[2] += value.z;
                }
            }
            for (int c = 0; c < 3; c++)
                rgb[3 * ((size_t)j * (size_t)view->width + (size_t)i) + (size_t)c] = (float)(sum[c] / cells);
        }
}

bool ao_exact_render(const struct ao_scene *scene, const struct ao_tracer *tracer, float ao_distance, int width,
                     int height, int grid, float *rgb, struct ao_exact_facts *facts, char *why, size_t why_size)
{
    struct closed_form *cf = malloc(sizeof *cf);
    if (!cf) {
        snprintf(why, why_size, "out of memory");
        return false;
    }
    struct ao_view view;
    char reason[256];
    bool ok = classify(scene, ao_distance, cf, reason, sizeof reason);
    if (!ok)
        snprintf(why, why_size, "no closed form: %s", reason);
    if (ok && !(ok = ao_camera_view(&scene->camera, width, height, &view)))
        snprintf(why, why_size, "the camera cannot form an image");
    if (ok) {
        render(scene, tracer, cf, &view, grid, rgb);
        facts->kind = cf->kind == KIND_CLOSED_BOX ? "closed box"
                      : cf->sphere && cf->plane   ? "sphere over a plane"
                      : cf->sphere                ? "sphere alone"
                                                  : "open plane";
        facts->ground_error = cf->sphere && cf->plane ? cf->ground_error : NAN;
    }
    free(cf);
    return ok;
}
