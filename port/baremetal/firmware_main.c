/* Example firmware main for a Cortex-M4F board: a template, and the image that
 * tools/cross-check measures to report what linking rsm costs.
 *
 * This file is the APPLICATION, not the library: it owns every piece of rsm
 * state, statically, at file scope (the library itself keeps none), and it is
 * the only place where interrupt handlers may reach that state directly.
 *
 * It sets up a millisecond tick clock, two UART receive rings filled from
 * their interrupts, two rsm_link_t on top of them (the Pioneer P3-DX on one
 * serial port, the SICK LMS 2xx on the other), the two drivers and the
 * localizer they feed, then runs the main loop. Everything that differs
 * between boards (clocks, register addresses, pins, interrupt numbers, the
 * vector table, the memory map) is in boards/<board>/ behind boards/board.h:
 *   mps2_an386  boots under QEMU (./tools/test runs it: the devices' ports are
 *               files there, so the drivers' handshakes go out and time out);
 *   stm32f407   an STM32F407 at 168 MHz (docs/bringup-stm32f4.md).
 * RSM_FIRMWARE_RUN_MS, when defined and not 0, ends the run after that many
 * milliseconds with a summary on the console (the emulated board's test).
 *
 * RSM_FIRMWARE_LASER picks, at compile time, what the laser port carries:
 *   RSM_FIRMWARE_LMS   a SICK LMS 2xx (the default; 9600 Bd at power-up,
 *                      switched to 38400);
 *   RSM_FIRMWARE_LD06  an LDRobot LD06/LD19 at 230400 Bd (listen only);
 *   RSM_FIRMWARE_RPLIDAR  a Slamtec RPLIDAR at 115200 Bd (A1, A2M8), run by
 *                      its driver: start-up requests, standard scan, no
 *                      motor command (an A1's motor line is the board's).
 * A spinning lidar's points go through the revolution assembler, one scan
 * a turn (every second point kept: an LD06's 450 a turn at 10 Hz are more
 * than RSM_MAX_BEAMS), de-skewed with the pose the robot's encoder packets
 * give, converted with the same geometry (and TicksMM) as the localizer's.
 * Those images poll both drivers without waiting (read timeouts 0) and
 * sleep until the next interrupt only when neither driver has a deadline
 * due (rsm_p3dx_next_deadline_us, rsm_ldlidar_next_deadline_us,
 * rsm_slamtec_next_deadline_us). */
#include <stddef.h>
#include <stdint.h>

#include "board.h"
#include "rsm/hal.h"
#include "rsm/localizer.h"
#include "rsm/p3dx.h"
#include "rsm/status.h"
#include "rsm/sync.h"
#include "tick_clock.h"
#include "uart_ring.h"

#ifndef RSM_FIRMWARE_RUN_MS
#define RSM_FIRMWARE_RUN_MS 0
#endif

#define RSM_FIRMWARE_LMS 0
#define RSM_FIRMWARE_LD06 1
#define RSM_FIRMWARE_RPLIDAR 2
#ifndef RSM_FIRMWARE_LASER
#define RSM_FIRMWARE_LASER RSM_FIRMWARE_LMS
#endif

#if RSM_FIRMWARE_LASER == RSM_FIRMWARE_LD06
#include "rsm/ldlidar.h"
#define FW_LASER_NAME "LD06"
#define FW_LASER_BAUD 230400u /* the LD06's only rate */
#elif RSM_FIRMWARE_LASER == RSM_FIRMWARE_RPLIDAR
#include "rsm/slamtec.h"
#define FW_LASER_NAME "RPLIDAR"
#define FW_LASER_BAUD 115200u /* A1, A2M8 */
#elif RSM_FIRMWARE_LASER == RSM_FIRMWARE_LMS
#include "rsm/sicklms.h"
#define FW_LASER_NAME "LMS 2xx"
#define FW_LASER_BAUD 9600u   /* the LMS's power-up rate */
#else
#error "RSM_FIRMWARE_LASER: RSM_FIRMWARE_LMS, RSM_FIRMWARE_LD06 or RSM_FIRMWARE_RPLIDAR"
#endif
#define FW_SPINNING (RSM_FIRMWARE_LASER != RSM_FIRMWARE_LMS)
#if FW_SPINNING
#include "rsm/odometry.h"
#include "rsm/revolution.h"
#endif

