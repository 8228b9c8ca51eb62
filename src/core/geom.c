#include "rsm/geom.h"

#include <math.h>
#include "core/fmath.h"

float rsm_wrap_angle(float a)
{
    if (!isfinite(a)) {
        return a;
    }
    /* fmodf keeps large inputs exact enough; the loop only fixes the edges.
     * Below one turn fmodf returns a itself: no call for the usual angle. */
    if (!(fabsf(a) < RSM_TWO_PI)) {
        a = fmodf(a, RSM_TWO_PI);
    }
    while (a > RSM_PI) {
        a -= RSM_TWO_PI;
    }
    while (a <= -RSM_PI) {
        a += RSM_TWO_PI;
    }
    return a;
}

rsm_pose_t rsm_pose_compose(const rsm_pose_t *a, const rsm_pose_t *b)
{
    const rsm_point_t p = {b->x, b->y};
    const rsm_point_t q = rsm_pose_apply(a, &p);
    rsm_pose_t r;
    r.x = q.x;
    r.y = q.y;
    r.theta = rsm_wrap_angle(a->theta + b->theta);
    return r;
}

rsm_pose_t rsm_pose_inverse(const rsm_pose_t *a)
{
    float c;
    float s;
    rsm_pose_t r;
    rsm_sincosf(a->theta, &s, &c);
    r.x = -c * a->x - s * a->y;
    r.y = s * a->x - c * a->y;
    r.theta = rsm_wrap_angle(-a->theta);
    return r;
}

rsm_pose_t rsm_pose_between(const rsm_pose_t *a, const rsm_pose_t *b)
{
    const rsm_pose_t inv = rsm_pose_inverse(a);
    return rsm_pose_compose(&inv, b);
}

int rsm_pose_apart(const rsm_pose_t *a, const rsm_pose_t *b, float m, float rad)
{
    const rsm_pose_t d = rsm_pose_between(a, b);
    return sqrtf(d.x * d.x + d.y * d.y) >= m || fabsf(d.theta) >= rad;
}

rsm_point_t rsm_pose_apply(const rsm_pose_t *a, const rsm_point_t *p)
{
    float c;
    float s;
    rsm_point_t r;
    rsm_sincosf(a->theta, &s, &c);
    r.x = a->x + c * p->x - s * p->y;
    r.y = a->y + s * p->x + c * p->y;
    return r;
}
