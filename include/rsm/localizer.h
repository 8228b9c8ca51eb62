/* The localizer: odometry's prediction, then per scan a match against the
 * persistent multi-resolution map (the default, RSM_METHOD_MAP: coarse to
 * fine under the prediction as prior; odometry's steps checked against the
 * scans; a search when a scan fits far worse than recent ones; a tracking
 * state), then the map written. The method switch also runs the paper's
 * pipeline (grid image -> Harris key points -> tentative matches -> RANSAC
 * -> EKF), the ICP baseline or odometry alone through the same filter, so
 * all are compared on equal terms.
 *
 * All state is caller-owned (rsm_localizer_t: about 125 KiB with the
 * default config.h and 64 KiB with rsm/config_small.h on a 32-bit target;
 * docs/RESULTS.md has the breakdown). Two localizers never interfere. Not
 * reentrant for one state; no function blocks or allocates. */
#ifndef RSM_LOCALIZER_H
#define RSM_LOCALIZER_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/config.h"
#include "rsm/geom.h"
#include "rsm/localizer_parts.h"
#include "rsm/odometry.h"
#include "rsm/scan.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum rsm_method {
    RSM_METHOD_PAPER = 0,    /* the paper's method: key points + RANSAC against a scrolling window */
    RSM_METHOD_ICP = 1,      /* the paper's baseline: point-to-point ICP, scan to scan */
    RSM_METHOD_ODOMETRY = 2, /* dead reckoning only */
    RSM_METHOD_MAP = 3       /* the default: coarse-to-fine matching against the persistent map */
} rsm_method_t;

/* What a scan did to the estimate. */
typedef enum rsm_outcome {
    RSM_SCAN_ACCEPTED = 0,       /* measurement fused */
    RSM_SCAN_FIRST = 1,          /* first scan: started the map */
    RSM_SCAN_ODOMETRY = 2,       /* method is odometry only */
    RSM_SCAN_FEW_POINTS = 3,     /* too few usable readings */
    RSM_SCAN_FEW_KEYPOINTS = 4,  /* too few key points in scan or reference */
    RSM_SCAN_FEW_MATCHES = 5,    /* too few tentative matches */
    RSM_SCAN_LOW_SUPPORT = 6,    /* RANSAC (or ICP) found no well-supported pose */
    RSM_SCAN_JUMP = 7,           /* measured pose too far for the covariance */
    RSM_SCAN_FILTER = 8,         /* EKF refused the update (singular) */
    RSM_SCAN_OUT_OF_ORDER = 9,   /* timestamp went backwards: scan ignored */
    RSM_SCAN_POOR_FIT = 10,      /* RSM_METHOD_MAP: the match fitted far worse than recent scans,
                                  * no search proved a pose, and odometry stood still or the
                                  * search was ambiguous: not fused, not written */
    RSM_SCAN_SEARCHING = 11,     /* RSM_METHOD_MAP: a global search (rsm_localizer_global) is under
                                  * way and has proven no pose yet: the estimate is unknown */
    RSM_SCAN_OUTCOMES = 12
} rsm_outcome_t;

/* The stages of one rsm_localizer_scan call, as the optional timing hook
 * (rsm_localizer_config_t.clock_fn) reports them. Each stage is charged the
 * time from its start to the start of the next; a stage a scan never reaches
 * (rejected early, other method) gets 0. */
typedef enum rsm_stage {
    RSM_STAGE_POINTS = 0,  /* readings -> points in the robot frame (every method) */
    RSM_STAGE_GRID = 1,    /* map recentred, points -> scan image in the map frame */
    RSM_STAGE_HARRIS = 2,  /* key points of the scan image and of the map near it */
    RSM_STAGE_MATCH = 3,   /* tentative matches */
    RSM_STAGE_RANSAC = 4,  /* two-point RANSAC pose and its noise */
    RSM_STAGE_REFINE = 5,  /* sub-cell alignment of the points to the map (rsm_map_align) */
    RSM_STAGE_ICP = 6,     /* the ICP baseline's alignment */
    RSM_STAGE_EKF = 7,     /* measurement noise, gate and update */
    RSM_STAGE_MAP = 8,     /* the scan superimposed on the map (and the ICP reference) */
    RSM_STAGE_MAPMATCH = 9, /* coarse-to-fine alignment to the persistent map (RSM_METHOD_MAP) */
    RSM_STAGE_COUNT = 10
} rsm_stage_t;

/* Measurement noise model for the EKF update. */
typedef enum rsm_noise_model {
    RSM_NOISE_RESIDUAL = 0, /* from the match residuals, floored */
    RSM_NOISE_FIXED = 1     /* the paper's (1 cell, 1 cell, 0.25 deg) */
} rsm_noise_model_t;

