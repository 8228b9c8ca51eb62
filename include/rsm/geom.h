/* Planar geometry shared by every module: poses, points, angle wrapping.
 * Units: metres and radians, counter-clockwise positive. */
#ifndef RSM_GEOM_H
#define RSM_GEOM_H

#ifdef __cplusplus
extern "C" {
#endif

#define RSM_PI 3.14159265358979323846f
#define RSM_TWO_PI 6.28318530717958647692f

/* A 2-D rigid pose: position in metres, heading in radians in (-pi, pi]. */
typedef struct rsm_pose {
    float x;
    float y;
    float theta;
} rsm_pose_t;

/* A point in metres. */
typedef struct rsm_point {
    float x;
    float y;
} rsm_point_t;

/* Wraps an angle to (-pi, pi]. Non-finite input is returned unchanged so that
 * callers can detect it. Pure, reentrant. */
float rsm_wrap_angle(float a);

/* a (+) b: pose b expressed in frame a, taken to the frame a is expressed in. */
rsm_pose_t rsm_pose_compose(const rsm_pose_t *a, const rsm_pose_t *b);

/* (-)a: the inverse transform, so that compose(inverse(a), a) = identity. */
rsm_pose_t rsm_pose_inverse(const rsm_pose_t *a);

/* inverse(a) (+) b: pose b expressed in the frame of pose a. */
rsm_pose_t rsm_pose_between(const rsm_pose_t *a, const rsm_pose_t *b);

/* 1 when b is at least m metres or rad radians from a (as seen from a),
 * else 0. */
int rsm_pose_apart(const rsm_pose_t *a, const rsm_pose_t *b, float m, float rad);

/* Applies pose a to point p (robot frame -> the frame a is expressed in). */
rsm_point_t rsm_pose_apply(const rsm_pose_t *a, const rsm_point_t *p);

#ifdef __cplusplus
}
#endif

#endif /* RSM_GEOM_H */
