/* The statements of a scene file; see scene_parse.h, and docs/contract.md for the format. */
#include "scene_parse.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "image_types.h"

enum { MAX_LINE = 4096, MAX_VALUES = 3 };

static const double PI = 3.14159265358979323846;

/* ---- values ---- */

static bool is_number(const char *s)
{
    char *end;
    strtod(s, &end);
    return end != s && *end == '\0';
}

/* Reads 1 to MAX_VALUES numbers after key into v; returns how many, or 0 after reporting. Every
 * value must also be finite as a float, which the geometry becomes. */
static int numbers(struct ao_cursor *c, const char *key, double *v, int min, int max)
{
    int n = 0;
    while (c->next < c->count && n < max && is_number(c->tokens[c->next])) {
        double d = strtod(c->tokens[c->next++], NULL);
        if (!isfinite(d) || fabs(d) > 3.0e38) {
            ao_cursor_fail(c, "'%s': value '%s' is not a finite number", key, c->tokens[c->next - 1]);
            return 0;
        }
        v[n++] = d;
    }
    if (n < min) {
        if (c->next < c->count && !is_number(c->tokens[c->next]))
            ao_cursor_fail(c, "'%s': expected a number, got '%s'", key, c->tokens[c->next]);
        else
            ao_cursor_fail(c, "'%s': expected %d number%s", key, min, min == 1 ? "" : "s");
        return 0;
    }
    return n;
}

static bool vector(struct ao_cursor *c, const char *key, struct ao_dvec3 *out)
{
    double v[3];
    if (!numbers(c, key, v, 3, 3))
        return false;
    *out = ao_dvec3_make(v[0], v[1], v[2]);
    return true;
}

static bool scalar(struct ao_cursor *c, const char *key, double *out)
{
    return numbers(c, key, out, 1, 1) == 1;
}

/* One number or three: a grey level or an RGB triple. */
static bool triple(struct ao_cursor *c, const char *key, struct ao_dvec3 *out)
{
    double v[3];
    int n = numbers(c, key, v, 1, 3);
    if (n == 2)
        return ao_cursor_fail(c, "'%s': expected 1 or 3 numbers, got 2", key);
    if (n == 0)
        return false;
    *out = n == 1 ? ao_dvec3_make(v[0], v[0], v[0]) : ao_dvec3_make(v[0], v[1], v[2]);
    return true;
}

/* triple() narrowed to float, for colours. */
static bool colour(struct ao_cursor *c, const char *key, struct ao_vec3 *out)
{
    struct ao_dvec3 v = {0};
    if (!triple(c, key, &v))
        return false;
    *out = ao_dvec3_narrow(v);
    return true;
}

/* A colour whose values must lie in [0, 1]: an albedo, or the background (brighter than an open
 * white surface it would be no sky, and it would scale the relative error that --target-error stops
 * at, e.g. 3e38 meets 1 % at once; below 0, an error column of inf). */
static bool unit_colour(struct ao_cursor *c, const char *key, struct ao_vec3 *out)
{
    if (!colour(c, key, out))
        return false;
    if (out->x < 0 || out->x > 1 || out->y < 0 || out->y > 1 || out->z < 0 || out->z > 1)
        return ao_cursor_fail(c, "'%s': values must lie in [0, 1]", key);
    return true;
}

static bool albedo(struct ao_cursor *c, struct ao_vec3 *out)
{
    return unit_colour(c, "albedo", out);
}

/* A crease angle: degrees from 0 to 180 (mesh.h). */
static bool crease_angle(struct ao_cursor *c, const char *key, double *out)
{
    if (!scalar(c, key, out))
        return false;
    return (*out >= 0.0 && *out <= 180.0) || ao_cursor_fail(c, "'%s': expected degrees from 0 to 180", key);
}

/* Takes the next key of a statement; reports duplicates through the seen mask. */
static const char *next_key(struct ao_cursor *c, const char *const *keys, unsigned *seen, int *which)
{
    const char *key = c->tokens[c->next++];
    for (int k = 0; keys[k]; k++) {
        if (strcmp(key, keys[k]) == 0) {
            if (*seen & (1u << k)) {
                ao_cursor_fail(c, "'%s' given twice", key);
                return NULL;
            }
            *seen |= 1u << k;
            *which = k;
            return key;
        }
    }
    ao_cursor_fail(c, "unknown key '%s' for '%s'", key, c->tokens[0]);
    return NULL;
}

static bool require(const struct ao_cursor *c, unsigned seen, const char *const *keys, unsigned needed)
{
    for (int k = 0; keys[k]; k++)
        if ((needed & (1u << k)) && !(seen & (1u << k)))
            return ao_cursor_fail(c, "'%s' needs '%s'", c->tokens[0], keys[k]);
    return true;
}

/* ---- statements ---- */

/* Scale, then rotation about a unit axis, then translation (the scene format's order), in double. */
struct transform {
    struct ao_dvec3 scale, axis, translate;
    double cos_angle, sin_angle;
};