typedef struct rsm_localizer_config {
    rsm_method_t method;
    rsm_scan_limits_t limits;       /* usable range interval */
    rsm_isolation_t isolation;      /* returns no neighbour confirms are not written into the
                                     * persistent map (RSM_METHOD_MAP); tol_m 0 = off. Default
                                     * off (slope 3, window 2, agree 1; 0.1 m turns it on): see
                                     * docs/map.md for what it costs on clean logs */
    rsm_occlusion_t occlusion;      /* returns behind a surface their neighbours span are dropped
                                     * before matching and writing (RSM_METHOD_MAP); window 0 =
                                     * off. Default window 2, span 0.3 m, tol 0.1 m, slope 3,
                                     * margin 0.2 m + 5 % of the range: docs/map.md */
    rsm_grid_config_t grid;         /* cell size and marking rule */
    rsm_harris_config_t harris;
    rsm_ransac_config_t ransac;
    rsm_icp_config_t icp;
    rsm_odometry_config_t odometry; /* geometry for ticks, and process noise */
    rsm_odometry_cal_config_t odometry_cal; /* online calibration of odometry's heading error (and,
                                     * with max_scale > 0, distance error) from the matches
                                     * (RSM_METHOD_MAP); memory 0 = off; default on */
    rsm_pose_t laser_mount;         /* the laser's pose in the robot frame; default zero */
    uint8_t laser_upside_down;      /* 1: the laser is mounted upside down (beam angles mirrored) */
    rsm_tmap_config_t tmap;         /* persistent map (RSM_METHOD_MAP) */
    rsm_mapmatch_config_t mapmatch; /* matching against it */
    float map_update_m;             /* write a scan into the persistent map after this much travel
                                     * since the last write; default 0.4 */
    float map_update_rad;           /* ... or this much turning; default 0.5 */
    float recover_ratio;            /* a match whose mean occupancy under its points falls below
                                     * this share of the recent mean (odometry far off: a slip, a
                                     * bump, a kidnap) triggers a search of +-recover_m; default 0.4 */
    float recover_m;                /* 0 = never search; default 1.0 */
    float recover_rad;              /* ... and of +-recover_rad in heading (a turn the odometry
                                     * misjudged); default 0.3 */
    float recover_margin;           /* a search's winner is taken only when its fit beats every
                                     * pose a doubt (doubt_m, doubt_rad) away from it by this
                                     * share, and (recover_budget 0) its share of readings on
                                     * walls too, else the scan is left ambiguous; default 0.1 */
    uint32_t recover_budget;        /* 0, the default: a recovery's search and proof whole in the
                                     * scan that asks for it (up to 1.8 million Cortex-M4
                                     * instructions on ACES). Else spread over the scans after
                                     * it in stages, this much work a scan at most (units of
                                     * about 18 instructions, as global_budget; 38000 kept ACES's
                                     * recovery scans under a million), the robot carried by
                                     * odometry meanwhile: at a cost in accuracy and in faults
                                     * (docs/robustness.md, "A recovery spread over scans");
                                     * its proof weighs fits alone, not wall shares */
    /* Odometry is evidence, not truth (RSM_METHOD_MAP): its step since the
     * last scan is matched against a second prediction when the scans give
     * cause to doubt it, and the prediction the scan fits better is kept
     * (docs/robustness.md, "Odometry that lies"). */
    float refute_margin;            /* a second prediction replaces odometry's when its fit beats
                                     * it by this share; 0 = never doubt odometry; default 0.1.
                                     * The last estimate without the step (a spike, a counter
                                     * reset, a slip) only when it fits as a tracking scan does
                                     * (track_min_fit); a weaker case searches around odometry's
                                     * prediction (recover_m) and keeps the step unless a pose is
                                     * proven (a long gap in the scans) */
    float conflict_max;             /* a scan whose beams pass through walls of the map (cells at
                                     * saturation on the finest level, more than 4 cells before
                                     * their return; up to 64 beams looked at) in more than this
                                     * share contradicts the map where it is placed (a robot
                                     * carried to where the map holds other walls): checked when
                                     * the match would not track by its fit (track_min_fit: a
                                     * search's winner too, then not taken; a plain match, then
                                     * refused if poor, else fused), and before
                                     * writing a scan that found too little map to match (then not
                                     * written); such a scan does not track, and reports lost at
                                     * once. 0 = off; default 0.5 (docs/robustness.md) */
    float doubt_m;                  /* odometry counted from the last scan that trusted it (not
                                     * from the last scan) predicts a pose this far ... */
    float doubt_rad;                /* ... or turned this far from the step's: both are matched
                                     * (after a stall, motion reported again; after a refuted
                                     * spike, the step that takes it back); defaults 0.1 m and
                                     * 0.1 rad */
    float wall_sigma_rad;           /* the walls' grid as a pull on the heading (RSM_METHOD_MAP,
                                     * while the map is written; docs/robustness.md, "Heading
                                     * from the walls"): a scan's straight walls set against the
                                     * two perpendicular directions the first scans' walls ran
                                     * along, as a measurement of this standard deviation for
                                     * 5 m of straight stretches, about 2.5 m of wall (more for
                                     * less, and softly less within the
                                     * window) would pull it; 0 = off; default 0.0015 */
    float wall_window_rad;          /* ... walls within this of the grid count (others are not
                                     * the grid's, or the heading is off by more than a grid
                                     * can tell); default 0.035 (2 degrees) */
    /* What the reported covariance adds to the filter's own (docs/robustness.md, "The
     * covariance"): the error a match cannot see because a scan's readings share it (the
     * map's cells, a wall's texture, a beam's width), which the filter's sum over readings
     * taken as independent leaves out. Only the report and rsm_localizer_covariance see
     * it; the filter weighs matches with its own. */
    float cov_floor_m;              /* standard deviation added in x and in y (as variances);
                                     * 0 = none; default 0.008: about the median per-pose error
                                     * on Intel's relations whatever the filter's own said */
    float cov_floor_rad;            /* ... and in heading; default 0.002 */
    /* The global search (rsm_localizer_global; docs/globalsearch.md). */
    uint32_t global_budget;         /* the search's work a scan may take at most, in units of
                                     * about 18 Cortex-M4 instructions (a bound grid's block read;
                                     * every other step of the search and its proof counts what it
                                     * was measured to cost); 0 = the whole search and proof in one
                                     * scan; default 45000: at most about 0.9 million instructions
                                     * a scan on the M4, measured on the Intel and ACES maps
                                     * (docs/globalsearch.md: the cost and the time it takes) */
    float global_min_share;         /* a pose is kept only when the occupancy summed under the
                                     * scan's points (cells of about 0.2 m) reaches a share of
                                     * their count: 0.97 in the first search, then 0.95, 0.90, ...
                                     * after each search that proved nothing, down to this;
                                     * default 0.8 */
    float global_min_fit;           /* the winner's fit (mean occupancy under all its points at the
                                     * finest level) must reach this share of the fit the map's own
                                     * scans had (saved with the map; 1 when unknown); default 0.8 */
    float global_crowded_fit;       /* the same share when at least as many poses reached the
                                     * search's bar unkept as it keeps (RSM_GLOBAL_CANDIDATES):
                                     * a rival the proof could not weigh may fit better than
                                     * those it did, so the winner must fit about as well as
                                     * the map's own scans; default 0.9 (below global_min_fit:
                                     * that one) */
    uint8_t global_when_lost;       /* 1: a localizer that reports lost starts a global search by
                                     * itself, within recover_m of the estimate first, the window
                                     * doubling with every second search that proves nothing
                                     * (rsm_localizer_global_near); default 0 */
    uint8_t map_frozen;             /* 1: localization mode: the persistent map is read, never
                                     * written (a map loaded with rsm_localizer_load_map stays as
                                     * it was saved); 0: scans keep updating it (the building
                                     * changes: doors, furniture); default 0 */
    uint8_t map_loaded_hit;         /* with updates on, what a return adds to a cell of a map that
                                     * was loaded or imported (rsm_localizer_load_map,
                                     * rsm_localizer_import_ros_map), in place of tmap.hit_inc: a
                                     * saved map holds many passes' evidence, and scans written
                                     * into it at a new map's rate blur it to one pass's
                                     * (docs/mapfile.md, "After a load"); 0: tmap.hit_inc;
                                     * default 1 */
    uint8_t map_min_hits;           /* map cells with this many hits are occupied; default 1 */
    uint8_t map_on_reject;          /* 1: superimpose rejected scans at the prediction; default 1 */
    uint16_t min_points;            /* usable readings needed; default 20 */
    uint8_t refuse_poor;            /* 1: a match that fits worse than recover_ratio of recent
                                     * scans, that no search replaced, and that came while
                                     * odometry stood still or after an ambiguous search, is
                                     * refused (RSM_SCAN_POOR_FIT); 0: fused; default 1
                                     * (RSM_METHOD_MAP) */
    float track_min_fit;            /* a matched scan tracks when its fit reaches this share of
                                     * recent scans' (and its beams do not contradict the map,
                                     * conflict_max); a few scans in a thousand fall below it on
                                     * Intel and ACES, a robot carried to a look-alike place
                                     * stays below it; default 0.7 */
    uint16_t lost_scans;            /* scans in a row that do not track (poor fit, refused,
                                     * unusable) after which the estimate is reported lost;
                                     * >= 1; default 10 */
    uint16_t min_keypoints;         /* key points needed in each image; default 4 */
    float match_window_m;           /* w of the +-w box; default 0.05 (one cell) */
    float search_sigmas;            /* nearest-neighbour radius in predicted std devs; default 3 */
    float search_min_m;             /* radius floor; default 0.15 */
    float search_max_m;             /* radius cap; default 0.6 */
    float gate_d2;                  /* Mahalanobis gate on the measured pose, 3 dof; default 16.27 (99.9%) */
    rsm_noise_model_t noise;        /* default RSM_NOISE_RESIDUAL */
    float r_min_xy_m;               /* residual model floors; default 0.003 m */
    float r_min_theta_rad;          /* default 0.001 rad */
    uint32_t refine_iterations;     /* Gauss-Newton steps aligning the points to the map after
                                     * RANSAC (sub-cell accuracy); 0 = the paper's method only;
                                     * default 10 */
    uint8_t refine_saturation;      /* map hits that count as fully occupied; default 2 */
    float refine_noise_scale;       /* scales the fit's covariance into R; default 10 */
    /* Optional timing hook; NULL by default, and then it costs one test per
     * stage. clock_fn(clock_ctx) returns a free-running counter in any unit
     * (microseconds, CPU cycles, nanoseconds, ...); differences are taken
     * modulo 2^32, so one scan must take less than one wrap. When set,
     * rsm_localizer_scan fills the report's stage_time and step_time in that
     * unit. It is called from inside rsm_localizer_scan and must not call
     * back into the localizer. */
    uint32_t (*clock_fn)(void *clock_ctx);
    void *clock_ctx;                /* passed to clock_fn; may be NULL */
} rsm_localizer_config_t;

