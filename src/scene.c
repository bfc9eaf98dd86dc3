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

static const float PI = 3.14159265358979323846f;
static const float DEFAULT_ALBEDO = 0.8f;

/* Where the parser is, for "file:line: message" reports. */
struct cursor {
    const char *path;
    int line;
    char *tokens[MAX_TOKENS];
    int count;
    int next;
};

static bool fail(const struct cursor *c, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "%s:%d: ", c->path, c->line);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    return false;
}

/* ---- value parsing ---- */

static bool is_number(const char *s)
{
    char *end;
    strtod(s, &end);
    return end != s && *end == '\0';
}

/* Reads 1 to MAX_VALUES numbers after key into v; returns how many, or 0 after reporting. */
static int numbers(struct cursor *c, const char *key, float *v, int min, int max)
{
    int n = 0;
    while (c->next < c->count && n < max && is_number(c->tokens[c->next])) {
        double d = strtod(c->tokens[c->next++], NULL);
        if (!isfinite(d) || fabs(d) > 3.0e38) {
            fail(c, "'%s': value '%s' is not a finite number", key, c->tokens[c->next - 1]);
            return 0;
        }
        v[n++] = (float)d;
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

static bool vector(struct cursor *c, const char *key, struct ao_vec3 *out)
{
    float v[3];
    if (!numbers(c, key, v, 3, 3))
        return false;
    *out = ao_vec3_make(v[0], v[1], v[2]);
    return true;
}

static bool scalar(struct cursor *c, const char *key, float *out)
{
    return numbers(c, key, out, 1, 1) == 1;
}

/* One number or three: a grey level or an RGB triple. */
static bool triple(struct cursor *c, const char *key, struct ao_vec3 *out)
{
    float v[3];
    int n = numbers(c, key, v, 1, 3);
    if (n == 2)
        return fail(c, "'%s': expected 1 or 3 numbers, got 2", key);
    if (n == 0)
        return false;
    *out = n == 1 ? ao_vec3_make(v[0], v[0], v[0]) : ao_vec3_make(v[0], v[1], v[2]);
    return true;
}

static bool albedo(struct cursor *c, struct ao_vec3 *out)
{
    if (!triple(c, "albedo", out))
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

static bool add_albedo(struct ao_scene *s, struct ao_vec3 rho, uint32_t *index)
{
    if (!resize(&s->albedos, s->albedo_count + 1, sizeof *s->albedos))
        return false;
    s->albedos[s->albedo_count] = rho;
    *index = (uint32_t)s->albedo_count++;
    return true;
}

/* Appends world-space vertices and triangles whose indices count from 0. */
static bool add_triangles(struct ao_scene *s, const struct ao_vec3 *positions,
                          const struct ao_vec3 *normals, size_t vertex_count,
                          const uint32_t *indices, size_t triangle_count, uint32_t albedo)
{
    size_t base = s->vertex_count, first = s->triangle_count;
    if (vertex_count > UINT32_MAX - base || triangle_count > UINT32_MAX - first ||
        !resize(&s->positions, base + vertex_count, sizeof *s->positions) ||
        !resize(&s->normals, base + vertex_count, sizeof *s->normals) ||
        !resize(&s->indices, first + triangle_count, 3 * sizeof *s->indices) ||
        !resize(&s->triangle_albedo, first + triangle_count, sizeof *s->triangle_albedo))
        return false;
    memcpy(s->positions + base, positions, vertex_count * sizeof *positions);
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

/* ---- statements ---- */

/* Scale, then rotation about a unit axis, then translation (SPEC.md's order). */
struct transform {
    struct ao_vec3 scale, axis, translate;
    float cos_angle, sin_angle;
};

/* Rodrigues' rotation of v about t->axis. */
static struct ao_vec3 rotate(const struct transform *t, struct ao_vec3 v)
{
    struct ao_vec3 k = t->axis;
    struct ao_vec3 r = ao_vec3_scale(v, t->cos_angle);
    r = ao_vec3_add(r, ao_vec3_scale(ao_vec3_cross(k, v), t->sin_angle));
    return ao_vec3_add(r, ao_vec3_scale(k, ao_vec3_dot(k, v) * (1.0f - t->cos_angle)));
}

/* Normals take the inverse transpose of the scale (1/s per axis), then the rotation. */
static void transform_mesh(struct ao_mesh *m, const struct transform *t)
{
    struct ao_vec3 inv = ao_vec3_make(1.0f / t->scale.x, 1.0f / t->scale.y, 1.0f / t->scale.z);
    for (size_t i = 0; i < m->vertex_count; i++) {
        m->positions[i] = ao_vec3_add(rotate(t, ao_vec3_mul(m->positions[i], t->scale)), t->translate);
        m->normals[i] = ao_vec3_normalize(rotate(t, ao_vec3_mul(m->normals[i], inv)));
    }
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

static bool parse_camera(struct cursor *c, struct ao_scene *s, bool *has_camera)
{
    static const char *const keys[] = {"eye", "target", "up", "fov", NULL};
    unsigned seen = 0;
    s->camera.up = ao_vec3_make(0, 1, 0);
    s->camera.fov = 40.0f;
    while (c->next < c->count) {
        int k;
        const char *key = next_key(c, keys, &seen, &k);
        if (!key)
            return false;
        bool ok = k == 0   ? vector(c, key, &s->camera.eye)
                  : k == 1 ? vector(c, key, &s->camera.target)
                  : k == 2 ? vector(c, key, &s->camera.up)
                           : scalar(c, key, &s->camera.fov);
        if (!ok)
            return false;
    }
    struct ao_view view;
    if (!require(c, seen, keys, 3u))
        return false;
    if (!(s->camera.fov > 0.0f && s->camera.fov < 180.0f))
        return fail(c, "'fov' must lie strictly between 0 and 180 degrees");
    if (!ao_camera_view(&s->camera, 1, 1, &view))
        return fail(c, "camera: eye equals target or up is parallel to the view direction");
    *has_camera = true;
    return true;
}

static bool parse_image(struct cursor *c, struct ao_scene *s)
{
    float v[2];
    if (numbers(c, "image", v, 2, 2) != 2)
        return false;
    if (v[0] != floorf(v[0]) || v[1] != floorf(v[1]) || v[0] < 1 || v[1] < 1 ||
        v[0] > AO_IMAGE_MAX_SIDE || v[1] > AO_IMAGE_MAX_SIDE || (double)v[0] * v[1] > AO_IMAGE_MAX_PIXELS)
        return fail(c, "'image': expected width and height, whole numbers from 1 to %d with at most "
                       "%d pixels", AO_IMAGE_MAX_SIDE, AO_IMAGE_MAX_PIXELS);
    s->width = (int)v[0];
    s->height = (int)v[1];
    return true;
}

static bool parse_sphere(struct cursor *c, struct ao_scene *s)
{
    static const char *const keys[] = {"center", "radius", "albedo", NULL};
    unsigned seen = 0;
    struct ao_sphere sp = {.albedo = ao_vec3_make(DEFAULT_ALBEDO, DEFAULT_ALBEDO, DEFAULT_ALBEDO)};
    while (c->next < c->count) {
        int k;
        const char *key = next_key(c, keys, &seen, &k);
        if (!key)
            return false;
        bool ok = k == 0 ? vector(c, key, &sp.center) : k == 1 ? scalar(c, key, &sp.radius) : albedo(c, &sp.albedo);
        if (!ok)
            return false;
    }
    if (!require(c, seen, keys, 3u))
        return false;
    if (!(sp.radius > 0.0f))
        return fail(c, "'radius' must be positive");
    if (!resize(&s->spheres, s->sphere_count + 1, sizeof *s->spheres))
        return fail(c, "out of memory");
    s->spheres[s->sphere_count++] = sp;
    return true;
}

static bool parse_quad(struct cursor *c, struct ao_scene *s)
{
    static const char *const keys[] = {"corner", "edge1", "edge2", "albedo", NULL};
    unsigned seen = 0;
    struct ao_vec3 corner = {0}, e1 = {0}, e2 = {0}, rho = ao_vec3_make(DEFAULT_ALBEDO, DEFAULT_ALBEDO, DEFAULT_ALBEDO);
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
    struct ao_vec3 n = ao_vec3_cross(e1, e2);
    if (!(ao_vec3_length(n) > 0.0f) || !ao_vec3_is_finite(n))
        return fail(c, "quad: edge1 and edge2 span no area");
    n = ao_vec3_normalize(n);
    struct ao_vec3 p[4] = {corner, ao_vec3_add(corner, e1), ao_vec3_add(ao_vec3_add(corner, e1), e2),
                           ao_vec3_add(corner, e2)};
    struct ao_vec3 normals[4] = {n, n, n, n};
    static const uint32_t tris[6] = {0, 1, 2, 0, 2, 3};
    uint32_t a;
    if (!add_albedo(s, rho, &a) || !add_triangles(s, p, normals, 4, tris, 2, a))
        return fail(c, "out of memory");
    return true;
}

static bool parse_mesh(struct cursor *c, struct ao_scene *s)
{
    static const char *const keys[] = {"albedo", "scale", "rotate", "translate", NULL};
    if (c->next >= c->count)
        return fail(c, "'mesh' needs a file name");
    char path[4096];
    if (!resolve_path(c, c->tokens[c->next++], path, sizeof path))
        return false;
    unsigned seen = 0;
    struct ao_vec3 rho = ao_vec3_make(DEFAULT_ALBEDO, DEFAULT_ALBEDO, DEFAULT_ALBEDO);
    struct transform t = {.scale = ao_vec3_make(1, 1, 1), .axis = ao_vec3_make(0, 1, 0), .cos_angle = 1};
    while (c->next < c->count) {
        int k;
        float r[4];
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
            t.axis = ao_vec3_normalize(ao_vec3_make(r[0], r[1], r[2]));
            if (!(ao_vec3_length(t.axis) > 0.0f))
                return fail(c, "'rotate': the axis must not be zero");
            t.cos_angle = cosf(r[3] * PI / 180.0f);
            t.sin_angle = sinf(r[3] * PI / 180.0f);
        }
        if (k == 3 && !vector(c, key, &t.translate))
            return false;
    }
    if (t.scale.x == 0.0f || t.scale.y == 0.0f || t.scale.z == 0.0f)
        return fail(c, "'scale' must not be zero");
    struct ao_mesh m = {0};
    if (!ao_mesh_load(&m, path))
        return false;
    transform_mesh(&m, &t);
    uint32_t a;
    bool ok = add_albedo(s, rho, &a) &&
              add_triangles(s, m.positions, m.normals, m.vertex_count, m.indices, m.triangle_count, a);
    s->degenerate_count += m.degenerate_count;
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

static bool parse_statement(struct cursor *c, struct ao_scene *s, bool *has_camera)
{
    const char *word = c->tokens[0];
    if (strcmp(word, "camera") == 0)
        return parse_camera(c, s, has_camera);
    if (strcmp(word, "image") == 0)
        return parse_image(c, s);
    if (strcmp(word, "sphere") == 0)
        return parse_sphere(c, s);
    if (strcmp(word, "quad") == 0)
        return parse_quad(c, s);
    if (strcmp(word, "mesh") == 0)
        return parse_mesh(c, s);
    if (strcmp(word, "background") == 0)
        return triple(c, word, &s->background) && (c->next == c->count || fail(c, "'background': expected 1 or 3 numbers"));
    if (strcmp(word, "ao-distance") == 0) {
        if (!scalar(c, word, &s->ao_distance))
            return false;
        return s->ao_distance > 0.0f || fail(c, "'ao-distance' must be positive");
    }
    return fail(c, "unknown keyword '%s'", word);
}

/* Bounding box of all geometry; false for an empty scene. */
static bool bounds(const struct ao_scene *s, struct ao_vec3 *lo, struct ao_vec3 *hi)
{
    *lo = ao_vec3_make(INFINITY, INFINITY, INFINITY);
    *hi = ao_vec3_make(-INFINITY, -INFINITY, -INFINITY);
    for (size_t i = 0; i < s->vertex_count; i++) {
        struct ao_vec3 p = s->positions[i];
        *lo = ao_vec3_make(fminf(lo->x, p.x), fminf(lo->y, p.y), fminf(lo->z, p.z));
        *hi = ao_vec3_make(fmaxf(hi->x, p.x), fmaxf(hi->y, p.y), fmaxf(hi->z, p.z));
    }
    for (size_t i = 0; i < s->sphere_count; i++) {
        struct ao_sphere sp = s->spheres[i];
        struct ao_vec3 r = ao_vec3_make(sp.radius, sp.radius, sp.radius);
        struct ao_vec3 a = ao_vec3_sub(sp.center, r), b = ao_vec3_add(sp.center, r);
        *lo = ao_vec3_make(fminf(lo->x, a.x), fminf(lo->y, a.y), fminf(lo->z, a.z));
        *hi = ao_vec3_make(fmaxf(hi->x, b.x), fmaxf(hi->y, b.y), fmaxf(hi->z, b.z));
    }
    return s->vertex_count + s->sphere_count > 0;
}

static void begin(struct ao_scene *s, const char *path)
{
    memset(s, 0, sizeof *s);
    const char *slash = strrchr(path, '/');
    snprintf(s->name, sizeof s->name, "%s", slash ? slash + 1 : path);
    s->ao_distance = INFINITY;
}

bool ao_scene_parse(struct ao_scene *scene, const char *text, const char *path)
{
    begin(scene, path);
    struct cursor c = {.path = path};
    bool has_camera = false, ok = true;
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
        ok = tokenize(&c, line) && (c.count == 0 || parse_statement(&c, scene, &has_camera));
    }
    struct ao_vec3 lo, hi;
    if (ok && !has_camera) {
        c.line = 0;
        if (bounds(scene, &lo, &hi))
            ao_camera_frame_box(&scene->camera, lo, hi);
        else
            ok = fail(&c, "no camera and nothing to frame: add a 'camera' line or some geometry");
    }
    if (!ok)
        ao_scene_finish(scene);
    return ok;
}

/* A bare mesh: the mesh itself, a large ground quad under it, a camera framed on the mesh. */
static bool load_bare_mesh(struct ao_scene *s, const char *path)
{
    begin(s, path);
    struct ao_mesh m = {0};
    if (!ao_mesh_load(&m, path))
        return false;
    uint32_t a;
    bool ok = add_albedo(s, ao_vec3_make(DEFAULT_ALBEDO, DEFAULT_ALBEDO, DEFAULT_ALBEDO), &a) &&
              add_triangles(s, m.positions, m.normals, m.vertex_count, m.indices, m.triangle_count, a);
    s->degenerate_count = m.degenerate_count;
    ao_mesh_finish(&m);
    struct ao_vec3 lo, hi;
    if (ok && bounds(s, &lo, &hi)) {
        ao_camera_frame_box(&s->camera, lo, hi);
        float size = 25.0f * fmaxf(hi.x - lo.x, fmaxf(hi.y - lo.y, hi.z - lo.z));
        struct ao_vec3 mid = ao_vec3_scale(ao_vec3_add(lo, hi), 0.5f);
        struct ao_vec3 p[4] = {ao_vec3_make(mid.x - size, lo.y, mid.z - size), ao_vec3_make(mid.x - size, lo.y, mid.z + size),
                               ao_vec3_make(mid.x + size, lo.y, mid.z + size), ao_vec3_make(mid.x + size, lo.y, mid.z - size)};
        struct ao_vec3 up = ao_vec3_make(0, 1, 0), normals[4] = {up, up, up, up};
        static const uint32_t tris[6] = {0, 1, 2, 0, 2, 3};
        ok = add_albedo(s, ao_vec3_make(0.5f, 0.5f, 0.5f), &a) && add_triangles(s, p, normals, 4, tris, 2, a);
    }
    if (!ok) {
        fprintf(stderr, "%s: out of memory\n", path);
        ao_scene_finish(s);
    }
    return ok;
}

bool ao_scene_load(struct ao_scene *scene, const char *path)
{
    memset(scene, 0, sizeof *scene);
    if (ao_mesh_is_mesh_path(path))
        return load_bare_mesh(scene, path);
    char *text;
    size_t got;
    if (!ao_file_read(path, &text, &got))
        return false;
    if (strlen(text) != got) {
        fprintf(stderr, "%s: not a text file (it contains a NUL byte)\n", path);
        free(text);
        return false;
    }
    bool ok = ao_scene_parse(scene, text, path);
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
