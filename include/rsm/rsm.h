/* Umbrella header: everything a firmware or host program needs from rsm
 * (the installed headers; docs/api.md lists them). */
#ifndef RSM_RSM_H
#define RSM_RSM_H

#include "rsm/aria.h"
#include "rsm/config.h"
#include "rsm/geom.h"
#include "rsm/hal.h"
#include "rsm/ld06.h"
#include "rsm/ldlidar.h"
#include "rsm/lidar.h"
#include "rsm/link_poll.h"
#include "rsm/lms.h"
#include "rsm/localizer.h"
#include "rsm/mapfile.h"
#include "rsm/mapimport.h"
#include "rsm/odometry.h"
#include "rsm/p3dx.h"
#include "rsm/revolution.h"
#include "rsm/rplidar.h"
#include "rsm/scan.h"
#include "rsm/sicklms.h"
#include "rsm/slamtec.h"
#include "rsm/status.h"
#include "rsm/sync.h"
#include "rsm/tilestore.h"
#include "rsm/version.h"

#endif /* RSM_RSM_H */