/* Rodrigues' rotation of v about t->axis. */
static struct ao_dvec3 rotate(const struct transform *t, struct ao_dvec3 v)
{
    struct ao_dvec3 k = t->axis;
    struct ao_dvec3 r = ao_dvec3_scale(v, t->cos_angle);
    r = ao_dvec3_add(r, ao_dvec3_scale(ao_dvec3_cross(k, v), t->sin_angle));
    return ao_dvec3_add(r, ao_dvec3_scale(k, ao_dvec3_dot(k, v) * (1.0 - t->cos_angle)));
}

/* The transform as an affine map: column j of L is the rotated axis j scaled by scale j. */
static struct ao_affine affine_of(const struct transform *t)
{
    struct ao_affine a;
    double s[3] = {t->scale.x, t->scale.y, t->scale.z};
    for (int j = 0; j < 3; j++) {
        struct ao_dvec3 e = ao_dvec3_make(j == 0 ? s[0] : 0.0, j == 1 ? s[1] : 0.0, j == 2 ? s[2] : 0.0);
        struct ao_dvec3 column = rotate(t, e);
        a.m[3 * j] = column.x, a.m[3 * j + 1] = column.y, a.m[3 * j + 2] = column.z;
    }
    a.m[9] = t->translate.x, a.m[10] = t->translate.y, a.m[11] = t->translate.z;
    return a;
}

/* Joins a mesh path to the scene file's directory unless it is absolute. */
static bool resolve_path(const struct ao_cursor *c, const char *name, char *out, size_t size)
{
    const char *slash = strrchr(c->path, '/');
    int dir = name[0] == '/' || !slash ? 0 : (int)(slash - c->path + 1);
    if (snprintf(out, size, "%.*s%s", dir, c->path, name) >= (int)size)
        return ao_cursor_fail(c, "mesh path too long");
    return true;
}

/* A camera line; its eye and target stay in world space until ao_world_place() checks the camera. */
static bool parse_camera(struct ao_cursor *c, struct ao_scene *s, struct ao_world *w)
{
    static const char *const keys[] = {"eye", "target", "up", "fov", NULL};
    unsigned seen = 0;
    struct ao_dvec3 up = ao_dvec3_make(0, 1, 0);
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
        return ao_cursor_fail(c, "'fov' must lie strictly between 0 and 180 degrees");
    s->camera.up = ao_dvec3_narrow(up);
    s->camera.fov = (float)fov;
    w->has_camera = true;
    w->camera_line = c->line;
    return true;
}

/* "image W H": the default size, whose buffers (accumulation, frames, a PNG's) the budget is charged
 * for unless the size is set elsewhere (--size): a 13-byte line asked for 3 GB. */
static bool parse_image(struct ao_cursor *c, struct ao_scene *s, struct ao_world *w)
{
    double v[2];
    if (numbers(c, "image", v, 2, 2) != 2)
        return false;
    if (v[0] != floor(v[0]) || v[1] != floor(v[1]) || v[0] < 1 || v[1] < 1 ||
        v[0] > AO_IMAGE_MAX_SIDE || v[1] > AO_IMAGE_MAX_SIDE || v[0] * v[1] > AO_IMAGE_MAX_PIXELS)
        return ao_cursor_fail(c, "'image': expected width and height, whole numbers from 1 to %d with at most "
                                 "%d pixels", AO_IMAGE_MAX_SIDE, AO_IMAGE_MAX_PIXELS);
    s->width = (int)v[0];
    s->height = (int)v[1];
    if (w->sized)
        return true;
    char what[96];
    snprintf(what, sizeof what, "'image' %dx%d: its buffers", s->width, s->height);
    ao_budget_give(w->budget, w->image_charge);   /* a line before it is replaced */
    w->image_charge = (uint64_t)s->width * (uint64_t)s->height * AO_BUDGET_PIXEL;
    if (ao_world_take(c, w, w->image_charge, what))
        return true;
    w->image_charge = 0;
    return false;
}

static bool parse_sphere(struct ao_cursor *c, struct ao_scene *s, struct ao_world *w)
{
    static const char *const keys[] = {"center", "radius", "albedo", NULL};
    unsigned seen = 0;
    struct ao_sphere sp = {.albedo = ao_vec3_make(AO_WORLD_ALBEDO, AO_WORLD_ALBEDO, AO_WORLD_ALBEDO)};
    struct ao_dvec3 center = {0};
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
        return ao_cursor_fail(c, "'radius' must be positive");
    if (!ao_world_charge(c, w, 1, 0, "sphere"))
        return false;
    if (!ao_scene_grow(&s->spheres, s->sphere_count, s->sphere_count + 1, sizeof *s->spheres) ||
        !ao_scene_grow(&w->sphere_centers, s->sphere_count, s->sphere_count + 1, sizeof *w->sphere_centers))
        return ao_cursor_fail(c, "out of memory");
    w->sphere_centers[s->sphere_count] = center;
    s->spheres[s->sphere_count++] = sp;
    return true;
}

