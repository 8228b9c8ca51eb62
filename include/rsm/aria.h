/* ARIA client protocol codec for a Pioneer P3-DX running ARCOS: packet
 * framing and checksum, command encoders, an incremental receiver and
 * decoders for the packets a client needs (SYNC replies, standard SIP,
 * ENCODER, CONFIG). Pure data in, data out: no I/O, no clocks, no heap,
 * no hidden state. Every state object is owned by the caller.
 *
 * Wire format (both directions):
 *     FA FB N ID payload[N-3] CKH CKL
 * N counts the bytes after itself (ID + payload + 2 checksum bytes), so a
 * frame is N + 3 bytes long, 6 .. 258. The checksum covers ID + payload.
 * Multi-byte data fields are little-endian; the checksum is big-endian.
 *
 * Field names follow the ARCOS manual (XPOS, THPOS, L VEL ...) in lower
 * snake case. Units are the raw protocol units of a P3-DX with ARCOS
 * (mm, mm/s, 2*pi/4096 rad, 0.1 V ...) unless a comment says otherwise. */
#ifndef RSM_ARIA_H
#define RSM_ARIA_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/config.h"
#include "rsm/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Capacities (RSM_ARIA_MAX_PACKET, RSM_ARIA_MAX_SONAR, RSM_ARIA_STR_SIZE)
 * are in rsm/config.h. They size the parser, the packet and the SYNC2, SIP
 * and CONFIGpac structs, so every function that sets one of those up or
 * fills it (rsm_aria_parser_init, rsm_aria_parser_feed,
 * rsm_aria_packet_build, rsm_aria_decode_sync2, _sip and _config) is a
 * macro, as rsm_localizer_init: it passes the caller's sizeof and
 * RSM_CONFIG_FINGERPRINT to the function of the same name ending in
 * _checked, which returns RSM_ERR_CONFIG, with nothing written, to a caller
 * compiled with other capacities than the library. */

/* ---- framing constants ------------------------------------------------------ */

#define RSM_ARIA_SYNC_1 0xFAu     /* first header byte */
#define RSM_ARIA_SYNC_2 0xFBu     /* second header byte */
#define RSM_ARIA_MIN_COUNT 3u     /* smallest byte count N: ID + checksum */
#define RSM_ARIA_MIN_PACKET 6u    /* smallest frame on the wire */
/* Largest payload (bytes after the ID) a frame can carry: N = 255. */
#define RSM_ARIA_MAX_PAYLOAD 252u
/* Payload limit used when encoding strings: the conservative spec limit of
 * 200 bytes, so a string argument carries at most 197 characters. */
#define RSM_ARIA_MAX_CMD_PAYLOAD 200u
#define RSM_ARIA_MAX_STR_ARG 197u
/* Largest magnitude of an integer argument (the robot reads an s16). */
#define RSM_ARIA_INT_MAX 32767

/* Argument type bytes. */
#define RSM_ARIA_ARGTYPE_INT 0x3Bu  /* INTARG: value >= 0, u16 LE follows */
#define RSM_ARIA_ARGTYPE_NINT 0x1Bu /* NINTARG: value < 0, |value| u16 LE follows */
#define RSM_ARIA_ARGTYPE_STR 0x2Bu  /* STRARG: length byte, characters, NUL */

/* ---- command numbers (host -> robot) ---------------------------------------- */

