/* Config validation that says which field is bad: each check stops at the
 * first field out of range, names it (as a path in rsm_localizer_config_t,
 * e.g. "odometry.wheel_base_m", a string in ROM) and returns RSM_ERR_INVAL.
 * And the capacity check of the set-up functions (RSM_SAME_BUILD).
 * Internal to the library. */
#ifndef RSM_CHECK_H
#define RSM_CHECK_H

#include <stddef.h>

#include "rsm/config.h"
#include "rsm/status.h"

/* In a function with a `const char **field` parameter (may be NULL):
 * unless cond holds, stores name there and returns RSM_ERR_INVAL. */
#define RSM_CHECK_FIELD(cond, name)      \
    do {                                 \
        if (!(cond)) {                   \
            if (field != NULL) {         \
                *field = (name);         \
            }                            \
            return RSM_ERR_INVAL;        \
        }                                \
    } while (0)

/* Whether a caller's object of size bytes, compiled with the capacity
 * digest fingerprint (RSM_CONFIG_FINGERPRINT as the caller saw it), is the
 * library's own type: a _checked set-up function (rsm_sync_init_checked,
 * rsm_scan_set_uniform_checked, ...) tests it before anything else and
 * returns RSM_ERR_CONFIG, with nothing written, when it does not hold. */
#define RSM_SAME_BUILD(type, size, fingerprint) \
    ((size) == sizeof(type) && (fingerprint) == (unsigned long)RSM_CONFIG_FINGERPRINT)

#endif /* RSM_CHECK_H */
