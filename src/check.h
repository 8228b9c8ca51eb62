/* Config validation that says which field is bad: each check stops at the
 * first field out of range, names it (as a path in rsm_localizer_config_t,
 * e.g. "odometry.wheel_base_m", a string in ROM) and returns RSM_ERR_INVAL.
 * Internal to the library. */
#ifndef RSM_CHECK_H
#define RSM_CHECK_H

#include <stddef.h>

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

#endif /* RSM_CHECK_H */