#define RSM_ARIA_CMD_PULSE 0u
#define RSM_ARIA_CMD_SYNC0 0u
#define RSM_ARIA_CMD_OPEN 1u
#define RSM_ARIA_CMD_SYNC1 1u
#define RSM_ARIA_CMD_CLOSE 2u
#define RSM_ARIA_CMD_SYNC2 2u
#define RSM_ARIA_CMD_POLLING 3u
#define RSM_ARIA_CMD_ENABLE 4u
#define RSM_ARIA_CMD_SETA 5u
#define RSM_ARIA_CMD_SETV 6u
#define RSM_ARIA_CMD_SETO 7u
#define RSM_ARIA_CMD_MOVE 8u
#define RSM_ARIA_CMD_ROTATE 9u
#define RSM_ARIA_CMD_SETRV 10u
#define RSM_ARIA_CMD_VEL 11u
#define RSM_ARIA_CMD_HEAD 12u
#define RSM_ARIA_CMD_DHEAD 13u
#define RSM_ARIA_CMD_SAY 15u
#define RSM_ARIA_CMD_JOYINFO 17u
#define RSM_ARIA_CMD_CONFIG 18u
#define RSM_ARIA_CMD_ENCODER 19u
#define RSM_ARIA_CMD_SETRVDIR 20u
#define RSM_ARIA_CMD_RVEL 21u
#define RSM_ARIA_CMD_DCHEAD 22u
#define RSM_ARIA_CMD_SETRA 23u
#define RSM_ARIA_CMD_SONAR 28u
#define RSM_ARIA_CMD_STOP 29u
#define RSM_ARIA_CMD_DIGOUT 30u
#define RSM_ARIA_CMD_VEL2 32u
#define RSM_ARIA_CMD_GRIPPER 33u
#define RSM_ARIA_CMD_ADSEL 35u
#define RSM_ARIA_CMD_GRIPPERVAL 36u
#define RSM_ARIA_CMD_GRIPPERPACREQUEST 37u
#define RSM_ARIA_CMD_IOREQUEST 40u
#define RSM_ARIA_CMD_TTY2 42u
#define RSM_ARIA_CMD_GETAUX 43u
#define RSM_ARIA_CMD_BUMPSTALL 44u
#define RSM_ARIA_CMD_JOYDRIVE 47u
#define RSM_ARIA_CMD_HOSTBAUD 50u
#define RSM_ARIA_CMD_AUX1BAUD 51u
#define RSM_ARIA_CMD_AUX2BAUD 52u
#define RSM_ARIA_CMD_ESTOP 55u
#define RSM_ARIA_CMD_GYRO 58u
#define RSM_ARIA_CMD_CHARGE 68u
#define RSM_ARIA_CMD_REVCOUNT 88u
#define RSM_ARIA_CMD_DRIFTFACTOR 89u
#define RSM_ARIA_CMD_SOUNDTOG 92u
#define RSM_ARIA_CMD_TICKSMM 93u
#define RSM_ARIA_CMD_BATTEST 250u
#define RSM_ARIA_CMD_RESET 253u
#define RSM_ARIA_CMD_MAINTENANCE 255u

/* HOSTBAUD / AUXnBAUD rate codes. */
#define RSM_ARIA_BAUD_9600 0u
#define RSM_ARIA_BAUD_19200 1u
#define RSM_ARIA_BAUD_38400 2u
#define RSM_ARIA_BAUD_57600 3u
#define RSM_ARIA_BAUD_115200 4u

/* VEL2 wheel speed limit in Vel2Divisor units (20 mm/s on a P3-DX). */
#define RSM_ARIA_VEL2_MAX 127

/* ---- packet types (robot -> host) ------------------------------------------- */

#define RSM_ARIA_PAC_SYNC0 0x00u
#define RSM_ARIA_PAC_SYNC1 0x01u
#define RSM_ARIA_PAC_SYNC2 0x02u
#define RSM_ARIA_PAC_CONFIG 0x20u
#define RSM_ARIA_PAC_SIP_STOPPED 0x32u
#define RSM_ARIA_PAC_SIP_MOVING 0x33u
#define RSM_ARIA_PAC_ENCODER 0x90u
#define RSM_ARIA_PAC_GYRO 0x98u
#define RSM_ARIA_PAC_SERAUX 0xB0u
#define RSM_ARIA_PAC_SERAUX2 0xB8u
#define RSM_ARIA_PAC_IO 0xF0u

/* ---- SIP bit fields ---------------------------------------------------------- */

/* STALL & BUMPERS */
#define RSM_ARIA_STALL_LEFT 0x0001u
#define RSM_ARIA_STALL_RIGHT 0x0100u
#define RSM_ARIA_BUMPERS_LOW_MASK 0x00FEu  /* bits 1-7 (ARIA: rear) */
#define RSM_ARIA_BUMPERS_HIGH_MASK 0xFE00u /* bits 9-15 (ARIA: front) */
/* FLAGS */
#define RSM_ARIA_FLAGS_MOTORS_ENABLED 0x0001u
#define RSM_ARIA_FLAGS_SONAR_MASK 0x001Eu
#define RSM_ARIA_FLAGS_ESTOP 0x0020u
#define RSM_ARIA_FLAGS_JOYSTICK_BUTTON 0x0200u
#define RSM_ARIA_FLAGS_CHARGER_POWER_GOOD 0x0400u

/* Which SIP fields after the sonar block were present (sip.present). */
#define RSM_ARIA_SIP_HAS_GRIP_STATE 0x0001u
#define RSM_ARIA_SIP_HAS_ANPORT 0x0002u
#define RSM_ARIA_SIP_HAS_ANALOG 0x0004u
#define RSM_ARIA_SIP_HAS_DIGIN 0x0008u
#define RSM_ARIA_SIP_HAS_DIGOUT 0x0010u
#define RSM_ARIA_SIP_HAS_BATTERY_X10 0x0020u
#define RSM_ARIA_SIP_HAS_CHARGE_STATE 0x0040u
#define RSM_ARIA_SIP_HAS_ROT_VEL 0x0080u
#define RSM_ARIA_SIP_HAS_FAULT_FLAGS 0x0100u
#define RSM_ARIA_SIP_HAS_LAT_VEL 0x0200u
#define RSM_ARIA_SIP_HAS_TEMPERATURE 0x0400u
#define RSM_ARIA_SIP_HAS_STATE_OF_CHARGE 0x0800u
#define RSM_ARIA_SIP_HAS_UC_TIME 0x1000u
#define RSM_ARIA_SIP_HAS_FLAGS3 0x2000u

