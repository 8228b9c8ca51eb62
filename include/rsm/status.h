/* rsm status codes: 0 is success, failures are negative, and functions that
 * return a count use the non-negative range for it. */
#ifndef RSM_STATUS_H
#define RSM_STATUS_H

#ifdef __cplusplus
extern "C" {
#endif

typedef enum rsm_status {
    RSM_OK = 0,
    RSM_ERR_INVAL = -1,      /* bad argument or configuration */
    RSM_ERR_NOMEM = -2,      /* a compile-time capacity was exceeded */
    RSM_ERR_AGAIN = -3,      /* need more input bytes (partial frame) */
    RSM_ERR_CHECKSUM = -4,   /* frame checksum or CRC mismatch */
    RSM_ERR_RANGE = -5,      /* value outside its legal range */
    RSM_ERR_TIMEOUT = -6,    /* nothing arrived within the given time */
    RSM_ERR_IO = -7,         /* the link reported an error */
    RSM_ERR_DEGENERATE = -8, /* no usable points, key points or matches */
    RSM_ERR_NOSYS = -9,      /* optional operation not provided */
    RSM_ERR_PROTO = -10,     /* protocol violation: NAK, unexpected reply */
    RSM_ERR_ORDER = -11,     /* timestamp went backwards */
    RSM_ERR_CONFIG = -12,    /* caller compiled with other capacities than the library */
    RSM_ERR_FORMAT = -13     /* stored data of another kind, version or build (a saved map) */
} rsm_status_t;

/* Returns a constant, never-NULL description of a status code (ROM string).
 * Unknown codes give "unknown status". Reentrant, ISR-safe. */
const char *rsm_strerror(int status);

#ifdef __cplusplus
}
#endif

#endif /* RSM_STATUS_H */
