/* Scene files and bare meshes; see scene.h and SPEC.md's "Scene file". */
#include "scene.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "file.h"
#include "image.h"
#include "mesh.h"

enum { MAX_TOKENS = 64, MAX_LINE = 4096, MAX_VALUES = 3 };

static const double PI = 3.14159265358979323846;
static const float DEFAULT_ALBEDO = 0.8f;

/* Where the parser is, for "file:line: message" reports. */
struct cursor {
    const char *path;
    int line;
    char *tokens[MAX_TOKENS];
    int count;
    int next;
};

/* Reports "path:line: message" (or "path: message" at line 0) as one line; returns false. */
static bool fail(const struct cursor *c, const char *fmt, ...)
{
    char message[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(message, sizeof message, fmt, ap);
    va_end(ap);
    if (c->line)
        ao_file_report("%s:%d: %s", c->path, c->line, message);
    else
        ao_file_report("%s: %s", c->path, message);
    return false;
}

/* ---- value parsing ---- */

static bool is_number(const char *s)
{
    char *end;
    strtod(s, &end);
    return end != s && *end == '\0';
}

/* Reads 1 to MAX_VALUES numbers after key into v; returns how many, or 0 after reporting. Every
 * value must also be finite as a float, which the geometry becomes. */
static int numbers(struct cursor *c, const char *key, double *v, int min, int max)
{
    int n = 0;
    while (c->next < c->count && n < max && is_number(c->tokens[c->next])) {
        double d = strtod(c->tokens[c->next++], NULL);
        if (!isfinite(d) || fabs(d) > 3.0e38) {
            fail(c, "'%s': value '%s' is not a finite number", key, c->tokens[c->next - 1]);
            return 0;
        }
        v[n++] = d;
    }
    if (n < min) {
        if (c->next < c->count && !is_number(c->tokens[c->next]))
            fail(c, "'%s': expected a number, got '%s'", key, c->tokens[c->next]);
        else
            fail(c, "'%s': expected %d number%s", key, min, min == 1 ? "" : "s");
        return 0;
    }
    return n;
}

/* A point or direction in double precision: scene coordinates until the scene is placed. */
struct dvec {
    double x, y, z;
};

static struct dvec dvec_make(double x, double y, double z)
{
    struct dvec v = {x, y, z};
    return v;
}

static struct dvec dvec_add(struct dvec a, struct dvec b)
{
    return dvec_make(a.x + b.x, a.y + b.y, a.z + b.z);
}

static struct dvec dvec_sub(struct dvec a, struct dvec b)
{
    return dvec_make(a.x - b.x, a.y - b.y, a.z - b.z);
}

static struct dvec dvec_scale(struct dvec a, double s)
{
    return dvec_make(a.x * s, a.y * s, a.z * s);
}

static struct dvec dvec_cross(struct dvec a, struct dvec b)
{
    return dvec_make(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

static double dvec_dot(struct dvec a, struct dvec b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

static struct dvec dvec_of(struct ao_vec3 v)
{
    return dvec_make(v.x, v.y, v.z);
}

/* The unit vector along v into *out; false when v is zero or not finite. Divided first by its
 * largest component, so that no square overflows or vanishes. */
static bool unit(struct dvec v, struct dvec *out)
{
    double big = fmax(fabs(v.x), fmax(fabs(v.y), fabs(v.z)));
    if (!(big > 0.0) || !isfinite(v.x) || !isfinite(v.y) || !isfinite(v.z))
        return false;
    v = dvec_scale(v, 1.0 / big);
    *out = dvec_scale(v, 1.0 / sqrt(dvec_dot(v, v)));
    return true;
}

/* v narrowed to float. */
static struct ao_vec3 narrow(struct dvec v)
{
    return ao_vec3_make((float)v.x, (float)v.y, (float)v.z);
}

static bool vector(struct cursor *c, const char *key, struct dvec *out)
{
    double v[3];
    if (!numbers(c, key, v, 3, 3))
        return false;
    *out = dvec_make(v[0], v[1], v[2]);
    return true;
}

static bool scalar(struct cursor *c, const char *key, double *out)
{
    return numbers(c, key, out, 1, 1) == 1;
}

/* One number or three: a grey level or an RGB triple. */
static bool triple(struct cursor *c, const char *key, struct dvec *out)
{
    double v[3];
    int n = numbers(c, key, v, 1, 3);
    if (n == 2)
        return fail(c, "'%s': expected 1 or 3 numbers, got 2", key);
    if (n == 0)
        return false;
    *out = n == 1 ? dvec_make(v[0], v[0], v[0]) : dvec_make(v[0], v[1], v[2]);
    return true;
}

/* triple() narrowed to float, for colours. */
static bool colour(struct cursor *c, const char *key, struct ao_vec3 *out)
{
    struct dvec v = {0};
    if (!triple(c, key, &v))
        return false;
    *out = narrow(v);
    return true;
}

static bool albedo(struct cursor *c, struct ao_vec3 *out)
{
    if (!colour(c, "albedo", out))
        return false;
    if (out->x < 0 || out->x > 1 || out->y < 0 || out->y > 1 || out->z < 0 || out->z > 1)
        return fail(c, "'albedo': values must lie in [0, 1]");
    return true;
}

/* Takes the next key of a statement; reports duplicates through the seen mask. */
static const char *next_key(struct cursor *c, const char *const *keys, unsigned *seen, int *which)
{
    const char *key = c->tokens[c->next++];
    for (int k = 0; keys[k]; k++) {
        if (strcmp(key, keys[k]) == 0) {
            if (*seen & (1u << k)) {
                fail(c, "'%s' given twice", key);
                return NULL;
            }
            *seen |= 1u << k;
            *which = k;
            return key;
        }
    }
    fail(c, "unknown key '%s' for '%s'", key, c->tokens[0]);
    return NULL;
}

static bool require(const struct cursor *c, unsigned seen, const char *const *keys, unsigned needed)
{
    for (int k = 0; keys[k]; k++)
        if ((needed & (1u << k)) && !(seen & (1u << k)))
            return fail(c, "'%s' needs '%s'", c->tokens[0], keys[k]);
    return true;
}

/* ---- growing the scene's arrays ---- */

/* Resizes *array to count elements of size bytes; false when that overflows or memory is short. */
static bool resize(void *array, size_t count, size_t size)
{
    void **slot = array;
    if (count > SIZE_MAX / size)
        return false;
    void *p = realloc(*slot, count * size);
    if (!p)
        return false;
    *slot = p;
    return true;
}

/* The scene's coordinates while it is read, in double precision and world space; ao_scene's float
 * positions, sphere centres and camera are filled from them once the whole scene is known
 * (place()). */
struct world {
    struct dvec *positions;       /* parallel to scene->normals */
    struct dvec *sphere_centers;  /* parallel to scene->spheres */
    struct dvec eye, target;      /* the camera's, when has_camera */
    bool has_camera;
    int camera_line;
    const char *extent_note;      /* what makes up the extent, for its message ("" in scene files) */
    struct ao_budget *budget;     /* charged for every element as it is added */
};

/* Charges an element of so many triangles (a sphere counts as one) and vertices to the budget;
 * false after reporting at the cursor's line. */
static bool charge(struct cursor *c, struct world *w, uint64_t triangles, uint64_t vertices, const char *what)
{
    uint64_t bytes = ao_budget_mesh(triangles, vertices);
    if (ao_budget_take(w->budget, bytes))
        return true;
    char why[200];
    ao_budget_explain(w->budget, bytes, why, sizeof why);
    return fail(c, "%s: %llu triangles and %llu vertices %s", what, (unsigned long long)triangles,
                (unsigned long long)vertices, why);
}

static bool add_albedo(struct ao_scene *s, struct ao_vec3 rho, uint32_t *index)
{
    if (!resize(&s->albedos, s->albedo_count + 1, sizeof *s->albedos))
        return false;
    s->albedos[s->albedo_count] = rho;
    *index = (uint32_t)s->albedo_count++;
    return true;
}

/* Appends world-space vertices and triangles whose indices count from 0. */
static bool add_triangles(struct ao_scene *s, struct world *w, const struct dvec *positions,
                          const struct ao_vec3 *normals, size_t vertex_count,
                          const uint32_t *indices, size_t triangle_count, uint32_t albedo)
{
    size_t base = s->vertex_count, first = s->triangle_count;
    if (vertex_count > UINT32_MAX - base || triangle_count > UINT32_MAX - first ||
        !resize(&w->positions, base + vertex_count, sizeof *w->positions) ||
        !resize(&s->normals, base + vertex_count, sizeof *s->normals) ||
        !resize(&s->indices, first + triangle_count, 3 * sizeof *s->indices) ||
        !resize(&s->triangle_albedo, first + triangle_count, sizeof *s->triangle_albedo))
        return false;
    memcpy(w->positions + base, positions, vertex_count * sizeof *positions);
    memcpy(s->normals + base, normals, vertex_count * sizeof *normals);
    for (size_t t = 0; t < triangle_count; t++) {
        for (int k = 0; k < 3; k++)
            s->indices[3 * (first + t) + k] = (uint32_t)base + indices[3 * t + k];
        s->triangle_albedo[first + t] = albedo;
    }
    s->vertex_count += vertex_count;
    s->triangle_count += triangle_count;
    return true;
}

/* Adds a mesh's note (mesh.h), if any, to the scene's notes as "name: note", after a "; " when
 * there are others; what does not fit is left out. */
static void add_note(struct ao_scene *s, const char *path, const char *note)
{
    if (!note[0])
        return;
    const char *slash = strrchr(path, '/');
    size_t used = strlen(s->notes);
    if (used + 4 < sizeof s->notes &&
        snprintf(s->notes + used, sizeof s->notes - used, "%s%s: %s", used ? "; " : "", slash ? slash + 1 : path,
                 note) < 0)
        s->notes[used] = '\0';
}

/* ---- statements ---- */

/* Scale, then rotation about a unit axis, then translation (SPEC.md's order), in double. */
struct transform {
    struct dvec scale, axis, translate;
    double cos_angle, sin_angle;
};

/* Rodrigues' rotation of v about t->axis. */
static struct dvec rotate(const struct transform *t, struct dvec v)
{
    struct dvec k = t->axis;
    struct dvec r = dvec_scale(v, t->cos_angle);
    r = dvec_add(r, dvec_scale(dvec_cross(k, v), t->sin_angle));
    return dvec_add(r, dvec_scale(k, dvec_dot(k, v) * (1.0 - t->cos_angle)));
}

/* The mesh's world positions into *out (malloc'd; NULL when memory is short); its normals
 * transformed in place: the inverse transpose of the scale (1/s per axis), then the rotation. The
 * inverse is taken as (sy sz, sx sz, sx sy) times the sign of sx sy sz, the same direction: no
 * 1/s overflows for a tiny scale (which would make the normals NaN). */
static bool transform_mesh(struct ao_mesh *m, const struct transform *t, struct dvec **out)
{
    *out = m->vertex_count ? malloc(m->vertex_count * sizeof **out) : NULL;
    if (m->vertex_count && !*out)
        return false;
    struct dvec s = t->scale;
    double sign = s.x * s.y * s.z < 0.0 ? -1.0 : 1.0;
    struct dvec inv = dvec_make(sign * s.y * s.z, sign * s.x * s.z, sign * s.x * s.y);
    for (size_t i = 0; i < m->vertex_count; i++) {
        struct dvec p = dvec_of(m->positions[i]), n = dvec_of(m->normals[i]);
        p = dvec_make(p.x * s.x, p.y * s.y, p.z * s.z);
        (*out)[i] = dvec_add(rotate(t, p), t->translate);
        struct dvec u = {0};
        unit(rotate(t, dvec_make(n.x * inv.x, n.y * inv.y, n.z * inv.z)), &u);   /* zero stays zero */
        m->normals[i] = narrow(u);
    }
    return true;
}

/* Joins a mesh path to the scene file's directory unless it is absolute. */
static bool resolve_path(const struct cursor *c, const char *name, char *out, size_t size)
{
    const char *slash = strrchr(c->path, '/');
    int dir = name[0] == '/' || !slash ? 0 : (int)(slash - c->path + 1);
    if (snprintf(out, size, "%.*s%s", dir, c->path, name) >= (int)size)
        return fail(c, "mesh path too long");
    return true;
}

/* A camera line; its eye and target stay in world space until place() checks the camera. */
static bool parse_camera(struct cursor *c, struct ao_scene *s, struct world *w)
{
    static const char *const keys[] = {"eye", "target", "up", "fov", NULL};
    unsigned seen = 0;
    struct dvec up = dvec_make(0, 1, 0);
    double fov = 40.0;
    while (c->next < c->count) {
        int k;
        const char *key = next_key(c, keys, &seen, &k);
        if (!key)
            return false;
        bool ok = k == 0   ? vector(c, key, &w->eye)
                  : k == 1 ? vector(c, key, &w->target)
                  : k == 2 ? vector(c, key, &up)
                           : scalar(c, key, &fov);
        if (!ok)
            return false;
    }
    if (!require(c, seen, keys, 3u))
        return false;
    if (!(fov > 0.0 && fov < 180.0))
        return fail(c, "'fov' must lie strictly between 0 and 180 degrees");
    s->camera.up = narrow(up);
    s->camera.fov = (float)fov;
    w->has_camera = true;
    w->camera_line = c->line;
    return true;
}

static bool parse_image(struct cursor *c, struct ao_scene *s)
{
    double v[2];
    if (numbers(c, "image", v, 2, 2) != 2)
        return false;
    if (v[0] != floor(v[0]) || v[1] != floor(v[1]) || v[0] < 1 || v[1] < 1 ||
        v[0] > AO_IMAGE_MAX_SIDE || v[1] > AO_IMAGE_MAX_SIDE || v[0] * v[1] > AO_IMAGE_MAX_PIXELS)
        return fail(c, "'image': expected width and height, whole numbers from 1 to %d with at most "
                       "%d pixels", AO_IMAGE_MAX_SIDE, AO_IMAGE_MAX_PIXELS);
    s->width = (int)v[0];
    s->height = (int)v[1];
    return true;
}

static bool parse_sphere(struct cursor *c, struct ao_scene *s, struct world *w)
{
    static const char *const keys[] = {"center", "radius", "albedo", NULL};
    unsigned seen = 0;
    struct ao_sphere sp = {.albedo = ao_vec3_make(DEFAULT_ALBEDO, DEFAULT_ALBEDO, DEFAULT_ALBEDO)};
    struct dvec center = {0};
    double radius = 0.0;
    while (c->next < c->count) {
        int k;
        const char *key = next_key(c, keys, &seen, &k);
        if (!key)
            return false;
        bool ok = k == 0 ? vector(c, key, &center) : k == 1 ? scalar(c, key, &radius) : albedo(c, &sp.albedo);
        if (!ok)
            return false;
    }
    if (!require(c, seen, keys, 3u))
        return false;
    sp.radius = (float)radius;
    if (!(sp.radius > 0.0f))
        return fail(c, "'radius' must be positive");
    if (!charge(c, w, 1, 0, "sphere"))
        return false;
    if (!resize(&s->spheres, s->sphere_count + 1, sizeof *s->spheres) ||
        !resize(&w->sphere_centers, s->sphere_count + 1, sizeof *w->sphere_centers))
        return fail(c, "out of memory");
    w->sphere_centers[s->sphere_count] = center;
    s->spheres[s->sphere_count++] = sp;
    return true;
}

static bool parse_quad(struct cursor *c, struct ao_scene *s, struct world *w)
{
    static const char *const keys[] = {"corner", "edge1", "edge2", "albedo", NULL};
    unsigned seen = 0;
    struct dvec corner = {0}, e1 = {0}, e2 = {0};
    struct ao_vec3 rho = ao_vec3_make(DEFAULT_ALBEDO, DEFAULT_ALBEDO, DEFAULT_ALBEDO);
    while (c->next < c->count) {
        int k;
        const char *key = next_key(c, keys, &seen, &k);
        if (!key)
            return false;
        bool ok = k == 0   ? vector(c, key, &corner)
                  : k == 1 ? vector(c, key, &e1)
                  : k == 2 ? vector(c, key, &e2)
                           : albedo(c, &rho);
        if (!ok)
            return false;
    }
    if (!require(c, seen, keys, 7u))
        return false;
    struct ao_vec3 n = narrow(dvec_cross(e1, e2));
    if (!(ao_vec3_length(n) > 0.0f) || !ao_vec3_is_finite(n))
        return fail(c, "quad: edge1 and edge2 span no area");
    n = ao_vec3_normalize(n);
    struct dvec p[4] = {corner, dvec_add(corner, e1), dvec_add(dvec_add(corner, e1), e2), dvec_add(corner, e2)};
    struct ao_vec3 normals[4] = {n, n, n, n};
    static const uint32_t tris[6] = {0, 1, 2, 0, 2, 3};
    uint32_t a;
    if (!charge(c, w, 2, 4, "quad"))
        return false;
    if (!add_albedo(s, rho, &a) || !add_triangles(s, w, p, normals, 4, tris, 2, a))
        return fail(c, "out of memory");
    return true;
}

static bool parse_mesh(struct cursor *c, struct ao_scene *s, struct world *w)
{
    static const char *const keys[] = {"albedo", "scale", "rotate", "translate", NULL};
    if (c->next >= c->count)
        return fail(c, "'mesh' needs a file name");
    char path[4096];
    if (!resolve_path(c, c->tokens[c->next++], path, sizeof path))
        return false;
    unsigned seen = 0;
    struct ao_vec3 rho = ao_vec3_make(DEFAULT_ALBEDO, DEFAULT_ALBEDO, DEFAULT_ALBEDO);
    struct transform t = {.scale = dvec_make(1, 1, 1), .axis = dvec_make(0, 1, 0), .cos_angle = 1};
    while (c->next < c->count) {
        int k;
        double r[4];
        const char *key = next_key(c, keys, &seen, &k);
        if (!key)
            return false;
        if (k == 0 && !albedo(c, &rho))
            return false;
        if (k == 1 && !triple(c, key, &t.scale))
            return false;
        if (k == 2) {
            if (numbers(c, key, r, 4, 4) != 4)
                return false;
            if (!unit(dvec_make(r[0], r[1], r[2]), &t.axis))
                return fail(c, "'rotate': the axis must not be zero");
            t.cos_angle = cos(r[3] * PI / 180.0);
            t.sin_angle = sin(r[3] * PI / 180.0);
        }
        if (k == 3 && !vector(c, key, &t.translate))
            return false;
    }
    if (t.scale.x == 0.0 || t.scale.y == 0.0 || t.scale.z == 0.0)
        return fail(c, "'scale' must not be zero");
    struct ao_mesh m = {0};
    if (!ao_mesh_load_budget(&m, path, w->budget))
        return false;
    if (!charge(c, w, m.triangle_count, m.vertex_count, path)) {
        ao_mesh_finish(&m);
        return false;
    }
    struct dvec *positions = NULL;
    uint32_t a;
    bool ok = transform_mesh(&m, &t, &positions) && add_albedo(s, rho, &a) &&
              add_triangles(s, w, positions, m.normals, m.vertex_count, m.indices, m.triangle_count, a);
    s->degenerate_count += m.degenerate_count;
    s->point_primitives += m.point_primitives;
    s->line_primitives += m.line_primitives;
    add_note(s, path, m.note);
    free(positions);
    ao_mesh_finish(&m);
    return ok || fail(c, "out of memory (or more than 2^32 vertices) adding '%s'", path);
}

/* ---- whole files ---- */

/* Splits a line into tokens in place, dropping a '#' comment; false when there are too many. */
static bool tokenize(struct cursor *c, char *line)
{
    char *hash = strchr(line, '#');
    if (hash)
        *hash = '\0';
    c->count = 0;
    c->next = 1;
    for (char *p = line; *p;) {
        while (*p == ' ' || *p == '\t' || *p == '\r')
            *p++ = '\0';
        if (!*p)
            break;
        if (c->count == MAX_TOKENS)
            return fail(c, "too many words on one line (at most %d)", MAX_TOKENS);
        c->tokens[c->count++] = p;
        while (*p && *p != ' ' && *p != '\t' && *p != '\r')
            p++;
    }
    return true;
}

static bool parse_statement(struct cursor *c, struct ao_scene *s, struct world *w)
{
    const char *word = c->tokens[0];
    if (strcmp(word, "camera") == 0)
        return parse_camera(c, s, w);
    if (strcmp(word, "image") == 0)
        return parse_image(c, s);
    if (strcmp(word, "sphere") == 0)
        return parse_sphere(c, s, w);
    if (strcmp(word, "quad") == 0)
        return parse_quad(c, s, w);
    if (strcmp(word, "mesh") == 0)
        return parse_mesh(c, s, w);
    if (strcmp(word, "background") == 0)
        return colour(c, word, &s->background) && (c->next == c->count || fail(c, "'background': expected 1 or 3 numbers"));
    if (strcmp(word, "ao-distance") == 0) {
        double d;
        if (!scalar(c, word, &d))
            return false;
        s->ao_distance = (float)d;
        return s->ao_distance > 0.0f || fail(c, "'ao-distance' must be positive");
    }
    return fail(c, "unknown keyword '%s'", word);
}

/* World-space bounding box of all geometry; false for an empty scene. */
static bool bounds(const struct ao_scene *s, const struct world *w, struct dvec *lo, struct dvec *hi)
{
    *lo = dvec_make(INFINITY, INFINITY, INFINITY);
    *hi = dvec_make(-INFINITY, -INFINITY, -INFINITY);
    for (size_t i = 0; i < s->vertex_count + s->sphere_count; i++) {
        bool vertex = i < s->vertex_count;
        struct dvec p = vertex ? w->positions[i] : w->sphere_centers[i - s->vertex_count];
        double r = vertex ? 0.0 : s->spheres[i - s->vertex_count].radius;
        *lo = dvec_make(fmin(lo->x, p.x - r), fmin(lo->y, p.y - r), fmin(lo->z, p.z - r));
        *hi = dvec_make(fmax(hi->x, p.x + r), fmax(hi->y, p.y + r), fmax(hi->z, p.z + r));
    }
    return s->vertex_count + s->sphere_count > 0;
}

/* The sizes of scene that the renderer draws as it would the same scene at size 1 (scene.h's
 * AO_SCENE_MIN_EXTENT and AO_SCENE_MAX_EXTENT; measured in docs/stability.md). It traces in single
 * precision with flush-to-zero on, so each product it forms must stay between 2^-126 (below, it
 * becomes 0) and 2^128 (above, infinite). With E the largest side of the box around the geometry,
 * eye and target, every local coordinate is at most E (place()'s origin is in the box), and:
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
 * The camera's eye and target are ray origins and directions: they belong to the box (Embree's
 * check, and the depth test's o), and ao_camera_view squares their distance, which must therefore
 * stay above 2^-63 (MIN_CAMERA_DISTANCE = 2^-60). Detail finer than the scene is not checked: a
 * triangle whose |Ng| is below 2^-63 (edges of about 3e-10) is shaded with the eye-facing normal
 * that stands in for degenerate ones, and a facet in a coordinate plane through the origin with
 * |Ng| below 2^-26 occludes itself, whatever the scene's size. */
static const double MIN_CAMERA_DISTANCE = 0x1p-60;

/* The largest side of the box lo..hi. */
static double largest_side(struct dvec lo, struct dvec hi)
{
    return fmax(hi.x - lo.x, fmax(hi.y - lo.y, hi.z - lo.z));
}

/* The box lo..hi grown to hold p. */
static void grow(struct dvec *lo, struct dvec *hi, struct dvec p)
{
    *lo = dvec_make(fmin(lo->x, p.x), fmin(lo->y, p.y), fmin(lo->z, p.z));
    *hi = dvec_make(fmax(hi->x, p.x), fmax(hi->y, p.y), fmax(hi->z, p.z));
}

/* Refuses a scene whose geometry (the box lo..hi, when any) or camera leaves the range derived
 * above, with one line naming the size; false after reporting. */
static bool check_range(const struct world *w, struct cursor *c, bool any, struct dvec lo, struct dvec hi)
{
    static const char range[] = "aoview renders scenes from %.3g to %.3g across (docs/stability.md)";
    char message[256];
    double size = any ? largest_side(lo, hi) : 0.0;
    c->line = 0;
    snprintf(message, sizeof message, range, AO_SCENE_MIN_EXTENT, AO_SCENE_MAX_EXTENT);
    if (any && !(size >= AO_SCENE_MIN_EXTENT && size <= AO_SCENE_MAX_EXTENT))
        return fail(c, "the scene is %.3g across%s; %s", size, w->extent_note, message);
    if (!w->has_camera)
        return true;
    c->line = w->camera_line;
    if (!any)
        lo = hi = w->eye;
    grow(&lo, &hi, w->eye);
    grow(&lo, &hi, w->target);
    if (!(largest_side(lo, hi) <= AO_SCENE_MAX_EXTENT))
        return fail(c, "camera: with it the scene is %.3g across; %s", largest_side(lo, hi), message);
    struct dvec d = dvec_sub(w->target, w->eye), along;
    double distance = unit(d, &along) ? dvec_dot(d, along) : 0.0;   /* |d|, no square to vanish */
    if (distance > 0.0 && distance < MIN_CAMERA_DISTANCE)
        return fail(c, "camera: eye and target are %.3g apart, closer than the %.3g aoview can aim by",
                    distance, MIN_CAMERA_DISTANCE);
    return true;
}

/* Moves the scene from world space into its local frame and narrows it to float: every position,
 * sphere centre and the camera become world - origin, with the origin at the bounding box's centre,
 * so that float precision follows the scene's size rather than its distance from (0, 0, 0). Where
 * the box holds (0, 0, 0) its coordinates are at most its size already (one bit worse than from
 * the centre) and the origin stays there, leaving such scenes exactly as written. A scene without
 * a camera line gets one framed on its box. False after reporting (the camera's line) or on
 * short memory. */
static bool place(struct ao_scene *s, struct world *w, struct cursor *c)
{
    struct dvec lo, hi, origin = {0};
    bool any = bounds(s, w, &lo, &hi);
    if (!check_range(w, c, any, lo, hi))
        return false;
    if (any && !(lo.x <= 0.0 && hi.x >= 0.0 && lo.y <= 0.0 && hi.y >= 0.0 && lo.z <= 0.0 && hi.z >= 0.0))
        origin = dvec_scale(dvec_add(lo, hi), 0.5);
    s->origin[0] = origin.x, s->origin[1] = origin.y, s->origin[2] = origin.z;
    if (s->vertex_count && !(s->positions = malloc(s->vertex_count * sizeof *s->positions))) {
        c->line = 0;
        return fail(c, "out of memory");
    }
    for (size_t i = 0; i < s->vertex_count; i++)
        s->positions[i] = narrow(dvec_sub(w->positions[i], origin));
    for (size_t i = 0; i < s->sphere_count; i++)
        s->spheres[i].center = narrow(dvec_sub(w->sphere_centers[i], origin));
    if (w->has_camera) {
        s->camera.eye = narrow(dvec_sub(w->eye, origin));
        s->camera.target = narrow(dvec_sub(w->target, origin));
        struct ao_view view;
        c->line = w->camera_line;
        if (!ao_camera_view(&s->camera, 1, 1, &view))
            return fail(c, "camera: eye equals target or up is parallel to the view direction");
        return true;
    }
    c->line = 0;
    if (!any)
        return fail(c, "no camera and nothing to frame: add a 'camera' line or some geometry");
    ao_camera_frame_box(&s->camera, narrow(dvec_sub(lo, origin)), narrow(dvec_sub(hi, origin)));
    return true;
}

static void begin(struct ao_scene *s, const char *path)
{
    memset(s, 0, sizeof *s);
    const char *slash = strrchr(path, '/');
    snprintf(s->name, sizeof s->name, "%s", slash ? slash + 1 : path);
    s->ao_distance = INFINITY;
}

/* ao_scene_parse charging budget. */
static bool parse_text(struct ao_scene *scene, const char *text, const char *path, struct ao_budget *budget)
{
    begin(scene, path);
    struct cursor c = {.path = path};
    struct world w = {.extent_note = "", .budget = budget};
    bool ok = true;
    char line[MAX_LINE + 2];
    for (const char *p = text; ok && *p;) {
        size_t len = strcspn(p, "\n");
        c.line++;
        if (len > MAX_LINE) {
            ok = fail(&c, "line longer than %d characters", MAX_LINE);
            break;
        }
        memcpy(line, p, len);
        line[len] = '\0';
        p += len + (p[len] == '\n');
        ok = tokenize(&c, line) && (c.count == 0 || parse_statement(&c, scene, &w));
    }
    ok = ok && place(scene, &w, &c);
    free(w.positions);
    free(w.sphere_centers);
    if (!ok)
        ao_scene_finish(scene);
    return ok;
}

bool ao_scene_parse(struct ao_scene *scene, const char *text, const char *path)
{
    struct ao_budget budget = {AO_BUDGET_DEFAULT, 0};
    return parse_text(scene, text, path, &budget);
}

/* The ground quad added under a bare mesh whose box is lo..hi: 50 times as wide as the mesh's
 * largest side E, AO_SCENE_GROUND_GAP E below its lowest point. At the lowest point itself (as
 * before) a flat model (a floor, a terrain tile, a sheet) lay within rounding of the ground, and
 * eye rays hit one or the other at random: speckle from 0.5 to 0.8 over the whole model. The gap
 * must clear the rounding of hit points (about 2^-23 of the camera distance, a few E) and stay
 * below what a contact shadow shows. Measured (docs/formats.md): the flat 2 x 2 square at 160x120,
 * 64 spp, still speckled at a gap of 1e-7 E (585 of its 1859 pixels below 0.9 rho) and was clean
 * from 1e-6 E up, on both tracers; the bare bunny at 640x480, 256 spp, against the gap 0, darkened
 * its contact shadow (the ground pixels below 0.9 rho) by 0.03 % at 1e-4 E, within the noise of that
 * mean, and by 0.3 % at 1e-3 E, 3 % at 1e-2 E. 1e-4 E keeps a factor 100 on either side. */
static bool add_ground(struct ao_scene *s, struct world *w, struct dvec lo, struct dvec hi)
{
    struct dvec mid = dvec_scale(dvec_add(lo, hi), 0.5);
    double extent = largest_side(lo, hi), size = 25.0 * extent, y = lo.y - AO_SCENE_GROUND_GAP * extent;
    struct dvec p[4] = {dvec_make(mid.x - size, y, mid.z - size), dvec_make(mid.x - size, y, mid.z + size),
                        dvec_make(mid.x + size, y, mid.z + size), dvec_make(mid.x + size, y, mid.z - size)};
    struct ao_vec3 up = ao_vec3_make(0, 1, 0), normals[4] = {up, up, up, up};
    static const uint32_t tris[6] = {0, 1, 2, 0, 2, 3};
    uint32_t a;
    return add_albedo(s, ao_vec3_make(0.5f, 0.5f, 0.5f), &a) && add_triangles(s, w, p, normals, 4, tris, 2, a);
}

/* A bare mesh: the mesh itself, with ground a large ground quad under it, a camera framed on the
 * mesh. */
static bool load_bare_mesh(struct ao_scene *s, const char *path, struct ao_budget *budget, bool ground)
{
    begin(s, path);
    struct ao_mesh m = {0};
    struct world w = {.extent_note = ground ? " (the mesh with its ground quad, 50 times as wide as the mesh)" : "",
                      .budget = budget};
    struct cursor c = {.path = path};
    if (!ao_mesh_load_budget(&m, path, budget))
        return false;
    if (!charge(&c, &w, m.triangle_count + 2 * ground, m.vertex_count + 4 * ground,
                ground ? "the mesh and its ground" : "the mesh")) {
        ao_mesh_finish(&m);
        return false;
    }
    struct transform identity = {.scale = dvec_make(1, 1, 1), .axis = dvec_make(0, 1, 0), .cos_angle = 1};
    struct dvec *positions = NULL, lo, hi;
    uint32_t a;
    bool ok = transform_mesh(&m, &identity, &positions) &&
              add_albedo(s, ao_vec3_make(DEFAULT_ALBEDO, DEFAULT_ALBEDO, DEFAULT_ALBEDO), &a) &&
              add_triangles(s, &w, positions, m.normals, m.vertex_count, m.indices, m.triangle_count, a);
    s->degenerate_count = m.degenerate_count;
    s->point_primitives = m.point_primitives;
    s->line_primitives = m.line_primitives;
    add_note(s, path, m.note);
    free(positions);
    ao_mesh_finish(&m);
    if (ok && bounds(s, &w, &lo, &hi)) {
        /* The camera framed on the mesh about its centre, then kept in world space. */
        struct dvec mid = dvec_scale(dvec_add(lo, hi), 0.5);
        ao_camera_frame_box(&s->camera, narrow(dvec_sub(lo, mid)), narrow(dvec_sub(hi, mid)));
        w.eye = dvec_add(mid, dvec_of(s->camera.eye));
        w.target = dvec_add(mid, dvec_of(s->camera.target));
        w.has_camera = true;
        ok = !ground || add_ground(s, &w, lo, hi);
    }
    if (!ok)
        ao_file_report("%s: out of memory", path);
    ok = ok && place(s, &w, &c);
    free(w.positions);
    if (!ok)
        ao_scene_finish(s);
    return ok;
}

bool ao_scene_load(struct ao_scene *scene, const char *path)
{
    return ao_scene_load_budget(scene, path, AO_BUDGET_DEFAULT);
}

bool ao_scene_load_budget(struct ao_scene *scene, const char *path, uint64_t budget_bytes)
{
    struct ao_scene_options options = {.budget = budget_bytes, .ground = true};
    return ao_scene_load_with(scene, path, &options);
}

bool ao_scene_load_with(struct ao_scene *scene, const char *path, const struct ao_scene_options *options)
{
    struct ao_budget budget = {options->budget, 0};
    memset(scene, 0, sizeof *scene);
    if (ao_mesh_is_mesh_path(path))
        return load_bare_mesh(scene, path, &budget, options->ground);
    char *text;
    size_t got;
    if (!ao_file_read_budget(path, &budget, &text, &got))
        return false;
    bool ok = strlen(text) == got;
    if (!ok)
        ao_file_report("%s: not a text file (it contains a NUL byte)", path);
    ok = ok && parse_text(scene, text, path, &budget);
    free(text);
    return ok;
}

void ao_scene_finish(struct ao_scene *scene)
{
    free(scene->spheres);
    free(scene->positions);
    free(scene->normals);
    free(scene->indices);
    free(scene->triangle_albedo);
    free(scene->albedos);
    memset(scene, 0, sizeof *scene);
}