rsm_localizer_config_t rsm_localizer_config_default(void);

/* What a scan made of odometry's step since the previous scan (RSM_METHOD_MAP). */
typedef enum rsm_odometry_verdict {
    RSM_ODOMETRY_TRUSTED = 0,   /* the step was the prediction (the usual case) */
    RSM_ODOMETRY_CAUGHT_UP = 1, /* odometry stood still while matching found the robot move,
                                 * then reported that motion too: it was counted once */
    RSM_ODOMETRY_REFUTED = 2,   /* the scan fits far better without the step (a spike, a
                                 * counter reset, wheels that slipped, or the step that takes
                                 * a refuted spike back): the step was dropped */
    RSM_ODOMETRY_RECOUNTED = 3  /* a match corrected odometry by more than a doubt before,
                                 * and odometry counted from before it fits far better: that
                                 * match was wrong, not odometry */
} rsm_odometry_verdict_t;

/* How far the estimate can be trusted, as the scans tell it. */
typedef enum rsm_track {
    RSM_TRACK_TRACKING = 0,  /* the last scan was matched and fitted the map as well as recent
                              * scans did (or a search proved where it is) */
    RSM_TRACK_UNCERTAIN = 1, /* the last scan fitted poorly, was refused or unusable, or its
                              * search was ambiguous: the estimate is the prediction's */
    RSM_TRACK_LOST = 2,      /* lost_scans scans in a row so: treat the estimate as unknown */
    RSM_TRACK_STATES = 3
} rsm_track_t;

