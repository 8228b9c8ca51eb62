/* Umbrella header: everything a firmware or host program needs from rsm. */
#ifndef RSM_RSM_H
#define RSM_RSM_H

#include "rsm/config.h"
#include "rsm/geom.h"
#include "rsm/status.h"

#endif /* RSM_RSM_H */