/* Which optional CONFIG fields were present (config.present). */
#define RSM_ARIA_CONFIG_HAS_SHUTDOWN_VOLTS 0x0001u
#define RSM_ARIA_CONFIG_HAS_FIRMWARE 0x0002u

/* ---- types -------------------------------------------------------------------- */

/* Argument kind of a command. */
typedef enum rsm_aria_arg_kind {
    RSM_ARIA_ARG_NONE = 0, /* command byte only */
    RSM_ARIA_ARG_INT = 1,  /* signed integer, |value| <= 32767 */
    RSM_ARIA_ARG_STR = 2   /* length-prefixed string plus a trailing NUL */
} rsm_aria_arg_kind_t;

/* One verified frame as it was on the wire. payload is frame + 4;
 * rsm_aria_payload() returns it. Invariants (kept by the receiver and by
 * rsm_aria_packet_build): frame_len = payload_len + 6, frame[3] = id. */
typedef struct rsm_aria_packet {
    uint8_t id;                         /* packet type */
    size_t payload_len;                 /* bytes after the ID: N - 3, 0..252 */
    size_t frame_len;                   /* bytes on the wire: N + 3, 6..258 */
    uint8_t frame[RSM_ARIA_MAX_PACKET]; /* FA FB N ID payload CKH CKL */
} rsm_aria_packet_t;

/* Receiver counters. Each wraps modulo 2^32 (compare with unsigned
 * differences). Every byte given to the receiver ends up in exactly one of:
 * a published packet, bytes_skipped, the first byte of a rejected
 * candidate (one per bad_length, checksum_errors and truncated event), or
 * the bytes still pending, so
 *     fed = published bytes + bytes_skipped + bad_length
 *           + checksum_errors + truncated + rsm_aria_parser_pending(). */
typedef struct rsm_aria_parser_stats {
    uint32_t bytes_skipped;   /* bytes passed over while hunting for FA FB,
                                 including re-scanned bytes of rejected
                                 candidates that started no new frame */
    uint32_t checksum_errors; /* complete candidates whose checksum failed
                                 (corruption, or a packet cut short and
                                 overrun by the next one) */
    uint32_t bad_length;      /* headers FA FB N with N < 3 */
    uint32_t packets_ok;      /* verified packets published */
    uint32_t truncated;       /* candidates with at least FA FB abandoned
                                 incomplete because the line went silent
                                 (rsm_aria_parser_timeout) */
} rsm_aria_parser_stats_t;

/* Incremental receiver. Initialise with rsm_aria_parser_init; the fields
 * other than stats are private. No pointers kept, so it may be copied or
 * placed anywhere. */
typedef struct rsm_aria_parser {
    rsm_aria_parser_stats_t stats;    /* public, read-only for the caller */
    uint8_t buf[RSM_ARIA_MAX_PACKET]; /* held bytes; a candidate starts at buf[0] */
    size_t have;                      /* bytes held in buf */
    size_t scan;                      /* held bytes examined so far (<= have) */
    int stale;                        /* held bytes predate a line timeout */
} rsm_aria_parser_t;

/* SYNC2 reply: three strings. */
typedef struct rsm_aria_sync2 {
    char name[RSM_ARIA_STR_SIZE];        /* robot name from FLASH */
    char robot_class[RSM_ARIA_STR_SIZE]; /* e.g. "Pioneer" */
    char subclass[RSM_ARIA_STR_SIZE];    /* e.g. "p3dx-sh" */
    uint8_t present;   /* strings found in the payload, 0..3; missing ones are "" */
    uint8_t truncated; /* bit 0 name, bit 1 class, bit 2 subclass: cut to fit */
} rsm_aria_sync2_t;

/* One sonar reading of a SIP. */
typedef struct rsm_aria_sonar {
    uint8_t num;    /* disc number, 0..31 */
    uint16_t range; /* mm (RangeConvFactor 1) */
} rsm_aria_sonar_t;

/* Standard SIP (types 0x32 and 0x33). Fields after the sonar block are
 * zero unless their RSM_ARIA_SIP_HAS_* bit is set in present. */