/* ---- the application's state (caller-owned rsm state, static here) -------- */

/* Milliseconds since the tick started; written only by rsm_app_tick_isr. */
static volatile uint32_t fw_ms_ticks;

static rsm_tick_clock_t fw_tick;          /* 64-bit microseconds from fw_ms_ticks */
static rsm_clock_t fw_clock;              /* fw_tick as an rsm_clock_t */
static rsm_uart_ring_t fw_rx[RSM_BOARD_PORTS]; /* filled by rsm_app_uart_isr */
static rsm_uart_link_config_t fw_uart_cfg[RSM_BOARD_PORTS]; /* filled from the board at start */
static rsm_uart_link_t fw_robot_uart;
static rsm_uart_link_t fw_laser_uart;
static rsm_link_t fw_robot_link;          /* the ARIA driver's */
static rsm_link_t fw_laser_link;          /* the laser driver's */

/* Counters for a debugger or a telemetry frame (count, don't print). */
static struct fw_stats {
    uint32_t robot_overflows;
    uint32_t laser_overflows;
    uint32_t encoder_events;
    uint32_t scan_events;
} fw_stats;

/* The two device drivers and the localizer they feed. The localizer is the
 * largest object (about 116 KiB with the default config.h); the drivers and
 * the fusion go to core-coupled RAM where the board has it. */
static rsm_localizer_config_t fw_loc_cfg;
static rsm_localizer_t fw_localizer;
static RSM_BOARD_CCM rsm_sync_config_t fw_sync_cfg;
static RSM_BOARD_CCM rsm_sync_t fw_sync;  /* fuses each scan with odometry at its own time */
static RSM_BOARD_CCM rsm_p3dx_config_t fw_robot_cfg;
static RSM_BOARD_CCM rsm_p3dx_t fw_robot;
#if RSM_FIRMWARE_LASER == RSM_FIRMWARE_LD06
static RSM_BOARD_CCM rsm_ldlidar_config_t fw_laser_cfg;
static RSM_BOARD_CCM rsm_ldlidar_t fw_laser;
#elif RSM_FIRMWARE_LASER == RSM_FIRMWARE_RPLIDAR
static RSM_BOARD_CCM rsm_slamtec_config_t fw_laser_cfg;
static RSM_BOARD_CCM rsm_slamtec_t fw_laser;
static RSM_BOARD_CCM rsm_slamtec_event_t fw_laser_ev; /* a capsule's points: not on the stack */
#else
static RSM_BOARD_CCM rsm_sicklms_config_t fw_laser_cfg;
static RSM_BOARD_CCM rsm_sicklms_t fw_laser;
/* The one scan the LMS driver decodes into, straight from the telegram;
 * rsm_sync_scan copies it while it waits for odometry, so the next scan
 * may arrive meanwhile. */
static RSM_BOARD_CCM rsm_scan_t fw_scan;
#endif
#if FW_SPINNING
static RSM_BOARD_CCM rsm_rev_config_t fw_rev_cfg;
static RSM_BOARD_CCM rsm_rev_t fw_rev;          /* the turn being gathered, and the last scan */
static RSM_BOARD_CCM rsm_odometry_t fw_rev_odo; /* the encoder counts as a pose, for the de-skew */
static RSM_BOARD_CCM rsm_pose_t fw_rev_pose;
#endif

/* ---- board functions behind the HAL ---------------------------------------- */

static uint32_t fw_read_ms(void *hw)
{
    (void)hw;
    return fw_ms_ticks;
}

static const rsm_tick_clock_config_t fw_tick_cfg = {
    fw_read_ms, NULL, 1000u, 32u
};

/* ---- interrupt handlers (the board's vector table points here) -------------- */

void rsm_app_tick_isr(void)
{
    fw_ms_ticks = fw_ms_ticks + 1u;
}

/* Moves every byte the port holds into its ring; the ring is the only state
 * shared with the main loop, and the ISR is its only producer. */
void rsm_app_uart_isr(rsm_board_port_t port)
{
    void *hw = rsm_board_port_hw(port);
    uint8_t byte;
    while (rsm_board_uart_rx_byte(hw, &byte)) {
        (void)rsm_uart_ring_push(&fw_rx[port], byte);
    }
}

/* ---- console ------------------------------------------------------------------ */

