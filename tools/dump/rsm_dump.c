/* rsm-dump: decodes a raw ARIA, SICK LMS 2xx, LD06/LD19 or RPLIDAR byte
 * stream (file, pipe, stdin, serial port, pseudo-terminal) and prints one
 * JSON object per frame, then one object with the receiver's counters.
 *
 * Exit status: 0 when the input was read (whatever it held), 1 when it
 * could not be opened, 2 for bad arguments. */
#include <errno.h>
#include <getopt.h>
#include <inttypes.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "json_out.h"
#include "rsm/aria.h"
#include "rsm/hal.h"
#include "rsm/ld06.h"
#include "rsm/lms.h"
#include "rsm/rplidar.h"
#include "rsm/status.h"
#include "rsm_posix.h"

/* Inter-byte silence after which a partial frame is abandoned (ARIA's
 * receive timeout; also used for the LMS), in ms. */
#define DUMP_GAP_MS 100u

typedef enum dump_proto { PROTO_NONE = 0, PROTO_ARIA, PROTO_LMS, PROTO_LD06, PROTO_RPLIDAR } dump_proto_t;

static const char *const proto_names[] = {"none", "aria", "lms", "ld06", "rplidar"};

typedef struct dump_opts {
    dump_proto_t proto;
    const char *input;
    uint32_t baud;
    uint32_t timeout_ms; /* 0: no silence timeout */
    uint32_t count;      /* 0: no limit; else stop after this many objects */
    int pretty;
    int distance_bits; /* 0: from the format default or a config reply */
} dump_opts_t;

/* Everything the run needs, in one caller-owned struct. */
typedef struct dump_ctx {
    dump_opts_t opt;
    json_out_t out;
    uint64_t seq;          /* objects printed so far */
    uint64_t bytes;        /* bytes read from the input */
    uint64_t decode_errors; /* verified frames whose decoder refused them */
    rsm_aria_parser_t aria;
    rsm_aria_packet_t pkt;
    rsm_lms_parser_t lms;
    rsm_lms_b0_format_t fmt;
    rsm_lms_scan_t scan;
    rsm_ld06_parser_t ld06;
    rsm_rplidar_parser_t rplidar;
    rsm_rplidar_event_t rp_event;
} dump_ctx_t;

static volatile sig_atomic_t stop_requested = 0;

/* --count reached: nothing more is decoded (an exact count for a test on a
 * stream that goes on). */
static int count_reached(const dump_ctx_t *d)
{
    return d->opt.count != 0u && d->seq >= d->opt.count;
}

static void on_signal(int sig)
{
    (void)sig;
    stop_requested = 1;
}

static void usage(FILE *f)
{
    fputs("usage: rsm-dump --protocol aria|lms|ld06|rplidar [--baud N] [--timeout-ms N] [--count N]\n"
          "                [--pretty] [--distance-bits 13..16] INPUT\n"
          "  INPUT         a capture file, a FIFO, a serial port, a pseudo-terminal, or - for stdin\n"
          "  --baud N      line rate for a serial port or pty (default: leave as is)\n"
          "  --timeout-ms  stop after this much silence on a live link (default: never)\n"
          "  --count N     stop once N objects (frames, events) are printed, decoding nothing\n"
          "                after the N-th (default: no limit)\n"
          "  --pretty      indented JSON instead of one object per line\n"
          "  --distance-bits  LMS 0xB0 distance field width (default 13, or from a 0xF4 reply)\n",
          f);
}

static int parse_u32(const char *s, uint32_t *out)
{
    char *end = NULL;
    unsigned long v;
    if (s == NULL || *s == '\0' || *s == '-' || *s == '+') {
        return 0;
    }
    errno = 0;
    v = strtoul(s, &end, 10);
    if (errno != 0 || end == NULL || *end != '\0' || v > 0xFFFFFFFFul) {
        return 0;
    }
    *out = (uint32_t)v;
    return 1;
}

enum { OPT_PROTOCOL = 256, OPT_BAUD, OPT_TIMEOUT_MS, OPT_COUNT, OPT_PRETTY, OPT_DISTANCE_BITS };

static const struct option dump_options[] = {
    {"protocol", required_argument, NULL, OPT_PROTOCOL},
    {"baud", required_argument, NULL, OPT_BAUD},
    {"timeout-ms", required_argument, NULL, OPT_TIMEOUT_MS},
    {"count", required_argument, NULL, OPT_COUNT},
    {"pretty", no_argument, NULL, OPT_PRETTY},
    {"distance-bits", required_argument, NULL, OPT_DISTANCE_BITS},
    {"help", no_argument, NULL, 'h'},
    {NULL, 0, NULL, 0}
};

/* Returns 0 to run, 2 on bad arguments, -1 after --help. Options and the
 * input may come in any order ("-" is the input stdin). */