typedef struct rsm_aria_sip {
    uint8_t type;               /* 0x32 stopped, 0x33 moving */
    uint16_t xpos;              /* XPOS & 0x7FFF, mm, wraps at 32768 */
    uint16_t ypos;              /* YPOS & 0x7FFF, mm, wraps at 32768 */
    int16_t thpos;              /* THPOS, 2*pi/4096 rad */
    int16_t l_vel;              /* L VEL, mm/s */
    int16_t r_vel;              /* R VEL, mm/s */
    uint8_t battery;            /* BATTERY, 0.1 V */
    uint16_t stall_and_bumpers; /* STALL & BUMPERS, RSM_ARIA_STALL_* */
    int16_t control;            /* CONTROL, THPOS units */
    uint16_t flags;             /* FLAGS, RSM_ARIA_FLAGS_* */
    uint8_t compass;            /* COMPASS, 2 deg units */
    uint8_t sonar_count;        /* SONAR COUNT as sent */
    size_t sonar_len;           /* readings stored: min(sonar_count, RSM_ARIA_MAX_SONAR) */
    rsm_aria_sonar_t sonar[RSM_ARIA_MAX_SONAR];
    uint8_t grip_state;         /* GRIP_STATE */
    uint8_t anport;             /* ANPORT */
    uint8_t analog;             /* ANALOG, 0..255 = 0..5 V */
    uint8_t digin;              /* DIGIN */
    uint8_t digout;             /* DIGOUT */
    uint16_t battery_x10;       /* BATTERYX10, 0.1 V */
    uint8_t charge_state;       /* CHARGESTATE 0..4 */
    int16_t rot_vel;            /* ROTVEL, 0.1 deg/s */
    uint16_t fault_flags;       /* FAULTFLAGS */
    int16_t lat_vel;            /* lateral velocity, mm/s (optional tail) */
    int8_t temperature;         /* deg C (optional tail) */
    int8_t state_of_charge;     /* percent (optional tail) */
    uint32_t uc_time;           /* controller time, us (optional tail) */
    uint32_t flags3;            /* FLAGS3 (optional tail) */
    uint32_t present;           /* RSM_ARIA_SIP_HAS_* bits */
} rsm_aria_sip_t;

/* ENCODER packet (type 0x90): raw free-running wheel counts. */
typedef struct rsm_aria_encoder {
    int32_t left;  /* left wheel encoder count, ticks */
    int32_t right; /* right wheel encoder count, ticks */
} rsm_aria_encoder_t;

/* CONFIGpac (type 0x20), fields in wire order up to TicksMM, then the
 * optional ShutdownVolts and firmware version. Later fields are ignored. */
typedef struct rsm_aria_config {
    char robot_type[RSM_ARIA_STR_SIZE]; /* e.g. "Pioneer" */
    char subtype[RSM_ARIA_STR_SIZE];    /* e.g. "p3dx-sh" */
    char serial_num[RSM_ARIA_STR_SIZE];
    uint8_t four_mot;        /* 4-motor flag */
    uint16_t rot_vel_top;    /* deg/s */
    uint16_t trans_vel_top;  /* mm/s */
    uint16_t rot_acc_top;    /* deg/s^2 */
    uint16_t trans_acc_top;  /* mm/s^2 */
    uint16_t pwm_max;
    char name[RSM_ARIA_STR_SIZE];
    uint8_t sip_cycle;       /* ms */
    uint8_t host_baud;       /* RSM_ARIA_BAUD_* code */
    uint8_t aux1_baud;
    uint16_t has_gripper;
    uint16_t front_sonar;
    uint8_t rear_sonar;
    uint16_t low_battery;    /* 0.1 V */
    uint16_t rev_count;
    uint16_t watchdog;       /* ms */
    uint8_t normal_mpacs;
    uint16_t stall_val;
    uint16_t stall_count;
    uint16_t joy_vel;
    uint16_t joy_rot_vel;
    uint16_t rot_vel_max;    /* deg/s */
    uint16_t trans_vel_max;  /* mm/s */
    uint16_t rot_accel;
    uint16_t rot_decel;
    uint16_t rot_kp;
    uint16_t rot_kv;
    uint16_t rot_ki;
    uint16_t trans_accel;
    uint16_t trans_decel;
    uint16_t trans_kp;
    uint16_t trans_kv;
    uint16_t trans_ki;
    uint8_t front_bumps;
    uint8_t rear_bumps;
    uint8_t charger;
    uint8_t sonar_cycle;     /* ms */
    uint8_t auto_baud;       /* 2 = the host baud rate may be switched */
    uint8_t has_gyro;        /* gyro type */
    int16_t drift_factor;
    uint8_t aux2_baud;
    uint8_t aux3_baud;
    uint16_t ticks_mm;       /* encoder ticks per mm of tyre travel */
    uint16_t shutdown_volts; /* 0.1 V, if RSM_ARIA_CONFIG_HAS_SHUTDOWN_VOLTS */
    char firmware[RSM_ARIA_STR_SIZE]; /* if RSM_ARIA_CONFIG_HAS_FIRMWARE */
    uint32_t present;        /* RSM_ARIA_CONFIG_HAS_* bits */
    uint8_t truncated;       /* bits 0..4: robot_type, subtype, serial_num,
                                name, firmware were cut to fit */
} rsm_aria_config_t;