/* Diagnostics of the last scan. */
typedef struct rsm_localizer_report {
    rsm_outcome_t outcome;
    rsm_track_t track;        /* how far the estimate after this scan can be trusted */
    float fit_ratio;          /* RSM_METHOD_MAP: the match's fit over the recent scans' (0 when
                               * no match was made) */
    rsm_odometry_verdict_t odometry; /* what the scan made of odometry's step */
    uint8_t recovered;        /* 1: a recovery search placed this scan (or a global search
                               * proved its pose) */
    uint8_t recovering;       /* 1: this scan began a tracking recovery or gave its time to
                               * one (recover_budget), the scan that one placed included */
    uint32_t search_work;     /* cells and blocks the global search read in this scan */
    rsm_pose_t pose;          /* estimate after this scan */
    float cov[9];             /* its covariance, row-major */
    rsm_pose_t measured;      /* scan-matching measurement (if one was made) */
    uint32_t points;          /* usable readings */
    uint32_t keypoints_cur;
    uint32_t keypoints_ref;
    uint32_t matches;
    uint32_t inliers;
    uint32_t iterations;      /* RANSAC hypotheses or ICP iterations */
    float residual_m;         /* RMS residual of the accepted fit */
    float mahalanobis_d2;     /* of the measurement against the prediction */
    float crossing;           /* RSM_METHOD_MAP: the share of the beams checked that passed
                               * through walls of the map (conflict_max); 0 when none were
                               * checked (a scan that fitted and was not due to be written) */
    float unpinned;           /* RSM_METHOD_MAP: the share (0 to 1) of the match's pull along
                               * the scan's surfaces left out because they all run one way
                               * (a bare corridor): the prediction kept that direction */
    /* With a clock_fn: time per stage and of the whole call (first to last
     * clock reading), in clock_fn's unit; the stages tile the call, so their
     * sum is step_time (modulo 2^32). All 0 without a clock_fn. */
    uint32_t stage_time[RSM_STAGE_COUNT];
    uint32_t step_time;
} rsm_localizer_report_t;