static int parse_args(int argc, char **argv, dump_opts_t *o)
{
    int opt;
    memset(o, 0, sizeof *o);
    opterr = 0; /* this program words its own messages */
    while ((opt = getopt_long(argc, argv, ":h", dump_options, NULL)) != -1) {
        switch (opt) {
        case 'h':
            usage(stdout);
            return -1;
        case OPT_PRETTY:
            o->pretty = 1;
            break;
        case OPT_PROTOCOL: {
            size_t k;
            for (k = 1; k < sizeof proto_names / sizeof proto_names[0]; ++k) {
                if (strcmp(optarg, proto_names[k]) == 0) {
                    o->proto = (dump_proto_t)k;
                }
            }
            if (o->proto == PROTO_NONE) {
                fprintf(stderr, "rsm-dump: unknown protocol '%s' (aria, lms, ld06 or rplidar)\n", optarg);
                return 2;
            }
            break;
        }
        case OPT_BAUD:
            if (!parse_u32(optarg, &o->baud) || o->baud == 0u) {
                fprintf(stderr, "rsm-dump: --baud needs a positive integer\n");
                return 2;
            }
            break;
        case OPT_TIMEOUT_MS:
            if (!parse_u32(optarg, &o->timeout_ms)) {
                fprintf(stderr, "rsm-dump: --timeout-ms needs a non-negative integer\n");
                return 2;
            }
            break;
        case OPT_COUNT:
            if (!parse_u32(optarg, &o->count) || o->count == 0u) {
                fprintf(stderr, "rsm-dump: --count needs a positive integer\n");
                return 2;
            }
            break;
        case OPT_DISTANCE_BITS: {
            uint32_t b = 0;
            if (!parse_u32(optarg, &b) || b < 13u || b > 16u) {
                fprintf(stderr, "rsm-dump: --distance-bits must be 13..16\n");
                return 2;
            }
            o->distance_bits = (int)b;
            break;
        }
        default: /* unknown option ('?') or a value missing (':') */
            fprintf(stderr, "rsm-dump: unknown or incomplete option '%s'\n", argv[optind - 1]);
            usage(stderr);
            return 2;
        }
    }
    if (optind < argc) {
        o->input = argv[optind++];
    }
    if (optind < argc) {
        fprintf(stderr, "rsm-dump: more than one input given ('%s')\n", argv[optind]);
        return 2;
    }
    if (o->proto == PROTO_NONE) {
        fprintf(stderr, "rsm-dump: --protocol aria|lms|ld06|rplidar is required\n");
        usage(stderr);
        return 2;
    }
    if (o->input == NULL) {
        fprintf(stderr, "rsm-dump: no input given\n");
        usage(stderr);
        return 2;
    }
    return 0;
}

/* ---- ARIA ------------------------------------------------------------------- */

static const char *aria_type_name(uint8_t id)
{
    switch (id) {
    case RSM_ARIA_PAC_SYNC0: return "sync0";
    case RSM_ARIA_PAC_SYNC1: return "sync1";
    case RSM_ARIA_PAC_SYNC2: return "sync2";
    case RSM_ARIA_PAC_CONFIG: return "config";
    case RSM_ARIA_PAC_SIP_STOPPED: return "sip_stopped";
    case RSM_ARIA_PAC_SIP_MOVING: return "sip_moving";
    case RSM_ARIA_PAC_ENCODER: return "encoder";
    case RSM_ARIA_PAC_GYRO: return "gyro";
    case RSM_ARIA_PAC_SERAUX: return "seraux";
    case RSM_ARIA_PAC_SERAUX2: return "seraux2";
    case RSM_ARIA_PAC_IO: return "io";
    default: return "unknown";
    }
}

static void kv_int(json_out_t *w, const char *k, int64_t v)
{
    json_key(w, k);
    json_int(w, v);
}

static void kv_str(json_out_t *w, const char *k, const char *v)
{
    json_key(w, k);
    json_str(w, v);
}

static void kv_hex(json_out_t *w, const char *k, uint32_t v, int width)
{
    json_key(w, k);
    json_hex(w, v, width);
}

static void kv_bool(json_out_t *w, const char *k, int v)
{
    json_key(w, k);
    json_bool(w, v);
}

static void kv_double(json_out_t *w, const char *k, double v)
{
    json_key(w, k);
    json_double(w, v);
}