/* ---- checksum ---------------------------------------------------------------- */

/* Computes the ARIA checksum of a packet body (ID + payload, no header,
 * no count byte): the big-endian 16-bit words of body are summed modulo
 * 2^16 and an odd last byte is XORed into the low byte.
 * body: len bytes, borrowed; may be NULL only if len is 0.
 * Returns the checksum, sent high byte first. Pure, reentrant, ISR-safe. */
uint16_t rsm_aria_checksum(const uint8_t *body, size_t len);

/* ---- encoders ------------------------------------------------------------------ */
/* Every encoder writes one complete frame into out (cap bytes, caller
 * owned) and returns the number of bytes written (6..258). On any error
 * out is left untouched and the return is negative:
 *   RSM_ERR_INVAL  NULL out, NULL data with a non-zero length, bad kind
 *   RSM_ERR_RANGE  an argument outside its documented range
 *   RSM_ERR_NOMEM  cap smaller than the frame
 * All encoders are pure, reentrant and ISR-safe. A 9-byte buffer holds
 * every frame except strings (length + 9) and raw frames (length + 6). */

/* Frames an arbitrary ID and payload (also robot -> host packets, e.g. for
 * simulators and tests). payload: len bytes, borrowed, len <= 252
 * (RSM_ERR_RANGE otherwise); NULL allowed when len is 0. */
int rsm_aria_encode_raw(uint8_t id, const uint8_t *payload, size_t len, uint8_t *out, size_t cap);

/* Generic command encoder. cmd: command number (RSM_ARIA_CMD_*).
 * kind NONE: value, str, str_len ignored.
 * kind INT: value in [-32767, 32767], else RSM_ERR_RANGE; sent as INTARG
 *   0x3B + value u16 LE when >= 0, NINTARG 0x1B + |value| u16 LE when < 0.
 * kind STR: str holds str_len bytes (not necessarily NUL-terminated, NUL
 *   bytes allowed), str_len <= RSM_ARIA_MAX_STR_ARG (197) else
 *   RSM_ERR_RANGE; sent as 0x2B, str_len, the bytes, then a NUL that the
 *   length byte does not count (as ARIA does). str may be NULL if str_len
 *   is 0. value ignored. */
int rsm_aria_encode(uint8_t cmd, rsm_aria_arg_kind_t kind, int32_t value, const char *str,
                    size_t str_len, uint8_t *out, size_t cap);

/* rsm_aria_encode with kind NONE: the command byte only (6 bytes). */
int rsm_aria_encode_none(uint8_t cmd, uint8_t *out, size_t cap);
/* rsm_aria_encode with kind INT: value in [-32767, 32767] (9 bytes). */
int rsm_aria_encode_int(uint8_t cmd, int32_t value, uint8_t *out, size_t cap);
/* rsm_aria_encode with kind STR: str_len <= 197 bytes (str_len + 9 bytes). */
int rsm_aria_encode_str(uint8_t cmd, const char *str, size_t str_len, uint8_t *out, size_t cap);

/* Handshake and session. SYNC0 is byte-identical to PULSE, SYNC1 to the
 * bare OPEN, SYNC2 to the bare CLOSE. The _int1 forms carry int 1, as
 * ARIA sends them; the bare forms are the manual's (both are accepted by
 * ARCOS as far as the sources show). */
/* SYNC0, first handshake step: FA FB 03 00 00 00. */
int rsm_aria_encode_sync0(uint8_t *out, size_t cap);
/* SYNC1, second handshake step: FA FB 03 01 00 01. */
int rsm_aria_encode_sync1(uint8_t *out, size_t cap);
/* SYNC2, third handshake step; the reply carries name, class, subclass. */
int rsm_aria_encode_sync2(uint8_t *out, size_t cap);
/* PULSE: keep-alive that resets the robot's watchdog; no argument. */
int rsm_aria_encode_pulse(uint8_t *out, size_t cap);
/* OPEN without an argument (manual form): start the SIP stream. */
int rsm_aria_encode_open(uint8_t *out, size_t cap);
/* OPEN with int 1 (ARIA's form). */
int rsm_aria_encode_open_int1(uint8_t *out, size_t cap);
/* CLOSE without an argument (manual form): end the session. */
int rsm_aria_encode_close(uint8_t *out, size_t cap);
/* CLOSE with int 1 (ARIA's form). */
int rsm_aria_encode_close_int1(uint8_t *out, size_t cap);