typedef struct rsm_localizer_counters {
    uint32_t scans;                          /* scans offered */
    uint32_t outcome[RSM_SCAN_OUTCOMES];     /* per outcome */
    rsm_scan_drops_t drops;                  /* unusable readings by reason */
    uint32_t motions;                        /* odometry increments applied */
    uint32_t bad_motions;                    /* non-finite increments refused */
    uint32_t searches;                       /* recovery searches run (RSM_METHOD_MAP) */
    uint32_t recovered;                      /* ... whose pose was taken */
    uint32_t ambiguous;                      /* ... whose winner a distinct pose fitted nearly
                                              * as well, or put nearly as many readings on
                                              * walls: not taken (recover_margin) */
    uint32_t global_searches;                /* global searches begun (rsm_localizer_global,
                                              * global_when_lost, or one that proved nothing) */
    uint32_t global_found;                   /* ... that proved a pose, which was taken */
    uint32_t global_ambiguous;               /* ... whose winner fitted too poorly or a rival
                                              * nearly as well, or, crowded, waits for a later
                                              * search to prove it too: begun again on a later
                                              * scan */
    uint32_t global_work;                    /* their cells and blocks read, all scans */
    uint32_t caught_up;                      /* odometry steps that reported motion matching had
                                              * already found (RSM_ODOMETRY_CAUGHT_UP) */
    uint32_t refuted;                        /* odometry steps the scans refuted and that were
                                              * dropped (RSM_ODOMETRY_REFUTED) */
    uint32_t recounted;                      /* matches taken back: odometry counted from before
                                              * them fitted far better (RSM_ODOMETRY_RECOUNTED) */
    uint32_t contradicted;                   /* scans whose beams passed through the map's walls
                                              * beyond conflict_max: refused or not written */
    uint32_t track[RSM_TRACK_STATES];        /* scans that left the estimate in each state (a
                                              * scan refused as out of order leaves none) */
    uint32_t unconfirmed;                    /* returns kept out of the persistent map: no
                                              * neighbour confirmed them (isolation) */
    uint32_t occluded;                       /* returns dropped: behind a surface their
                                              * neighbours span (occlusion) */
    uint32_t unpinned;                       /* matches that left the position along the
                                              * scan's surfaces to the prediction, wholly
                                              * or in part (report.unpinned > 0) */
} rsm_localizer_counters_t;

/* What rsm_localizer_init writes into rsm_localizer_t.magic: the other
 * functions refuse a localizer without it (never initialised, or zeroed). */
#define RSM_LOCALIZER_MAGIC 0x52534d4cUL

/* A tracking recovery spread over scans (RSM_METHOD_MAP): a search within
 * +-radius_m and recover_rad of where the scan that asked for it was
 * predicted, the basins it found descended with that scan's readings, and
 * the winner, once proven, carried by odometry to the scan at hand. The
 * readings are kept in the global search's memory, idle while tracking. */
#define RSM_RECOVER_STARTS 3
typedef struct rsm_recovery {
    uint8_t phase;                    /* idle, searching, descending, proving, taking, resting */
    uint8_t stage;                    /* 0: headings only (a turn misjudged), 1: positions within
                                       * a coarse cell too, 2: within recover_m (each after the one
                                       * before proved nothing) */
    uint8_t fresh;                    /* no scan of it has run yet */
    uint8_t found;                    /* basins the search kept */
    uint8_t done;                     /* descents made (the tracked pose's fit first) */
    uint8_t best;                     /* the winner among them */
    uint8_t proved;                   /* a bit a basin: matched with a scan of the proof */
    uint8_t checked;                  /* the scan searched was checked against the map's walls */
    int32_t heading;                  /* the search's next heading (-fan .. fan) */
    float radius_m;
    float prior[9];                   /* the filter's covariance at the scan searched */
    rsm_pose_t pred;                  /* the prediction there: the search's centre, the prior's mean */
    rsm_pose_t tracked;               /* where tracking put that scan: the rival to beat */
    float tracked_hit;                /* its fit with the scan of the proof */
    rsm_pose_t base;                  /* the estimate that scan ended at: odometry carries the
                                       * winner from there; at rest, where the robot was */
    rsm_pose_t start[RSM_RECOVER_STARTS]; /* the basins, best first */
    float cost[RSM_RECOVER_STARTS];
    int32_t ij[2 * RSM_RECOVER_STARTS];
    rsm_pose_t end[RSM_RECOVER_STARTS];   /* where their descents ended, then their matches
                                           * with the proof's scans (carried back to the
                                           * scan searched) */
    float hit[RSM_RECOVER_STARTS];        /* their descents' fits (< 0: failed, or out of the
                                           * proof); at the verdict, the scan's */
} rsm_recovery_t;

