/* Pinhole camera and viewer moves; see camera.h. */
#include "camera.h"

static const float PI = 3.14159265358979323846f;

/* Whether p lies within AO_CAMERA_REACH of the origin in every coordinate (not NaN). */
static bool within_reach(struct ao_vec3 p)
{
    return fabsf(p.x) <= AO_CAMERA_REACH && fabsf(p.y) <= AO_CAMERA_REACH && fabsf(p.z) <= AO_CAMERA_REACH;
}

bool ao_camera_view(const struct ao_camera *c, int width, int height, struct ao_view *v)
{
    struct ao_vec3 dir = ao_vec3_sub(c->target, c->eye);
    struct ao_vec3 side = ao_vec3_cross(dir, c->up);
    float dir_len = ao_vec3_length(dir);
    if (!(dir_len > 0.0f) || !(ao_vec3_length(side) > 1e-6f * dir_len * ao_vec3_length(c->up)) ||
        !(c->fov > 0.0f && c->fov < 180.0f) || width <= 0 || height <= 0)
        return false;
    v->eye = c->eye;
    v->forward = ao_vec3_normalize(dir);
    v->right = ao_vec3_normalize(ao_vec3_cross(v->forward, c->up));
    v->up = ao_vec3_cross(v->right, v->forward);
    v->tan_half_fov = tanf(0.5f * c->fov * PI / 180.0f);
    v->aspect = (float)width / (float)height;
    v->width = width;
    v->height = height;
    return true;
}

bool ao_camera_view_coarse(const struct ao_camera *c, int width, int height, int block, struct ao_view *v)
{
    if (!ao_camera_view(c, width, height, v))
        return false;
    /* ao_camera_ray's screen coordinates are affine in the pixel position: with n = ceil(width /
     * block) columns, sx' = (2 x' / n - 1) t a' stands for the image's sx = (2 block x' / width - 1)
     * t a when t a' = t a block n / width, off by the constant t a' - t a; rows likewise. The
     * constants go into forward (the direction is normalized after the sum). */
    int columns = (width + block - 1) / block, rows = (height + block - 1) / block;
    float t = v->tan_half_fov, ta = t * v->aspect;
    float coarse_ta = ta * (float)block * (float)columns / (float)width;
    float coarse_t = t * (float)block * (float)rows / (float)height;
    v->forward = ao_vec3_add(v->forward, ao_vec3_add(ao_vec3_scale(v->right, coarse_ta - ta),
                                                     ao_vec3_scale(v->up, t - coarse_t)));
    v->tan_half_fov = coarse_t;
    v->aspect = coarse_ta / coarse_t;
    v->width = columns;
    v->height = rows;
    return true;
}

void ao_camera_orbit(struct ao_camera *c, float yaw, float pitch)
{
    /* Spherical coordinates of the eye about the target, with the camera's up as the pole. */
    struct ao_vec3 pole = ao_vec3_normalize(c->up);
    struct ao_vec3 offset = ao_vec3_sub(c->eye, c->target);
    float radius = ao_vec3_length(offset);
    struct ao_basis f = ao_basis_from_normal(pole);
    float x = ao_vec3_dot(offset, f.t), y = ao_vec3_dot(offset, f.b), z = ao_vec3_dot(offset, pole);
    float theta = acosf(fmaxf(-1.0f, fminf(1.0f, z / radius))) - pitch;
    float phi = atan2f(y, x) - yaw;
    const float margin = 0.01f;
    theta = fmaxf(margin, fminf(PI - margin, theta));
    struct ao_vec3 local = ao_basis_to_world(&f, sinf(theta) * cosf(phi), sinf(theta) * sinf(phi),
                                             cosf(theta));
    c->eye = ao_vec3_add(c->target, ao_vec3_scale(local, radius));
}

void ao_camera_pan(struct ao_camera *c, float dx, float dy)
{
    struct ao_view v;
    if (!ao_camera_view(c, 1, 1, &v))
        return;
    float extent = 2.0f * v.tan_half_fov * ao_vec3_length(ao_vec3_sub(c->target, c->eye));
    struct ao_vec3 move = ao_vec3_add(ao_vec3_scale(v.right, -dx * extent), ao_vec3_scale(v.up, dy * extent));
    struct ao_vec3 eye = ao_vec3_add(c->eye, move), target = ao_vec3_add(c->target, move);
    if (within_reach(eye) && within_reach(target)) {
        c->eye = eye;
        c->target = target;
    }
}

void ao_camera_zoom(struct ao_camera *c, float factor)
{
    struct ao_vec3 offset = ao_vec3_sub(c->eye, c->target);
    float radius = ao_vec3_length(offset);
    float next = fmaxf(radius * factor, 1e-4f * radius);
    struct ao_vec3 eye = ao_vec3_add(c->target, ao_vec3_scale(offset, next / radius));
    if (next > 0.0f && isfinite(next) && within_reach(eye))
        c->eye = eye;
}

void ao_camera_frame_box(struct ao_camera *c, struct ao_vec3 lo, struct ao_vec3 hi)
{
    struct ao_vec3 center = ao_vec3_scale(ao_vec3_add(lo, hi), 0.5f);
    float radius = 0.5f * ao_vec3_length(ao_vec3_sub(hi, lo));
    if (!(radius > 0.0f))
        radius = 1.0f;
    c->fov = 40.0f;
    c->up = ao_vec3_make(0.0f, 1.0f, 0.0f);
    c->target = center;
    /* Far enough that the bounding sphere fits the vertical field of view, from 20 degrees up. */
    float distance = 1.1f * radius / sinf(0.5f * c->fov * PI / 180.0f);
    struct ao_vec3 dir = ao_vec3_normalize(ao_vec3_make(0.0f, 0.36f, 1.0f));
    c->eye = ao_vec3_add(center, ao_vec3_scale(dir, distance));
}