/* ENABLE 1 when on is non-zero (motors on), ENABLE 0 otherwise. */
int rsm_aria_encode_enable(int on, uint8_t *out, size_t cap);
/* ENCODER 2 (continuous 0x90 packets) when on is non-zero, ENCODER 0 otherwise. */
int rsm_aria_encode_encoder(int on, uint8_t *out, size_t cap);
/* SONAR 1 when on is non-zero, SONAR 0 otherwise. */
int rsm_aria_encode_sonar(int on, uint8_t *out, size_t cap);
/* CONFIG with int 1: asks for one CONFIGpac (0x20). */
int rsm_aria_encode_config(uint8_t *out, size_t cap);
/* SETO: reset the odometry origin to (0, 0, 0). */
int rsm_aria_encode_seto(uint8_t *out, size_t cap);
/* SETA: mm_s2 > 0 sets the translational acceleration, < 0 the
 * deceleration, in mm/s^2; |mm_s2| <= 32767. */
int rsm_aria_encode_seta(int32_t mm_s2, uint8_t *out, size_t cap);
/* SETV: maximum translational speed, mm/s, 0..32767. */
int rsm_aria_encode_setv(int32_t mm_s, uint8_t *out, size_t cap);
/* SETRV: maximum rotational speed, deg/s, 0..32767. */
int rsm_aria_encode_setrv(int32_t deg_s, uint8_t *out, size_t cap);
/* VEL: translational velocity, mm/s, |mm_s| <= 32767. */
int rsm_aria_encode_vel(int32_t mm_s, uint8_t *out, size_t cap);
/* RVEL: rotational velocity, deg/s, counter-clockwise positive. */
int rsm_aria_encode_rvel(int32_t deg_s, uint8_t *out, size_t cap);
/* ROTATE: rotational velocity, deg/s (same meaning as RVEL). */
int rsm_aria_encode_rotate(int32_t deg_s, uint8_t *out, size_t cap);
/* HEAD: turn to an absolute heading, deg, counter-clockwise positive
 * (firmware expects 0..359; ARIA also sends -180..180). */
int rsm_aria_encode_head(int32_t deg, uint8_t *out, size_t cap);
/* DHEAD: turn relative to the current heading, deg (+ = CCW). */
int rsm_aria_encode_dhead(int32_t deg, uint8_t *out, size_t cap);
/* MOVE: translate this many mm (negative = backwards). */
int rsm_aria_encode_move(int32_t mm, uint8_t *out, size_t cap);
/* VEL2: independent wheel speeds in Vel2Divisor units (20 mm/s on a
 * P3-DX), each in [-127, 127] (RSM_ERR_RANGE otherwise). The word
 * left << 8 | (right & 0xFF) is sent as a signed 16-bit integer, so a
 * negative left wheel gives NINTARG with the two's-complement magnitude
 * (left -5, right 5 -> 1B FB 04); the robot negates it back. */
int rsm_aria_encode_vel2(int32_t left, int32_t right, uint8_t *out, size_t cap);
/* STOP: decelerate to a stop. */
int rsm_aria_encode_stop(uint8_t *out, size_t cap);
/* ESTOP: emergency stop, ignores the deceleration setting. */
int rsm_aria_encode_estop(uint8_t *out, size_t cap);
/* HOSTBAUD: code is an RSM_ARIA_BAUD_* value, 0..4, else RSM_ERR_RANGE. */
int rsm_aria_encode_hostbaud(uint8_t code, uint8_t *out, size_t cap);
/* TTY2: send len bytes of str out of the robot's AUX1 port (string
 * argument, see rsm_aria_encode). */
int rsm_aria_encode_tty2(const char *str, size_t len, uint8_t *out, size_t cap);

/* Maps a bit rate to its HOSTBAUD/AUXnBAUD code. Returns the code 0..4,
 * or RSM_ERR_RANGE for any other rate. Pure, reentrant. */
int rsm_aria_baud_code(uint32_t baud);

/* ---- receiver ------------------------------------------------------------------ */

/* Puts p into its initial state: nothing held, every counter zero. Also
 * the way to drop held bytes, e.g. after a baud-rate change.
 * Returns RSM_OK, or RSM_ERR_INVAL if p is NULL (RSM_ERR_CONFIG: see the
 * capacities above). Reentrant on distinct parsers. */
#define rsm_aria_parser_init(p) \
    rsm_aria_parser_init_checked((p), sizeof(rsm_aria_parser_t), (unsigned long)RSM_CONFIG_FINGERPRINT)