typedef struct rsm_localizer {
    uint32_t magic;                      /* RSM_LOCALIZER_MAGIC once initialised */
    const rsm_localizer_config_t *cfg;   /* kept by pointer */
    rsm_ekf_t ekf;
    rsm_odometry_t odo;
    rsm_odometry_cal_t odo_cal;          /* the correction in force (RSM_METHOD_MAP) */
    /* Only one method runs per localizer, so their states share memory. */
    union {
        struct {
            rsm_map_t map;                        /* scrolling window of hit counts */
            rsm_image_t image;                    /* current scan image */
            rsm_ransac_t ransac;
            uint32_t visited[RSM_BITMAP_WORDS];   /* reference candidates already listed */
            rsm_harris_work_t harris;
            rsm_cell_t cands[RSM_MAX_CANDIDATES];
            rsm_keypoint_t kp_cur[RSM_MAX_KEYPOINTS];
            rsm_keypoint_t kp_ref[RSM_MAX_KEYPOINTS];
            rsm_point_t pt_cur[RSM_MAX_KEYPOINTS];
            rsm_point_t pt_ref[RSM_MAX_KEYPOINTS];
            rsm_match_t matches[RSM_MAX_MATCHES];
        } paper;                                  /* RSM_METHOD_PAPER */
        rsm_icp_t icp;                            /* RSM_METHOD_ICP: its reference scan */
        struct {
            rsm_tmap_t map;                       /* the persistent map */
            rsm_pose_t written;                   /* pose of the last write into it */
            float fit;                            /* recent mean occupancy under a scan's points */
            rsm_pose_t anchor;                    /* the estimate after the last scan */
            rsm_pose_t trusted;                   /* ... after the last scan that trusted
                                                   * odometry's step (before a stall or a
                                                   * refuted step) */
            rsm_pose_t since;                     /* odometry's steps since then, composed */
            rsm_pose_t last_step;                 /* the robot's last step between two scans, as
                                                   * estimated (odometry's where a search
                                                   * jumped) */
            float walk_p[9];                      /* the covariance odometry's steps since the
                                                   * last scan give as a walk of ordinary steps
                                                   * (rsm_odometry_noise_walk): the prior after
                                                   * a gap in the scans ... */
            uint8_t walk_apart;                   /* ... when a step since then was longer
                                                   * than RSM_ODOMETRY_WALK_STEP_M (else the
                                                   * filter's own) */
            rsm_odometry_verdict_t held;          /* why it is held there: a stall (CAUGHT_UP),
                                                   * a refuted step, a large correction
                                                   * (RECOUNTED) */
            float map_fit;                        /* how well the map's own scans fitted it: the
                                                   * fit saved with a loaded map (0: none loaded),
                                                   * the bar of a global search's proof */
            float wall_ref;                       /* the walls' grid direction in the world,
                                                   * modulo a quarter turn, as learnt so far
                                                   * (fixed after the first 20 scans) ... */
            float wall_c;                         /* ... learnt from the first scans: their
                                                   * directions at four times the angle, */
            float wall_s;                         /* summed (cosines, sines) */
            uint32_t wall_scans;                  /* scans summed so far */
            rsm_global_t global;                  /* the global search, when one runs */
            rsm_recovery_t recovery;              /* a recovery in progress, its readings kept in
                                                   * global's (idle while the robot tracks) */
            uint8_t *search_mem;                  /* memory lent to the search's grids ... */
            uint32_t search_bytes;                /* ... and its size (rsm_localizer_set_search_memory) */
        } persistent;                             /* RSM_METHOD_MAP */
    } state;
    rsm_point_t pts[RSM_MAX_BEAMS];      /* usable readings, robot frame */
    /* The usable readings in the world frame, which a map write spread
     * over the next scans reads; no write runs during a global search,
     * whose bound grids take the same memory. */
    union {
        rsm_point_t world[RSM_MAX_BEAMS];
        uint8_t global_grid[RSM_GLOBAL_GRID_BYTES];
    } frame;
    rsm_scan_trig_t trig;                /* the beam angles' cosines and sines */
    uint64_t last_stamp_us;
    uint32_t motions_at_scan;            /* counters.motions when the last scan came */
    uint8_t have_scan;
    uint32_t poor_run;                   /* scans in a row that did not track */
    rsm_localizer_counters_t counters;
    rsm_localizer_report_t last;
} rsm_localizer_t;

/* RSM_OK if cfg is one rsm_localizer_init accepts; else RSM_ERR_INVAL
 * with the first bad field named in *field (when field is not NULL) as its
 * path in the struct: "grid.sigma_m", "odometry.wheel_base_m", "recover_m",
 * "mapmatch" (that part as a whole), "cfg" for NULL. Only the chosen
 * method's part (ransac, icp, or tmap, mapmatch and the map_* and recover_*
 * fields) is checked. The name is a static string. Reads only. */
int rsm_localizer_config_check(const rsm_localizer_config_t *cfg, const char **field);

/* Validates cfg (and each module's part) and starts at pose x0 with
 * covariance p0 (NULL: zero). Returns RSM_OK, or RSM_ERR_INVAL: for a bad
 * cfg with loc untouched (rsm_localizer_config_check names the field);
 * else loc or x0 is NULL, or x0 or p0 is unusable. Coordinates
 * must stay within 1e6 m of the origin (the paper's method refuses a start
 * beyond it; the maps drop points beyond it), and floats resolve only
 * centimetres from about 1e5 m on: far from the origin, work in a frame
 * centred near the robot (docs/robustness.md, "Coordinates").
 * cfg is kept by pointer, not copied: it must outlive loc; its odometry
 * part alone is copied (into loc->odo.cfg), so that
 * rsm_localizer_set_odometry can change it later.
 * A macro: it passes the caller's sizeof(rsm_localizer_t) and capacity
 * digest (RSM_CONFIG_FINGERPRINT), so that an application compiled with
 * other capacities than the library gets RSM_ERR_CONFIG, with nothing
 * written, instead of a state object of the wrong size. */
#define rsm_localizer_init(loc, cfg, x0, p0) \
    rsm_localizer_init_checked((loc), sizeof(rsm_localizer_t), (unsigned long)RSM_CONFIG_FINGERPRINT, (cfg), (x0), (p0))

int rsm_localizer_init_checked(rsm_localizer_t *loc, size_t loc_size, unsigned long fingerprint,
                               const rsm_localizer_config_t *cfg, const rsm_pose_t *x0, const float p0[9]);

/* Predicts with an odometry increment (robot frame at the step's start).
 * Before the first scan it moves the start pose without process noise: the
 * map is anchored where the first scan is taken, so no scan can observe
 * what was lost before it (and a run that starts at the first scan's
 * odometry pose, as rsm-nav --carmen does, gets the same filter as one that
 * drove there from an earlier start). Non-finite increments are refused
 * with RSM_ERR_RANGE and counted. */