static void aria_sip_fields(json_out_t *w, const rsm_aria_sip_t *s)
{
    size_t i;
    kv_int(w, "xpos", s->xpos);
    kv_int(w, "ypos", s->ypos);
    kv_int(w, "thpos", s->thpos);
    kv_double(w, "th_deg", (double)s->thpos * 360.0 / 4096.0);
    kv_int(w, "l_vel", s->l_vel);
    kv_int(w, "r_vel", s->r_vel);
    kv_int(w, "battery", s->battery);
    kv_hex(w, "stall_and_bumpers", s->stall_and_bumpers, 4);
    kv_bool(w, "left_stall", (s->stall_and_bumpers & RSM_ARIA_STALL_LEFT) != 0u);
    kv_bool(w, "right_stall", (s->stall_and_bumpers & RSM_ARIA_STALL_RIGHT) != 0u);
    kv_int(w, "control", s->control);
    kv_hex(w, "flags", s->flags, 4);
    kv_bool(w, "motors_enabled", (s->flags & RSM_ARIA_FLAGS_MOTORS_ENABLED) != 0u);
    kv_bool(w, "estop", (s->flags & RSM_ARIA_FLAGS_ESTOP) != 0u);
    kv_int(w, "compass", s->compass);
    kv_int(w, "sonar_count", s->sonar_count);
    json_key(w, "sonar");
    json_begin_arr(w);
    for (i = 0; i < s->sonar_len; ++i) {
        json_begin_obj(w);
        kv_int(w, "num", s->sonar[i].num);
        kv_int(w, "range", s->sonar[i].range);
        json_end_obj(w);
    }
    json_end_arr(w);
    if (s->present & RSM_ARIA_SIP_HAS_GRIP_STATE) {
        kv_int(w, "grip_state", s->grip_state);
    }
    if (s->present & RSM_ARIA_SIP_HAS_ANPORT) {
        kv_int(w, "anport", s->anport);
    }
    if (s->present & RSM_ARIA_SIP_HAS_ANALOG) {
        kv_int(w, "analog", s->analog);
    }
    if (s->present & RSM_ARIA_SIP_HAS_DIGIN) {
        kv_hex(w, "digin", s->digin, 2);
    }
    if (s->present & RSM_ARIA_SIP_HAS_DIGOUT) {
        kv_hex(w, "digout", s->digout, 2);
    }
    if (s->present & RSM_ARIA_SIP_HAS_BATTERY_X10) {
        kv_int(w, "battery_x10", s->battery_x10);
    }
    if (s->present & RSM_ARIA_SIP_HAS_CHARGE_STATE) {
        kv_int(w, "charge_state", s->charge_state);
    }
    if (s->present & RSM_ARIA_SIP_HAS_ROT_VEL) {
        kv_int(w, "rot_vel", s->rot_vel);
        kv_double(w, "rot_vel_deg_s", (double)s->rot_vel / 10.0);
    }
    if (s->present & RSM_ARIA_SIP_HAS_FAULT_FLAGS) {
        kv_hex(w, "fault_flags", s->fault_flags, 4);
    }
    if (s->present & RSM_ARIA_SIP_HAS_LAT_VEL) {
        kv_int(w, "lat_vel", s->lat_vel);
    }
    if (s->present & RSM_ARIA_SIP_HAS_TEMPERATURE) {
        kv_int(w, "temperature", s->temperature);
    }
    if (s->present & RSM_ARIA_SIP_HAS_STATE_OF_CHARGE) {
        kv_int(w, "state_of_charge", s->state_of_charge);
    }
    if (s->present & RSM_ARIA_SIP_HAS_UC_TIME) {
        kv_int(w, "uc_time", s->uc_time);
    }
    if (s->present & RSM_ARIA_SIP_HAS_FLAGS3) {
        kv_hex(w, "flags3", s->flags3, 8);
    }
}

static void aria_config_fields(json_out_t *w, const rsm_aria_config_t *c)
{
    kv_str(w, "robot_type", c->robot_type);
    kv_str(w, "subtype", c->subtype);
    kv_str(w, "serial_num", c->serial_num);
    kv_int(w, "four_mot", c->four_mot);
    kv_int(w, "rot_vel_top", c->rot_vel_top);
    kv_int(w, "trans_vel_top", c->trans_vel_top);
    kv_int(w, "rot_acc_top", c->rot_acc_top);
    kv_int(w, "trans_acc_top", c->trans_acc_top);
    kv_int(w, "pwm_max", c->pwm_max);
    kv_str(w, "name", c->name);
    kv_int(w, "sip_cycle", c->sip_cycle);
    kv_int(w, "host_baud", c->host_baud);
    kv_int(w, "aux1_baud", c->aux1_baud);
    kv_int(w, "has_gripper", c->has_gripper);
    kv_int(w, "front_sonar", c->front_sonar);
    kv_int(w, "rear_sonar", c->rear_sonar);
    kv_int(w, "low_battery", c->low_battery);
    kv_int(w, "rev_count", c->rev_count);
    kv_int(w, "watchdog", c->watchdog);
    kv_int(w, "normal_mpacs", c->normal_mpacs);
    kv_int(w, "stall_val", c->stall_val);
    kv_int(w, "stall_count", c->stall_count);
    kv_int(w, "joy_vel", c->joy_vel);
    kv_int(w, "joy_rot_vel", c->joy_rot_vel);
    kv_int(w, "rot_vel_max", c->rot_vel_max);
    kv_int(w, "trans_vel_max", c->trans_vel_max);
    kv_int(w, "rot_accel", c->rot_accel);
    kv_int(w, "rot_decel", c->rot_decel);
    kv_int(w, "rot_kp", c->rot_kp);
    kv_int(w, "rot_kv", c->rot_kv);
    kv_int(w, "rot_ki", c->rot_ki);
    kv_int(w, "trans_accel", c->trans_accel);
    kv_int(w, "trans_decel", c->trans_decel);
    kv_int(w, "trans_kp", c->trans_kp);
    kv_int(w, "trans_kv", c->trans_kv);
    kv_int(w, "trans_ki", c->trans_ki);
    kv_int(w, "front_bumps", c->front_bumps);
    kv_int(w, "rear_bumps", c->rear_bumps);
    kv_int(w, "charger", c->charger);
    kv_int(w, "sonar_cycle", c->sonar_cycle);
    kv_int(w, "auto_baud", c->auto_baud);
    kv_int(w, "has_gyro", c->has_gyro);
    kv_int(w, "drift_factor", c->drift_factor);
    kv_int(w, "aux2_baud", c->aux2_baud);
    kv_int(w, "aux3_baud", c->aux3_baud);
    kv_int(w, "ticks_mm", c->ticks_mm);
    if (c->present & RSM_ARIA_CONFIG_HAS_SHUTDOWN_VOLTS) {
        kv_int(w, "shutdown_volts", c->shutdown_volts);
    }
    if (c->present & RSM_ARIA_CONFIG_HAS_FIRMWARE) {
        kv_str(w, "firmware", c->firmware);
    }
}