static bool parse_quad(struct ao_cursor *c, struct ao_scene *s, struct ao_world *w)
{
    static const char *const keys[] = {"corner", "edge1", "edge2", "albedo", NULL};
    unsigned seen = 0;
    struct ao_dvec3 corner = {0}, e1 = {0}, e2 = {0};
    struct ao_vec3 rho = ao_vec3_make(AO_WORLD_ALBEDO, AO_WORLD_ALBEDO, AO_WORLD_ALBEDO);
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
    struct ao_vec3 n = ao_dvec3_narrow(ao_dvec3_cross(e1, e2));
    if (!(ao_vec3_length(n) > 0.0f) || !ao_vec3_is_finite(n))
        return ao_cursor_fail(c, "quad: edge1 and edge2 span no area");
    n = ao_vec3_normalize(n);
    if (!ao_world_charge(c, w, 2, 4, "quad"))
        return false;
    (void)s;
    struct ao_dvec3 p[4] = {corner, ao_dvec3_add(corner, e1), ao_dvec3_add(ao_dvec3_add(corner, e1), e2),
                            ao_dvec3_add(corner, e2)};
    return ao_world_add_quad(w, p, n, rho) || ao_cursor_fail(c, "out of memory");
}

static bool parse_mesh(struct ao_cursor *c, struct ao_scene *s, struct ao_world *w)
{
    static const char *const keys[] = {"albedo", "scale", "rotate", "translate", "crease", NULL};
    if (c->next >= c->count)
        return ao_cursor_fail(c, "'mesh' needs a file name");
    char path[4096];
    if (!resolve_path(c, c->tokens[c->next++], path, sizeof path))
        return false;
    unsigned seen = 0;
    struct ao_vec3 rho = ao_vec3_make(AO_WORLD_ALBEDO, AO_WORLD_ALBEDO, AO_WORLD_ALBEDO);
    struct transform t = {.scale = ao_dvec3_make(1, 1, 1), .axis = ao_dvec3_make(0, 1, 0), .cos_angle = 1};
    double crease = w->crease;
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
            if (!ao_dvec3_unit(ao_dvec3_make(r[0], r[1], r[2]), &t.axis))
                return ao_cursor_fail(c, "'rotate': the axis must not be zero");
            t.cos_angle = cos(r[3] * PI / 180.0);
            t.sin_angle = sin(r[3] * PI / 180.0);
        }
        if (k == 3 && !vector(c, key, &t.translate))
            return false;
        if (k == 4 && !crease_angle(c, key, &crease))
            return false;
    }
    if (t.scale.x == 0.0 || t.scale.y == 0.0 || t.scale.z == 0.0)
        return ao_cursor_fail(c, "'scale' must not be zero");
    const struct ao_world_file *f = ao_world_find_file(w, path, crease);
    if (!f && !(f = ao_world_load_file(c, s, w, path, crease)))
        return false;
    struct ao_affine line = affine_of(&t);
    return ao_world_place_model(c, s, w, f, &line, rho, path);
}

/* Splits a line into tokens in place, dropping a '#' comment; false when there are too many. */
static bool tokenize(struct ao_cursor *c, char *line)
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
        if (c->count == AO_CURSOR_TOKENS)
            return ao_cursor_fail(c, "too many words on one line (at most %d)", AO_CURSOR_TOKENS);
        c->tokens[c->count++] = p;
        while (*p && *p != ' ' && *p != '\t' && *p != '\r')
            p++;
    }
    return true;
}

static bool parse_statement(struct ao_cursor *c, struct ao_scene *s, struct ao_world *w)
{
    const char *word = c->tokens[0];
    if (strcmp(word, "camera") == 0)
        return parse_camera(c, s, w);
    if (strcmp(word, "image") == 0)
        return parse_image(c, s, w);
    if (strcmp(word, "sphere") == 0)
        return parse_sphere(c, s, w);
    if (strcmp(word, "quad") == 0)
        return parse_quad(c, s, w);
    if (strcmp(word, "mesh") == 0)
        return parse_mesh(c, s, w);
    if (strcmp(word, "background") == 0)
        return unit_colour(c, word, &s->background) &&
               (c->next == c->count || ao_cursor_fail(c, "'background': expected 1 or 3 numbers"));
    if (strcmp(word, "ao-distance") == 0) {
        double d;
        if (!scalar(c, word, &d))
            return false;
        s->ao_distance = (float)d;
        return s->ao_distance > 0.0f || ao_cursor_fail(c, "'ao-distance' must be positive");
    }
    return ao_cursor_fail(c, "unknown keyword '%s'", word);
}

bool ao_scene_parse_lines(struct ao_cursor *c, struct ao_scene *s, struct ao_world *w, const char *text)
{
    char line[MAX_LINE + 2];
    for (const char *p = text; *p;) {
        size_t len = strcspn(p, "\n");
        c->line++;
        if (len > MAX_LINE)
            return ao_cursor_fail(c, "line longer than %d characters", MAX_LINE);
        memcpy(line, p, len);
        line[len] = '\0';
        p += len + (p[len] == '\n');
        if (!tokenize(c, line) || (c->count > 0 && !parse_statement(c, s, w)))
            return false;
    }
    return true;
}