static void fw_stop(const char *what, int status)
{
    rsm_board_put_str("rsm example firmware: ");
    rsm_board_put_str(what);
    rsm_board_put_str(": ");
    rsm_board_put_str(rsm_strerror(status));
    rsm_board_put_str("\n");
    rsm_board_exit(1);
}

/* ---- the laser: set-up, encoder samples, poll ------------------------------------ */

#if FW_SPINNING
/* The revolution assembler and the de-skew's odometry, either lidar's. */
static int fw_turns_init(void)
{
    int rc;
    (void)rsm_rev_config_default(&fw_rev_cfg);
    fw_rev_cfg.mount = fw_loc_cfg.laser_mount; /* the localizer's, for the de-skew */
    fw_rev_cfg.upside_down = fw_loc_cfg.laser_upside_down;
    fw_rev_cfg.keep_every = 2u;                 /* an LD06's 450 points a turn at 10 Hz */
    if ((rc = rsm_rev_init(&fw_rev, &fw_rev_cfg)) != RSM_OK) {
        return rc;
    }
    return rsm_odometry_init(&fw_rev_odo, &fw_loc_cfg.odometry);
}

/* An encoder sample, for the de-skew: the pose it gives, at its stamp.
 * restart: the first of a connection (the counts may have started over). */
static void fw_laser_encoder(const rsm_odometry_sample_t *s, int restart)
{
    rsm_motion_t u;
    if (restart) {
        rsm_odometry_restart(&fw_rev_odo);
    }
    if (rsm_odometry_update_ticks_at(&fw_rev_odo, s->left, s->right, s->stamp_us, &u) == RSM_OK) {
        fw_rev_pose = rsm_odometry_apply(&fw_rev_pose, &u);
    }
    (void)rsm_rev_odometry(&fw_rev, s->stamp_us, &fw_rev_pose);
}

/* The robot's calibration, taken by the localizer: the de-skew's too. */
static void fw_laser_odometry(const rsm_odometry_config_t *odo)
{
    (void)rsm_odometry_set_config(&fw_rev_odo, odo);
}

/* A driver's points into the assembler; each whole turn to the fusion. */
static void fw_turn_points(const rsm_lidar_point_t *pts, size_t n)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        if (rsm_rev_push(&fw_rev, &pts[i]) == 1) {
            (void)rsm_sync_scan(&fw_sync, &fw_rev.scan);
            fw_stats.scan_events++;
        }
    }
}

/* The link was lost: a whole turn still waiting for odometry goes to the
 * fusion with what there is; the turn in progress has a hole. */
static void fw_turns_lost(void)
{
    if (rsm_rev_flush(&fw_rev) == 1) {
        (void)rsm_sync_scan(&fw_sync, &fw_rev.scan);
        fw_stats.scan_events++;
    }
    rsm_rev_reset(&fw_rev);
}
#endif

#if RSM_FIRMWARE_LASER == RSM_FIRMWARE_LD06
static int fw_laser_init(void)
{
    int rc;
    (void)rsm_ldlidar_config_default(&fw_laser_cfg);
    fw_laser_cfg.read_timeout_us = 0u; /* one wait for both links: see the main loop */
    if ((rc = fw_turns_init()) != RSM_OK ||
        (rc = rsm_ldlidar_init(&fw_laser, &fw_laser_link, &fw_clock, &fw_laser_cfg)) != RSM_OK) {
        return rc;
    }
    return rsm_ldlidar_connect(&fw_laser);
}

/* One poll; returns 1 if something happened. */
static int fw_laser_poll(void)
{
    rsm_ldlidar_event_t ev;
    if (rsm_ldlidar_poll(&fw_laser, &ev) != RSM_OK) {
        return 0;
    }
    if (ev.type == RSM_LDLIDAR_EVENT_LINK_LOST) {
        fw_turns_lost();
    } else if (ev.type == RSM_LDLIDAR_EVENT_POINTS) {
        fw_turn_points(ev.points, ev.count);
    }
    return ev.type != RSM_LDLIDAR_EVENT_NONE;
}