static void emit_aria_packet(dump_ctx_t *d)
{
    json_out_t *w = &d->out;
    const rsm_aria_packet_t *p = &d->pkt;
    const uint8_t *payload = rsm_aria_payload(p);
    int status = RSM_OK;
    json_begin_obj(w);
    kv_int(w, "seq", (int64_t)d->seq++);
    kv_str(w, "protocol", "aria");
    kv_int(w, "id", p->id);
    kv_hex(w, "id_hex", p->id, 2);
    kv_str(w, "type", aria_type_name(p->id));
    kv_int(w, "length", (int64_t)p->frame_len);
    switch (p->id) {
    case RSM_ARIA_PAC_SYNC0:
    case RSM_ARIA_PAC_SYNC1:
        json_key(w, "fields");
        json_begin_obj(w);
        kv_int(w, "step", rsm_aria_decode_sync(p));
        json_end_obj(w);
        break;
    case RSM_ARIA_PAC_SYNC2: {
        rsm_aria_sync2_t s;
        status = rsm_aria_decode_sync2(p, &s);
        if (status == RSM_OK) {
            json_key(w, "fields");
            json_begin_obj(w);
            kv_int(w, "step", 2);
            kv_int(w, "present", s.present);
            kv_str(w, "name", s.name);
            kv_str(w, "class", s.robot_class);
            kv_str(w, "subclass", s.subclass);
            json_end_obj(w);
        }
        break;
    }
    case RSM_ARIA_PAC_SIP_STOPPED:
    case RSM_ARIA_PAC_SIP_MOVING: {
        static rsm_aria_sip_t s; /* large with many sonars; single-threaded tool */
        status = rsm_aria_decode_sip(p, &s);
        if (status == RSM_OK) {
            json_key(w, "fields");
            json_begin_obj(w);
            aria_sip_fields(w, &s);
            json_end_obj(w);
        }
        break;
    }
    case RSM_ARIA_PAC_ENCODER: {
        rsm_aria_encoder_t e;
        status = rsm_aria_decode_encoder(p, &e);
        if (status == RSM_OK) {
            json_key(w, "fields");
            json_begin_obj(w);
            kv_int(w, "left", e.left);
            kv_int(w, "right", e.right);
            json_end_obj(w);
        }
        break;
    }
    case RSM_ARIA_PAC_CONFIG: {
        static rsm_aria_config_t c;
        status = rsm_aria_decode_config(p, &c);
        if (status == RSM_OK) {
            json_key(w, "fields");
            json_begin_obj(w);
            aria_config_fields(w, &c);
            json_end_obj(w);
        }
        break;
    }
    default:
        json_key(w, "payload_hex");
        json_hexbytes(w, payload, p->payload_len);
        break;
    }
    if (status != RSM_OK) {
        d->decode_errors++;
        kv_str(w, "error", rsm_strerror(status));
        json_key(w, "payload_hex");
        json_hexbytes(w, payload, p->payload_len);
    }
    json_end_obj(w);
}

/* Feeds bytes (len may be 0 to drain) and prints every packet. */
/* The *_feed functions return the bytes they decoded (all of buf unless
 * --count was reached). */
static size_t aria_feed(dump_ctx_t *d, const uint8_t *buf, size_t len)
{
    size_t off = 0;
    while (!count_reached(d)) {
        size_t used = 0;
        const int r = rsm_aria_parser_feed(&d->aria, buf + off, len - off, &used, &d->pkt);
        off += used;
        if (r == 1) {
            emit_aria_packet(d);
            continue;
        }
        break;
    }
    return off;
}

static void aria_gap(dump_ctx_t *d)
{
    int guard = 0;
    /* Each timeout abandons one candidate; drain until nothing is held. */
    while (rsm_aria_parser_pending(&d->aria) > 0u && guard++ < 1000) {
        (void)rsm_aria_parser_timeout(&d->aria);
        (void)aria_feed(d, NULL, 0);
    }
}

/* ---- LMS ------------------------------------------------------------------------ */