int rsm_aria_parser_init_checked(rsm_aria_parser_t *p, size_t p_size, unsigned long fingerprint);

/* Feeds received bytes; publishes at most one verified packet per call.
 * p: an initialised parser, caller owned, modified.
 * data: len bytes, borrowed; may be NULL if len is 0.
 * consumed: receives how many bytes of data were used (<= len).
 * out: receives the packet when 1 is returned; untouched otherwise.
 * Returns 1 when a packet whose checksum verified was written to *out;
 * *consumed may then be less than len and the caller must call again with
 * data + *consumed. Returns 0 when all of data was consumed and no further
 * packet can be completed from the bytes held. RSM_ERR_INVAL (with
 * *consumed = 0 when consumed is not NULL) for NULL p, consumed or out,
 * or NULL data with len > 0; RSM_ERR_CONFIG (nothing written, see the
 * capacities above). Intended use: call in a loop until it
 * returns 0 -- also with len 0 after a 1 -- since held bytes can complete
 * more than one packet.
 * Receiver rules: hunt for FA FB (a byte after FA that is not FB restarts
 * the hunt with that byte); N < 3 is rejected (bad_length); N >= 3
 * collects N more bytes; the checksum is verified; unknown IDs are
 * published, not errors. The framing is by length, so FA FB inside a
 * payload never interrupts a packet.
 * Resynchronisation: when a candidate is rejected (bad length, checksum
 * failure, timeout) only its first byte is discarded; the bytes after it
 * are examined again, from the parser's own buffer, for a new FA FB, so a
 * valid frame that began inside a corrupt or overlong candidate is never
 * lost. Held bytes never exceed one candidate (N + 3 <= 258 bytes) and all
 * moves stay inside buf.
 * Processing is byte-exact: splitting the same bytes into different
 * chunks gives the same packets and counters. Reentrant on distinct
 * parsers; not ISR-safe against another call on the same parser. */
#define rsm_aria_parser_feed(p, data, len, consumed, out)                                        \
    rsm_aria_parser_feed_checked((p), (data), (len), (consumed), (out), sizeof(rsm_aria_packet_t), \
                                 (unsigned long)RSM_CONFIG_FINGERPRINT)

int rsm_aria_parser_feed_checked(rsm_aria_parser_t *p, const uint8_t *data, size_t len, size_t *consumed,
                                 rsm_aria_packet_t *out, size_t out_size, unsigned long fingerprint);

/* Tells the receiver that the line has been silent for the inter-byte
 * timeout (ARIA uses 100 ms). A partial candidate that already has FA FB
 * is abandoned and counted in stats.truncated; a lone FA is counted in
 * bytes_skipped. Bytes held after the abandoned candidate's first byte are
 * marked final: the next rsm_aria_parser_feed call (len 0 is fine)
 * examines them before any new byte, publishes complete frames found in
 * them and abandons, as truncated, any further candidate they leave
 * incomplete, so bytes from before the silence never join bytes from
 * after it.
 * If the caller stopped calling rsm_aria_parser_feed after a 1, before a
 * 0, the held bytes have not all been examined yet: they are only marked
 * final and any abandonment is counted by the next feed call.
 * Returns 1 if a candidate was counted as truncated, 0 otherwise,
 * RSM_ERR_INVAL if p is NULL. Same reentrancy as rsm_aria_parser_feed. */
int rsm_aria_parser_timeout(rsm_aria_parser_t *p);

/* Returns the number of bytes held (a partial candidate or bytes waiting
 * to be examined again), 0..258; 0 for NULL. Pure. */
size_t rsm_aria_parser_pending(const rsm_aria_parser_t *p);

/* ---- packets and decoders -------------------------------------------------------- */

/* Returns the payload of pkt (pkt->payload_len bytes, inside pkt), or
 * NULL if pkt is NULL. Pure. */
const uint8_t *rsm_aria_payload(const rsm_aria_packet_t *pkt);

/* Builds pkt as if the receiver had published the frame with this ID and
 * payload (checksum computed). payload: len bytes, borrowed, len <= 252.
 * Returns RSM_OK, RSM_ERR_INVAL (NULL pkt, NULL payload with len > 0) or
 * RSM_ERR_RANGE (len > 252) or RSM_ERR_CONFIG (see the capacities above);
 * pkt untouched on error. Pure, reentrant. */
#define rsm_aria_packet_build(pkt, id, payload, len)                                                    \
    rsm_aria_packet_build_checked((pkt), sizeof(rsm_aria_packet_t), (unsigned long)RSM_CONFIG_FINGERPRINT, \
                                  (id), (payload), (len))

