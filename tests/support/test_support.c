#include "test_support.h"

#include <stdio.h>

static const char *join(char *out, size_t cap, const char *root, const char *rel)
{
    int n = snprintf(out, cap, "%s/%s", root, rel);
    if (n < 0 || (size_t)n >= cap) {
        return NULL;
    }
    return out;
}

const char *rsm_test_source_path(char *out, size_t cap, const char *rel)
{
    return join(out, cap, RSM_SOURCE_DIR, rel);
}

const char *rsm_test_shared_path(char *out, size_t cap, const char *rel)
{
    return join(out, cap, RSM_SHARED_DIR, rel);
}