static const char *lms_type_name(uint8_t cmd)
{
    switch (cmd) {
    case RSM_LMS_REPLY_POWER_ON: return "power_on";
    case RSM_LMS_REPLY_RESET: return "reset";
    case RSM_LMS_REPLY_NOT_ACK: return "not_acknowledged";
    case RSM_LMS_REPLY_MODE: return "mode";
    case RSM_LMS_REPLY_VALUES: return "values";
    case RSM_LMS_REPLY_STATUS: return "status";
    case RSM_LMS_REPLY_TYPE: return "type";
    case RSM_LMS_REPLY_VARIANT: return "variant";
    case RSM_LMS_REPLY_CONFIG: return "config";
    case RSM_LMS_REPLY_SET_CONFIG: return "set_config";
    default: return "unknown";
    }
}

static const char *lms_code_name(uint8_t code)
{
    switch (code) {
    case RSM_LMS_READING_OK: return "ok";
    case RSM_LMS_READING_NO_ECHO: return "no_echo";
    case RSM_LMS_READING_DAZZLED: return "dazzled";
    case RSM_LMS_READING_OVERFLOW: return "overflow";
    case RSM_LMS_READING_SNR_LOW: return "snr_low";
    case RSM_LMS_READING_CHANNEL_ERROR: return "channel_error";
    case RSM_LMS_READING_TOO_FAR: return "too_far";
    default: return "reserved";
    }
}

static void lms_config_fields(json_out_t *w, const rsm_lms_config_t *c)
{
    kv_int(w, "blanking", c->blanking);
    kv_int(w, "stop_threshold", c->stop_threshold);
    kv_int(w, "peak_threshold", c->peak_threshold);
    kv_hex(w, "availability", c->availability, 2);
    kv_hex(w, "measuring_mode", c->measuring_mode, 2);
    kv_str(w, "units", c->units == RSM_LMS_UNITS_MM ? "mm" : c->units == RSM_LMS_UNITS_CM ? "cm" : "other");
    json_key(w, "block_hex");
    json_hexbytes(w, c->block, c->block_len);
}

static int lms_b0_fields(dump_ctx_t *d, const rsm_lms_telegram_t *t)
{
    json_out_t *w = &d->out;
    rsm_lms_scan_t *s = &d->scan;
    size_t i;
    const int status = rsm_lms_decode_b0(t, &d->fmt, s);
    if (status != RSM_OK) {
        return status;
    }
    json_key(w, "fields");
    json_begin_obj(w);
    kv_int(w, "count", (int64_t)s->count);
    kv_hex(w, "count_word", s->count_word, 4);
    kv_str(w, "units", s->units == RSM_LMS_UNITS_MM ? "mm" : "cm");
    kv_int(w, "distance_bits", d->fmt.distance_bits);
    kv_int(w, "partial", s->partial);
    kv_int(w, "partial_index", s->partial_index);
    if (s->step_cdeg != 0u) {
        kv_double(w, "start_deg", (double)s->start_cdeg / 100.0);
        kv_double(w, "step_deg", (double)s->step_cdeg / 100.0);
    } else {
        json_key(w, "start_deg");
        json_null(w);
        json_key(w, "step_deg");
        json_null(w);
    }
    if (s->index_len > 0u) {
        json_key(w, "index_hex");
        json_hexbytes(w, s->index, s->index_len);
    }
    json_key(w, "ranges_m");
    json_begin_arr(w);
    for (i = 0; i < s->count; ++i) {
        if (s->reading[i].code == RSM_LMS_READING_OK) {
            json_double(w, (double)s->reading[i].range_m);
        } else {
            json_null(w);
        }
    }
    json_end_arr(w);
    json_key(w, "codes");
    json_begin_arr(w);
    for (i = 0; i < s->count; ++i) {
        json_str(w, lms_code_name(s->reading[i].code));
    }
    json_end_arr(w);
    json_key(w, "flags");
    json_begin_arr(w);
    for (i = 0; i < s->count; ++i) {
        json_int(w, s->reading[i].flags);
    }
    json_end_arr(w);
    json_key(w, "raw");
    json_begin_arr(w);
    for (i = 0; i < s->count; ++i) {
        json_int(w, s->reading[i].raw);
    }
    json_end_arr(w);
    json_end_obj(w);
    return RSM_OK;
}

static int lms_text_fields(json_out_t *w, const rsm_lms_telegram_t *t)
{
    rsm_lms_text_reply_t r;
    const int status = t->cmd == RSM_LMS_REPLY_POWER_ON ? rsm_lms_decode_power_on(t, &r)
                                                         : rsm_lms_decode_type_reply(t, &r);
    if (status == RSM_OK) {
        json_key(w, "fields");
        json_begin_obj(w);
        json_key(w, "text");
        json_strn(w, r.text, r.text_len);
        json_end_obj(w);
    }
    return status;
}