int rsm_localizer_motion(rsm_localizer_t *loc, const rsm_motion_t *u);

/* Predicts from raw wheel encoder counters (see rsm_odometry_update_ticks);
 * the first call only latches and returns RSM_ERR_AGAIN. */
int rsm_localizer_ticks(rsm_localizer_t *loc, uint32_t left, uint32_t right);

/* Processes one scan taken at the current predicted pose. A scan with no
 * motion applied since the previous one first predicts a zero increment
 * (the odometry noise floors sigma_trans_min_m and sigma_rot_min_rad):
 * without it a robot with no odometry would keep P at zero and the estimate
 * could never move; such a robot should raise those floors to what it may
 * travel between scans. Always fills
 * *rep (may be NULL) and returns RSM_OK when the estimate is usable,
 * whatever the outcome; rejected scans leave the prediction in place and say
 * why in rep->outcome and the counters. Returns RSM_ERR_ORDER (scan ignored)
 * when its timestamp is older than the previous scan's, RSM_ERR_INVAL for
 * bad arguments or a count above RSM_MAX_BEAMS, RSM_ERR_CONFIG when the
 * caller was compiled with other capacities (its rsm_scan_t is another
 * size: the scan is not read, nothing is written, *rep included). A macro
 * as rsm_sync_scan, passing the caller's sizeof(rsm_scan_t) and
 * RSM_CONFIG_FINGERPRINT. */
#define rsm_localizer_scan(loc, scan, rep)                                                                      \
    rsm_localizer_scan_checked((loc), (scan), sizeof(rsm_scan_t), (unsigned long)RSM_CONFIG_FINGERPRINT, (rep))

int rsm_localizer_scan_checked(rsm_localizer_t *loc, const rsm_scan_t *scan, size_t scan_size,
                               unsigned long fingerprint, rsm_localizer_report_t *rep);

/* Puts the estimate at x with covariance p (NULL: zero), as a caller that
 * knows where the robot is would (it was carried, or a map was loaded and
 * the robot stands where it was saved): the next scan is matched from
 * there; odometry counts from there; the tracking state is tracking again.
 * The map, and how well recent scans fitted it, are kept. Returns RSM_OK, or
 * RSM_ERR_INVAL (loc never initialised, x NULL or not finite, p not
 * finite) with loc unchanged. */
int rsm_localizer_set_pose(rsm_localizer_t *loc, const rsm_pose_t *x, const float p[9]);

/* Forgets where the robot is and searches the whole persistent map for it
 * (RSM_METHOD_MAP): the robot was switched on somewhere in a loaded map,
 * or carried. From the next scan with enough readings on, the search runs
 * over that scan, global_budget work a scan, while odometry
 * keeps counting; scans report RSM_SCAN_SEARCHING and RSM_TRACK_LOST, and
 * nothing is written into the map. When it is done, each pose it kept is
 * descended with a share of that scan (as many a scan as global_budget
 * pays for), and the best is the winner when its fit reaches
 * global_min_fit of the map's own (global_crowded_fit when at least as
 * many poses passed the search unkept as it keeps) and beats every
 * distinct rival's (doubt_m, doubt_rad away) by recover_margin; the
 * winner, carried by odometry to the scan at hand, must fit it as well and be pinned by it:
 * that scan is RSM_SCAN_ACCEPTED with report.recovered set and the
 * estimate tracking again. A verdict left in doubt is made again with the
 * same poses once the robot has moved on, up to 4 times; otherwise, or
 * when the best fits too poorly, the search begins again. Calling it
 * during a search starts over. Returns RSM_OK; RSM_ERR_INVAL for loc NULL
 * or never initialised; RSM_ERR_NOSYS for another method;
 * RSM_ERR_DEGENERATE when the map is empty, RSM_ERR_NOMEM when it is too
 * wide for the search's grids (wider than 2^RSM_GLOBAL_MAX_H cells of the
 * level searched, or than the grid memory holds with blocks 2^(
 * RSM_GLOBAL_MAX_BASE_H) cells apart: 13 km by default); loc unchanged on
 * error. */
int rsm_localizer_global(rsm_localizer_t *loc);

/* rsm_localizer_global over the positions within radius_m of the estimate
 * (as odometry carries it to the scan the search begins with; every
 * heading still), a window that doubles with every second search that
 * proved nothing (each window is searched at two bars: docs/globalsearch.md),
 * until it holds the whole map: for a robot switched on where it
 * was switched off (rsm_localizer_set_pose to the saved pose first), or
 * one whose estimate is known to be near. radius_m 0 is the whole map.
 * Returns as rsm_localizer_global, and RSM_ERR_INVAL for a negative or
 * non-finite radius_m. */
int rsm_localizer_global_near(rsm_localizer_t *loc, float radius_m);

/* 1 while a global search is under way (begun or to begin at the next
 * scan), else 0 (also for loc NULL). */
int rsm_localizer_searching(const rsm_localizer_t *loc);