static uint64_t fw_laser_deadline(void)
{
    return rsm_ldlidar_next_deadline_us(&fw_laser);
}
#elif RSM_FIRMWARE_LASER == RSM_FIRMWARE_RPLIDAR
static int fw_laser_init(void)
{
    int rc;
    (void)rsm_slamtec_config_default(&fw_laser_cfg);
    fw_laser_cfg.read_timeout_us = 0u; /* one wait for both links: see the main loop */
    if ((rc = fw_turns_init()) != RSM_OK ||
        (rc = rsm_slamtec_init(&fw_laser, &fw_laser_link, &fw_clock, &fw_laser_cfg)) != RSM_OK) {
        return rc;
    }
    /* Connecting only starts the start-up requests; poll drives them. */
    return rsm_slamtec_connect(&fw_laser);
}

static int fw_laser_poll(void)
{
    if (rsm_slamtec_poll(&fw_laser, &fw_laser_ev) != RSM_OK) {
        return 0;
    }
    if (fw_laser_ev.type == RSM_SLAMTEC_EVENT_LINK_LOST) {
        fw_turns_lost();
    } else if (fw_laser_ev.type == RSM_SLAMTEC_EVENT_POINTS) {
        fw_turn_points(fw_laser_ev.points, fw_laser_ev.count);
    }
    return fw_laser_ev.type != RSM_SLAMTEC_EVENT_NONE;
}

static uint64_t fw_laser_deadline(void)
{
    return rsm_slamtec_next_deadline_us(&fw_laser);
}
#else
static int fw_laser_init(void)
{
    int rc;
    (void)rsm_sicklms_config_default(&fw_laser_cfg);
    fw_laser_cfg.baud = 38400u; /* switch the laser up from its power-up 9600 */
    if ((rc = rsm_sicklms_init(&fw_laser, &fw_laser_link, &fw_clock, &fw_laser_cfg, &fw_scan)) != RSM_OK) {
        return rc;
    }
    /* Connecting only starts the handshake; poll drives it. */
    return rsm_sicklms_connect(&fw_laser);
}

static void fw_laser_encoder(const rsm_odometry_sample_t *s, int restart)
{
    (void)s; /* the LMS measures a scan at once: nothing to de-skew */
    (void)restart;
}

static void fw_laser_odometry(const rsm_odometry_config_t *odo)
{
    (void)odo;
}

static int fw_laser_poll(void)
{
    rsm_sicklms_event_t lev;
    if (rsm_sicklms_poll(&fw_laser, &lev) == RSM_OK && lev.type == RSM_SICKLMS_EVENT_SCAN && lev.scan != NULL) {
        (void)rsm_sync_scan(&fw_sync, lev.scan);
        fw_stats.scan_events++;
        return 1;
    }
    return 0;
}
#endif

/* Whether either driver has something to do now even without new bytes
 * (the LMS image's drivers wait inside their polls: never). */
static int fw_deadline_due(uint64_t now_us)
{
#if FW_SPINNING
    return rsm_p3dx_next_deadline_us(&fw_robot) <= now_us || fw_laser_deadline() <= now_us;
#else
    (void)now_us;
    return 0;
#endif
}

/* ---- start-up and main loop ------------------------------------------------- */

