/* Reading a ROS map (map_server's YAML + PGM, as rsm-nav --map, ROS
 * map_server, slam_toolbox or Cartographer's map saver write it) into the
 * localizer's persistent map (include/rsm/mapimport.h).
 *
 * The YAML's keys: image (a PGM; a relative path is relative to the YAML's
 * folder), resolution, origin [x, y, yaw], negate, occupied_thresh,
 * free_thresh, all required, and mode (trinary, scale or raw; trinary when
 * absent); other keys are ignored. The PGM is P5 (binary) or P2 (ASCII)
 * with a maxval up to 255, comments allowed; 16-bit images are refused.
 * A pixel is occupied when, as map_server reads it, its occupancy
 * p = (maxval - v) / maxval (v / maxval with negate) is above
 * occupied_thresh; in raw mode when v is at most 100 and v / 100 is above
 * occupied_thresh. Only occupied pixels are imported; free and unknown ones
 * write nothing. Docs: docs/mapfile.md, "Importing a ROS map". */
#ifndef RSM_NAV_ROSMAP_H
#define RSM_NAV_ROSMAP_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/localizer.h"
#include "rsm/mapimport.h"

/* Reads yaml_path and its image whole, checks everything, and only then
 * empties loc's persistent map and imports the image, row by row. Returns
 * 0 when all of it went in; 1 when it went in incomplete (the pool was
 * full, or pixels lay beyond the map's range): err says how much was lost;
 * -1 on any fault (unreadable or malformed YAML or PGM, a missing or bad
 * key, a 16-bit or truncated image, one of another size than its header
 * says, a localizer not of RSM_METHOD_MAP): err says what and where, and
 * loc is untouched. err gets a NUL-terminated message of at most errcap
 * bytes (nothing on 0). *report (may be NULL) gets the import's counts. */
int rsm_rosmap_load(const char *yaml_path, rsm_localizer_t *loc, rsm_import_report_t *report, char *err,
                    size_t errcap);

#endif