static void emit_lms_telegram(dump_ctx_t *d, const rsm_lms_telegram_t *t)
{
    json_out_t *w = &d->out;
    int status = RSM_OK;
    json_begin_obj(w);
    kv_int(w, "seq", (int64_t)d->seq++);
    kv_str(w, "protocol", "lms");
    kv_str(w, "event", "telegram");
    kv_hex(w, "address", t->adr, 2);
    kv_int(w, "cmd", t->cmd);
    kv_hex(w, "cmd_hex", t->cmd, 2);
    kv_str(w, "type", lms_type_name(t->cmd));
    kv_int(w, "length", t->len);
    if (t->data_len > 0u) {
        rsm_lms_status_byte_t sb;
        const uint8_t raw = t->data[t->data_len - 1u];
        (void)rsm_lms_decode_status_byte(raw, &sb);
        kv_hex(w, "status", raw, 2);
        kv_int(w, "severity", sb.severity);
        kv_bool(w, "implausible", sb.implausible);
        kv_bool(w, "pollution", sb.pollution);
    }
    switch (t->cmd) {
    case RSM_LMS_REPLY_VALUES:
        status = lms_b0_fields(d, t);
        break;
    case RSM_LMS_REPLY_MODE: {
        rsm_lms_mode_reply_t r;
        status = rsm_lms_decode_mode_reply(t, &r);
        if (status == RSM_OK) {
            json_key(w, "fields");
            json_begin_obj(w);
            kv_int(w, "result", r.result);
            json_end_obj(w);
        }
        break;
    }
    case RSM_LMS_REPLY_VARIANT: {
        rsm_lms_variant_reply_t r;
        status = rsm_lms_decode_variant_reply(t, &r);
        if (status == RSM_OK) {
            json_key(w, "fields");
            json_begin_obj(w);
            kv_int(w, "result", r.result);
            kv_int(w, "angle_deg", r.angle_deg);
            kv_int(w, "resolution_cdeg", r.resolution_cdeg);
            json_end_obj(w);
        }
        break;
    }
    case RSM_LMS_REPLY_RESET: {
        uint8_t st;
        status = rsm_lms_decode_reset_reply(t, &st);
        break;
    }
    case RSM_LMS_REPLY_NOT_ACK: {
        uint8_t st;
        status = rsm_lms_decode_not_ack(t, &st);
        break;
    }
    case RSM_LMS_REPLY_POWER_ON:
    case RSM_LMS_REPLY_TYPE:
        status = lms_text_fields(w, t);
        break;
    case RSM_LMS_REPLY_CONFIG: {
        rsm_lms_config_t c;
        status = rsm_lms_decode_config(t, &c);
        if (status == RSM_OK) {
            rsm_lms_b0_format_t f;
            json_key(w, "fields");
            json_begin_obj(w);
            lms_config_fields(w, &c);
            json_end_obj(w);
            /* Later 0xB0 telegrams follow this configuration, unless the
             * user fixed the distance width on the command line. */
            if (d->opt.distance_bits == 0 && rsm_lms_b0_format_from_config(&c, &f) == RSM_OK) {
                d->fmt = f;
            }
        }
        break;
    }
    case RSM_LMS_REPLY_SET_CONFIG: {
        rsm_lms_config_reply_t r;
        status = rsm_lms_decode_config_reply(t, &r);
        if (status == RSM_OK) {
            json_key(w, "fields");
            json_begin_obj(w);
            kv_int(w, "result", r.result);
            lms_config_fields(w, &r.config);
            json_end_obj(w);
        }
        break;
    }
    default:
        json_key(w, "data_hex");
        json_hexbytes(w, t->data, t->data_len);
        break;
    }
    if (status != RSM_OK) {
        d->decode_errors++;
        kv_str(w, "error", rsm_strerror(status));
        json_key(w, "data_hex");
        json_hexbytes(w, t->data, t->data_len);
    }
    json_end_obj(w);
}

static void emit_lms_event(dump_ctx_t *d, const rsm_lms_event_t *ev)
{
    if (ev->type == RSM_LMS_EVENT_TELEGRAM) {
        emit_lms_telegram(d, &ev->telegram);
        return;
    }
    json_begin_obj(&d->out);
    kv_int(&d->out, "seq", (int64_t)d->seq++);
    kv_str(&d->out, "protocol", "lms");
    kv_str(&d->out, "event", ev->type == RSM_LMS_EVENT_ACK ? "ack" : "nak");
    json_end_obj(&d->out);
}

static size_t lms_feed(dump_ctx_t *d, const uint8_t *buf, size_t len)
{
    size_t off = 0;
    while (!count_reached(d)) {
        size_t used = 0;
        rsm_lms_event_t ev;
        const int r = rsm_lms_parser_feed(&d->lms, buf + off, len - off, &used, &ev);
        off += used;
        if (r == 1) {
            emit_lms_event(d, &ev);
            continue;
        }
        break;
    }
    return off;
}

static void lms_gap(dump_ctx_t *d)
{
    rsm_lms_event_t ev;
    int guard = 0;
    while (rsm_lms_parser_timeout(&d->lms, &ev) == 1 && guard++ < 100000) {
        emit_lms_event(d, &ev);
    }
}

/* ---- spinning lidars ----------------------------------------------------------------- */

/* points: [[angle_deg, range_m, quality, start], ...] */
static void lidar_points(json_out_t *w, const rsm_lidar_point_t *p, size_t n)
{
    size_t i;
    json_key(w, "points");
    json_begin_arr(w);
    for (i = 0; i < n; ++i) {
        json_begin_arr(w);
        json_double(w, (double)p[i].angle_deg);
        json_double(w, (double)p[i].range_m);
        json_int(w, p[i].quality);
        json_int(w, p[i].start);
        json_end_arr(w);
    }
    json_end_arr(w);
}