int rsm_aria_packet_build_checked(rsm_aria_packet_t *pkt, size_t pkt_size, unsigned long fingerprint, uint8_t id,
                                  const uint8_t *payload, size_t len);

/* The decoders below read pkt (borrowed) and fill *out (caller owned).
 * They do not re-verify the checksum; they do check that pkt is
 * self-consistent (frame_len = payload_len + 6 <= RSM_ARIA_MAX_PACKET,
 * frame[3] = id) and return RSM_ERR_INVAL otherwise. Those of SYNC2, SIP
 * and CONFIGpac also return RSM_ERR_CONFIG (see the capacities above). On
 * any error *out is left untouched. All are pure, reentrant and ISR-safe. */

/* SYNC reply: returns the handshake step 0, 1 or 2 of a packet with ID
 * 0, 1 or 2 (payload ignored), RSM_ERR_INVAL for NULL or any other ID. */
int rsm_aria_decode_sync(const rsm_aria_packet_t *pkt);

/* SYNC2 reply (ID 2): robot name, class and subclass, each ended by a NUL
 * or by the end of the payload; missing strings are left empty and
 * counted out of out->present. Strings longer than RSM_ARIA_STR_SIZE - 1
 * are cut, flagged in out->truncated and still skipped correctly.
 * Returns RSM_OK, or RSM_ERR_INVAL (NULL, inconsistent packet, ID != 2). */
#define rsm_aria_decode_sync2(pkt, out) \
    rsm_aria_decode_sync2_checked((pkt), (out), sizeof(rsm_aria_sync2_t), (unsigned long)RSM_CONFIG_FINGERPRINT)

int rsm_aria_decode_sync2_checked(const rsm_aria_packet_t *pkt, rsm_aria_sync2_t *out, size_t out_size,
                                  unsigned long fingerprint);

/* Standard SIP (ID 0x32 or 0x33). Fields through the sonar readings are
 * required; each later field is decoded only if all its bytes remain, in
 * wire order, stopping at the first that does not fit, and is flagged in
 * out->present. Returns RSM_OK, RSM_ERR_INVAL (NULL, inconsistent packet,
 * other ID) or RSM_ERR_RANGE (payload shorter than 19 + 3 * SONAR COUNT). */
#define rsm_aria_decode_sip(pkt, out) \
    rsm_aria_decode_sip_checked((pkt), (out), sizeof(rsm_aria_sip_t), (unsigned long)RSM_CONFIG_FINGERPRINT)

int rsm_aria_decode_sip_checked(const rsm_aria_packet_t *pkt, rsm_aria_sip_t *out, size_t out_size,
                                unsigned long fingerprint);

/* ENCODER packet (ID 0x90): left and right s32 LE counts; bytes after the
 * first 8 are ignored (N >= 11). Returns RSM_OK, RSM_ERR_INVAL (NULL,
 * inconsistent packet, other ID) or RSM_ERR_RANGE (payload < 8 bytes). */
int rsm_aria_decode_encoder(const rsm_aria_packet_t *pkt, rsm_aria_encoder_t *out);

/* CONFIGpac (ID 0x20). Every field through TicksMM is required (the four
 * strings on the way must end with a NUL); ShutdownVolts and the firmware
 * string (ended by a NUL or the payload end) are optional and flagged in
 * out->present. Returns RSM_OK, RSM_ERR_INVAL (NULL, inconsistent packet,
 * other ID) or RSM_ERR_RANGE (payload ends before TicksMM). */
#define rsm_aria_decode_config(pkt, out) \
    rsm_aria_decode_config_checked((pkt), (out), sizeof(rsm_aria_config_t), (unsigned long)RSM_CONFIG_FINGERPRINT)

int rsm_aria_decode_config_checked(const rsm_aria_packet_t *pkt, rsm_aria_config_t *out, size_t out_size,
                                   unsigned long fingerprint);

/* ---- odometry helpers -------------------------------------------------------------- */

/* Difference now - prev of two 15-bit XPOS/YPOS readings (bit 15 of each
 * is ignored), taken modulo 2^15 into [-16384, 16383] units (mm on a
 * P3-DX). Example: prev 32760, now 10 -> +18. Pure, reentrant. */
int16_t rsm_aria_pos_delta15(uint16_t now, uint16_t prev);

/* (Encoder counts: rsm_odometry_count_delta in rsm/odometry.h, with 32 bits.) */

/* Converts a THPOS value, or a difference of two (4096 units per turn), to
 * radians wrapped to (-pi, pi]. Example: 1024 -> pi/2. Pure, reentrant. */
float rsm_aria_th_to_rad(int32_t th_units);

#ifdef __cplusplus
}
#endif

#endif /* RSM_ARIA_H */