int main(void)
{
    uint64_t now_us = 0u;
    int rc;
    int p;

    rsm_board_init();
    rsm_board_put_str("rsm example firmware on ");
    rsm_board_put_str(rsm_board_name);
    rsm_board_put_str(", laser: " FW_LASER_NAME "\n");

    /* Rings first: the interrupts that fill them start below. */
    for (p = 0; p < (int)RSM_BOARD_PORTS; ++p) {
        fw_uart_cfg[p].tx_byte = rsm_board_uart_tx_byte;
        fw_uart_cfg[p].set_baud = rsm_board_uart_set_baud;
        fw_uart_cfg[p].idle = rsm_board_idle;
        fw_uart_cfg[p].hw = rsm_board_port_hw((rsm_board_port_t)p);
        rsm_uart_ring_init(&fw_rx[p]);
    }
    if ((rc = rsm_tick_clock_init(&fw_tick, &fw_tick_cfg, &fw_clock)) != RSM_OK ||
        (rc = rsm_uart_link_init(&fw_robot_uart, &fw_uart_cfg[RSM_BOARD_PORT_ROBOT], &fw_rx[RSM_BOARD_PORT_ROBOT],
                                 &fw_clock, &fw_robot_link)) != RSM_OK ||
        (rc = rsm_uart_link_init(&fw_laser_uart, &fw_uart_cfg[RSM_BOARD_PORT_LASER], &fw_rx[RSM_BOARD_PORT_LASER],
                                 &fw_clock, &fw_laser_link)) != RSM_OK) {
        fw_stop("port set-up", rc);
    }
    /* The P3-DX powers up at 9600 baud. */
    (void)rsm_link_set_baud(&fw_robot_link, 9600u);
    (void)rsm_link_set_baud(&fw_laser_link, FW_LASER_BAUD);
    rsm_board_start_interrupts();

    {
        const rsm_pose_t start = {0.0f, 0.0f, 0.0f};
        fw_loc_cfg = rsm_localizer_config_default();
        (void)rsm_p3dx_config_default(&fw_robot_cfg);
#if FW_SPINNING
        fw_robot_cfg.read_timeout_us = 0u; /* one wait for both links */
#endif
        fw_sync_cfg = rsm_sync_config_default();
        if ((rc = rsm_localizer_init(&fw_localizer, &fw_loc_cfg, &start, NULL)) != RSM_OK ||
            (rc = rsm_sync_init(&fw_sync, &fw_localizer, &fw_sync_cfg, NULL, NULL)) != RSM_OK ||
            (rc = rsm_p3dx_init(&fw_robot, &fw_robot_link, &fw_clock, &fw_robot_cfg)) != RSM_OK ||
            (rc = fw_laser_init()) != RSM_OK) {
            fw_stop("driver set-up", rc);
        }
        /* Connecting only starts the handshake; poll drives it. A link
         * error here is retried by the driver's own timeout. */
        (void)rsm_p3dx_connect(&fw_robot);
    }

    for (;;) {
        int moved = 0;
        /* Keeps the tick clock's 64-bit extension current, and is the time
         * base for everything below. */
        (void)rsm_clock_now_us(&fw_clock, &now_us);

        /* The drivers read their links themselves, never waiting longer
         * than their read timeout; their events feed the localizer. */
        {
            rsm_p3dx_event_t rev;
            const int rst = rsm_p3dx_poll(&fw_robot, &rev);
            if (rst == RSM_OK && rev.type == RSM_P3DX_EVENT_ENCODER) {
                fw_laser_encoder(&rev.encoder.sample, !rev.encoder.has_delta);
                (void)rsm_sync_encoder(&fw_sync, &rev.encoder.sample);
                fw_stats.encoder_events++;
                moved = 1;
            } else if (rst == RSM_OK && rev.type == RSM_P3DX_EVENT_CONNECTED) {
                /* The robot's own calibration (its CONFIGpac's TicksMM),
                 * from the next encoder sample on. */
                rsm_odometry_config_t odo = fw_localizer.odo.cfg;
                if (rsm_p3dx_odometry_config(&fw_robot, &odo) == RSM_OK &&
                    rsm_localizer_set_odometry(&fw_localizer, &odo) == RSM_OK) {
                    fw_laser_odometry(&odo);
                }
            }
            moved |= fw_laser_poll();
        }

        (void)rsm_sync_poll(&fw_sync, now_us); /* a scan waits at most max_wait_us for odometry */
        fw_stats.robot_overflows = rsm_uart_ring_overflows(&fw_rx[RSM_BOARD_PORT_ROBOT]);
        fw_stats.laser_overflows = rsm_uart_ring_overflows(&fw_rx[RSM_BOARD_PORT_LASER]);
#if RSM_FIRMWARE_RUN_MS != 0
        if (now_us >= (uint64_t)RSM_FIRMWARE_RUN_MS * 1000u) {
            rsm_board_put_str("rsm example firmware: ran ");
            rsm_board_put_dec((uint32_t)(now_us / 1000u));
            rsm_board_put_str(" ms: encoder events ");
            rsm_board_put_dec(fw_stats.encoder_events);
            rsm_board_put_str(", scans ");
            rsm_board_put_dec(fw_stats.scan_events);
            rsm_board_put_str(", receive overflows ");
            rsm_board_put_dec(fw_stats.robot_overflows + fw_stats.laser_overflows);
            rsm_board_put_str("\nM stack ");
            rsm_board_put_dec((uint32_t)rsm_stack_used());
            rsm_board_put_str(" of ");
            rsm_board_put_dec((uint32_t)rsm_stack_size());
            rsm_board_put_str("\n");
            rsm_board_exit(0);
        }
#endif
        if (moved == 0 && !fw_deadline_due(now_us)) {
            rsm_board_idle(NULL);
        }
    }
}