static size_t ld06_feed(dump_ctx_t *d, const uint8_t *buf, size_t len)
{
    size_t off = 0;
    rsm_ld06_packet_t pkt;
    rsm_lidar_point_t pts[RSM_LD06_POINTS];
    while (off < len && !count_reached(d)) {
        size_t used = 0;
        const int r = rsm_ld06_parser_feed(&d->ld06, buf + off, len - off, &used, &pkt);
        off += used;
        if (r != 1) {
            break;
        }
        json_begin_obj(&d->out);
        kv_int(&d->out, "seq", (int64_t)d->seq++);
        kv_str(&d->out, "protocol", "ld06");
        kv_str(&d->out, "type", "packet");
        kv_int(&d->out, "speed_dps", pkt.speed_dps);
        kv_int(&d->out, "start_cdeg", pkt.start_cdeg);
        kv_int(&d->out, "end_cdeg", pkt.end_cdeg);
        kv_int(&d->out, "timestamp_ms", pkt.timestamp_ms);
        (void)rsm_ld06_points(&pkt, pts);
        lidar_points(&d->out, pts, RSM_LD06_POINTS);
        json_end_obj(&d->out);
    }
    return off;
}

static void emit_rplidar_event(dump_ctx_t *d, const rsm_rplidar_event_t *e)
{
    static const char *const names[] = {"none", "descriptor", "info", "health", "samplerate",
                                        "points"};
    json_out_t *w = &d->out;
    json_begin_obj(w);
    kv_int(w, "seq", (int64_t)d->seq++);
    kv_str(w, "protocol", "rplidar");
    kv_str(w, "type", names[e->type]);
    kv_hex(w, "answer", e->answer, 2);
    switch (e->type) {
    case RSM_RPLIDAR_EVENT_INFO:
        kv_int(w, "model", e->info.model);
        kv_int(w, "firmware_major", e->info.firmware_major);
        kv_int(w, "firmware_minor", e->info.firmware_minor);
        kv_int(w, "hardware", e->info.hardware);
        json_key(w, "serial_hex");
        json_hexbytes(w, e->info.serial, sizeof e->info.serial);
        break;
    case RSM_RPLIDAR_EVENT_HEALTH:
        kv_int(w, "status", e->health.status);
        kv_int(w, "error_code", e->health.error_code);
        break;
    case RSM_RPLIDAR_EVENT_SAMPLERATE:
        kv_int(w, "standard_us", e->samplerate.standard_us);
        kv_int(w, "express_us", e->samplerate.express_us);
        break;
    case RSM_RPLIDAR_EVENT_POINTS:
        lidar_points(w, e->points, e->count);
        break;
    default:
        break;
    }
    json_end_obj(w);
}

static size_t rplidar_feed(dump_ctx_t *d, const uint8_t *buf, size_t len)
{
    size_t off = 0;
    while (off < len && !count_reached(d)) {
        size_t used = 0;
        const int r = rsm_rplidar_parser_feed(&d->rplidar, buf + off, len - off, &used, &d->rp_event);
        off += used;
        if (r != 1) {
            break;
        }
        emit_rplidar_event(d, &d->rp_event);
    }
    return off;
}

/* ---- run ---------------------------------------------------------------------------- */

/* Returns the bytes decoded (fewer than len once --count is reached). */
static size_t feed(dump_ctx_t *d, const uint8_t *buf, size_t len)
{
    switch (d->opt.proto) {
    case PROTO_ARIA:
        return aria_feed(d, buf, len);
    case PROTO_LMS:
        return lms_feed(d, buf, len);
    case PROTO_LD06:
        return ld06_feed(d, buf, len);
    default:
        return rplidar_feed(d, buf, len);
    }
}

static void gap(dump_ctx_t *d)
{
    switch (d->opt.proto) {
    case PROTO_ARIA:
        aria_gap(d);
        break;
    case PROTO_LMS:
        lms_gap(d);
        break;
    case PROTO_LD06:
        (void)rsm_ld06_parser_flush(&d->ld06);
        break;
    default:
        (void)rsm_rplidar_parser_flush(&d->rplidar);
        break;
    }
}

/* The counters every receiver keeps, under the same names. */
static void framing_counts(json_out_t *w, uint32_t frames, uint32_t skipped, uint32_t checksum,
                           uint32_t truncated)
{
    kv_int(w, "frames", frames);
    kv_int(w, "bytes_skipped", skipped);
    kv_int(w, "checksum_errors", checksum);
    kv_int(w, "truncated", truncated);
}

