#include "rsm/status.h"

const char *rsm_strerror(int status)
{
    switch (status) {
    case RSM_OK: return "ok";
    case RSM_ERR_INVAL: return "invalid argument";
    case RSM_ERR_NOMEM: return "capacity exceeded";
    case RSM_ERR_AGAIN: return "need more data";
    case RSM_ERR_CHECKSUM: return "checksum mismatch";
    case RSM_ERR_RANGE: return "value out of range";
    case RSM_ERR_TIMEOUT: return "timed out";
    case RSM_ERR_IO: return "i/o error";
    case RSM_ERR_DEGENERATE: return "degenerate input";
    case RSM_ERR_NOSYS: return "not supported";
    case RSM_ERR_PROTO: return "protocol error";
    case RSM_ERR_ORDER: return "timestamp out of order";
    case RSM_ERR_CONFIG: return "built with other capacities than the library";
    case RSM_ERR_FORMAT: return "not a map of this format, version or build";
    default: return "unknown status";
    }
}