/* Lends the global search `bytes` of memory at mem for its bound grids,
 * from now on; mem NULL with bytes 0: none, the grids share the memory of
 * the scan a map write reads (RSM_GLOBAL_GRID_BYTES), as without a call.
 * More memory lays the grids' blocks closer: tighter bounds, fewer reads
 * to the same pose (RSM_GLOBAL_LEND_BYTES: about 0.6 times the
 * reads on the Intel log; docs/globalsearch.md); beyond what a map needs
 * for blocks a quarter of each box apart it is not used. The memory must
 * outlive its use, untouched by anything else; rsm_localizer_init forgets
 * it. The grids are built into it at once (as a map load does), and a
 * search under way begins again; in lent memory they stay through the
 * map's writes (a search after tracking with updates on does not build
 * them again; docs/globalsearch.md, "Grids kept through writes"). Returns RSM_OK; RSM_ERR_INVAL for loc
 * never initialised, mem NULL with bytes not 0 or the other way, or fewer
 * bytes than RSM_GLOBAL_GRID_BYTES; RSM_ERR_NOSYS for another method. */
int rsm_localizer_set_search_memory(rsm_localizer_t *loc, void *mem, size_t bytes);

/* Sets the odometry geometry and noise at run time, e.g. from the robot's
 * own calibration once its driver has read it (rsm_p3dx_odometry_config).
 * odo_cfg is validated as rsm_localizer_init validates cfg->odometry and
 * copied into loc (loc->odo.cfg; the caller's struct is free on return,
 * and loc->cfg->odometry, read only by init, is not touched). Increments
 * from the next encoder sample on use it; the latched counts are kept
 * unless counter_bits changes (the next sample then only latches). The
 * corrections learnt so far (loc->odo_cal) start over: they were
 * learnt for the old geometry.
 * Returns RSM_OK, or RSM_ERR_INVAL (loc or odo_cfg NULL, a non-positive or
 * non-finite ticks_per_m_left/right or wheel_base_m, counter_bits outside
 * 16..32, a negative or non-finite noise or plausibility figure) with loc
 * unchanged. */
int rsm_localizer_set_odometry(rsm_localizer_t *loc, const rsm_odometry_config_t *odo_cfg);

/* What the last scan looked like to the localizer: its usable readings
 * (within the range limits, the laser mount applied) in the robot frame,
 * as rsm_localizer_scan matched them (place them at the report's pose to
 * draw them). Copies min(cap, count) points to out (out may be NULL when
 * cap is 0) and returns count: the usable readings of the last scan
 * processed (0 before the first; a scan refused as out of order leaves the
 * previous one's). 0 for loc NULL or never initialised. Reads only. */
size_t rsm_localizer_scan_points(const rsm_localizer_t *loc, rsm_point_t *out, size_t cap);

/* What the persistent map looks like (RSM_METHOD_MAP): the occupancy in
 * [0, 1] of the finest cell holding world point (x, y) (0 where nothing
 * was seen, or the tile was reused), in *occupancy; and, with
 * rsm_localizer_map_bounds, the world box (metres) of the finest tiles
 * held (RSM_ERR_DEGENERATE while the map is empty). Both return RSM_OK,
 * RSM_ERR_NOSYS for another method, or RSM_ERR_INVAL for NULL pointers or
 * loc never initialised (outputs untouched on error). Read only. */
int rsm_localizer_map_occupancy(const rsm_localizer_t *loc, float x, float y, float *occupancy);
int rsm_localizer_map_bounds(const rsm_localizer_t *loc, float *x0, float *y0, float *x1, float *y1);

/* Current estimate; NaN in every field for loc NULL or never initialised. */
rsm_pose_t rsm_localizer_pose(const rsm_localizer_t *loc);

/* Its covariance as the last report gave it, row-major into out[9]: the
 * filter's own plus cov_floor_m and cov_floor_rad squared on the
 * diagonal. RSM_OK, or RSM_ERR_INVAL for NULL pointers or loc never
 * initialised (out untouched). Reads only. */
int rsm_localizer_covariance(const rsm_localizer_t *loc, float out[9]);

/* How far the current estimate can be trusted, as the last scan left it
 * (RSM_TRACK_TRACKING before any scan: the start pose is the caller's).
 * RSM_TRACK_LOST for loc NULL or never initialised. Reads only. */
rsm_track_t rsm_localizer_track(const rsm_localizer_t *loc);

/* Short name of a tracking state ("tracking", "uncertain", "lost";
 * "unknown" past the last). */
const char *rsm_track_name(rsm_track_t t);

/* Short name of an odometry verdict ("trusted", "caught_up", "refuted",
 * "recounted"; "unknown" past the last). */
const char *rsm_odometry_verdict_name(rsm_odometry_verdict_t v);

/* Short name of an outcome, for logs ("accepted", "few_keypoints", ...). */
const char *rsm_outcome_name(rsm_outcome_t o);

/* Short name of a stage, for logs ("grid", "harris", ...; "unknown" past
 * the last). */
const char *rsm_stage_name(rsm_stage_t s);

#ifdef __cplusplus
}
#endif

#endif /* RSM_LOCALIZER_H */