static void emit_summary(dump_ctx_t *d, const char *end, int err)
{
    json_out_t *w = &d->out;
    json_begin_obj(w);
    kv_bool(w, "summary", 1);
    kv_str(w, "protocol", proto_names[d->opt.proto]);
    kv_int(w, "bytes", (int64_t)d->bytes);
    if (d->opt.proto == PROTO_ARIA) {
        const rsm_aria_parser_stats_t *s = &d->aria.stats;
        framing_counts(w, s->packets_ok, s->bytes_skipped, s->checksum_errors, s->truncated);
        kv_int(w, "bad_length", s->bad_length);
    } else if (d->opt.proto == PROTO_LD06) {
        const rsm_ld06_stats_t *s = &d->ld06.stats;
        framing_counts(w, s->packets_ok, s->bytes_skipped, s->crc_errors, s->truncated);
        kv_int(w, "bad_fields", s->bad_fields);
    } else if (d->opt.proto == PROTO_RPLIDAR) {
        const rsm_rplidar_stats_t *s = &d->rplidar.stats;
        framing_counts(w, s->descriptors + s->responses + s->nodes + s->capsules, s->bytes_skipped,
                       s->checksum_errors, s->truncated);
        kv_int(w, "bad_descriptors", s->bad_descriptors);
        kv_int(w, "bad_nodes", s->bad_nodes);
        kv_int(w, "unpaired", s->unpaired);
        kv_int(w, "points", s->points);
    } else {
        const rsm_lms_parser_stats_t *s = &d->lms.stats;
        framing_counts(w, s->telegrams_ok, s->bytes_skipped, s->crc_errors, s->truncated);
        kv_int(w, "bad_length", s->bad_length);
        kv_int(w, "acks", s->acks);
        kv_int(w, "naks", s->naks);
    }
    kv_int(w, "decode_errors", (int64_t)d->decode_errors);
    kv_str(w, "end", end);
    if (err != 0) {
        kv_int(w, "errno", err);
        kv_str(w, "error", strerror(err));
    }
    json_end_obj(w);
}

static int run(dump_ctx_t *d)
{
    rsm_posix_auto_link_t ls;
    rsm_link_t link;
    uint8_t buf[4096];
    uint64_t last_rx_ms;
    int gap_done = 1;
    const char *end = "eof";
    int end_errno = 0;
    int status;

    status = rsm_posix_link_open_auto(&ls, d->opt.input, d->opt.baud, 0u, &link);
    if (status != RSM_OK) {
        const int e = rsm_posix_auto_errno(&ls);
        fprintf(stderr, "rsm-dump: cannot open '%s': %s%s%s\n", d->opt.input,
                e != 0 ? strerror(e) : rsm_strerror(status), e != 0 ? " - " : "",
                e != 0 ? rsm_strerror(status) : "");
        return 1;
    }
    last_rx_ms = rsm_posix_clock_now_us(NULL) / 1000u;
    while (!stop_requested) {
        uint64_t now_ms;
        uint32_t wait_ms = DUMP_GAP_MS;
        int n;
        if (d->opt.timeout_ms != 0u && d->opt.timeout_ms < wait_ms) {
            wait_ms = d->opt.timeout_ms;
        }
        n = rsm_link_read(&link, buf, sizeof buf, wait_ms * 1000u);
        now_ms = rsm_posix_clock_now_us(NULL) / 1000u;
        if (n > 0) {
            /* Only what was decoded counts: the summary's bytes stay the sum
             * of the frames and the bytes skipped. */
            d->bytes += (uint64_t)feed(d, buf, (size_t)n);
            last_rx_ms = now_ms;
            gap_done = 0;
            fflush(stdout);
            if (count_reached(d)) {
                end = "count";
                break;
            }
            continue;
        }
        if (n < 0) {
            if (rsm_posix_auto_eof(&ls)) {
                end = "eof";
            } else {
                end = "io_error";
                end_errno = rsm_posix_auto_errno(&ls);
            }
            break;
        }
        /* Silence: abandon a partial frame after the inter-byte gap (a no-op
         * when nothing is held). */
        if (!gap_done && now_ms - last_rx_ms >= DUMP_GAP_MS) {
            gap(d);
            gap_done = 1;
            if (count_reached(d)) {
                end = "count"; /* the count's last frame came out of the gap */
                break;
            }
        }
        if (d->opt.timeout_ms != 0u && now_ms - last_rx_ms >= d->opt.timeout_ms) {
            end = "silence";
            break;
        }
    }
    if (stop_requested) {
        end = "interrupted";
    }
    gap(d);
    emit_summary(d, end, end_errno);
    (void)rsm_posix_link_close(&ls);
    return 0;
}

int main(int argc, char **argv)
{
    static dump_ctx_t d; /* large (parser buffers, a scan): not on the stack */
    struct sigaction sa;
    int r;

    memset(&d, 0, sizeof d);
    r = parse_args(argc, argv, &d.opt);
    if (r != 0) {
        return r < 0 ? 0 : r;
    }
    json_out_init(&d.out, stdout, d.opt.pretty);
    (void)rsm_aria_parser_init(&d.aria);
    (void)rsm_lms_parser_init(&d.lms);
    (void)rsm_ld06_parser_init(&d.ld06);
    (void)rsm_rplidar_parser_init(&d.rplidar);
    (void)rsm_lms_b0_format_default(&d.fmt);
    if (d.opt.distance_bits != 0) {
        d.fmt.distance_bits = (uint8_t)d.opt.distance_bits;
    }

    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    (void)sigaction(SIGINT, &sa, NULL);
    (void)sigaction(SIGTERM, &sa, NULL);

    r = run(&d);
    fflush(stdout);
    return r;
}
