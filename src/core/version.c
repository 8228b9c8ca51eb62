#include "rsm/version.h"

/* The literal is compiled into the library, so it names the library's
 * version even when the caller's headers are of another one. */
const char *rsm_version(void)
{
    return RSM_VERSION_STRING;
}
