/* SICK LMS 200/211/221/291 binary telegram codec: CRC, request encoders, an
 * incremental receiver and reply decoders. Pure code: no I/O, no heap, no
 * global state. The driver that owns the serial port sits on top of it.
 *
 * Telegram layout (both directions, multi-byte fields LSB first):
 *     STX(0x02) ADR LEN(u16) CMD data... CRC(u16)      total = LEN + 6
 * LEN counts CMD and the data bytes; in replies the last data byte is the
 * status byte. ADR is the LMS address (0x00 default) in requests and
 * 0x80 | address in replies. Outside telegrams the LMS answers every request
 * with one unframed byte, ACK 0x06 or NAK 0x15.
 *
 * Angles in this API follow the scanner frame: 0 deg points to the scanner's
 * right, 90 deg straight ahead, 180 deg to its left (counter-clockwise seen
 * from above). In a robot frame with x forward and y left, the bearing of a
 * reading is (angle - 90 deg) for an upright scanner. */
#ifndef RSM_LMS_H
#define RSM_LMS_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/config.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- protocol constants ------------------------------------------------ */

#define RSM_LMS_STX 0x02u /* first byte of every telegram */
#define RSM_LMS_ACK 0x06u /* unframed "request accepted" byte */
#define RSM_LMS_NAK 0x15u /* unframed "request rejected (CRC/format)" byte */
#define RSM_LMS_REPLY_ADR 0x80u /* bit set in the ADR byte of every reply */

/* Bytes a telegram adds around CMD + data: STX, ADR, 2 LEN, 2 CRC. */
#define RSM_LMS_OVERHEAD 6u

/* Largest LEN field the receiver accepts: 814 (0xB0 with 401 values is
 * LEN 806, optional index bytes add a few), lowered if RSM_LMS_MAX_TELEGRAM
 * was configured smaller than 820. A LEN of 0 or above this is rejected. */
#define RSM_LMS_MAX_LEN \
    ((RSM_LMS_MAX_TELEGRAM - 6) < 814 ? (RSM_LMS_MAX_TELEGRAM - 6) : 814)

/* Request command codes (host -> LMS). */
#define RSM_LMS_CMD_RESET 0x10u         /* software reset */
#define RSM_LMS_CMD_MODE 0x20u          /* change operating mode / baud rate */
#define RSM_LMS_CMD_GET_VALUES 0x30u    /* request measured values */
#define RSM_LMS_CMD_GET_STATUS 0x31u    /* request the status block */
#define RSM_LMS_CMD_GET_TYPE 0x3Au      /* request the device type text */
#define RSM_LMS_CMD_SET_VARIANT 0x3Bu   /* set angular range / resolution */
#define RSM_LMS_CMD_GET_CONFIG 0x74u    /* read the configuration block */
#define RSM_LMS_CMD_SET_CONFIG 0x77u    /* write the configuration block */

/* Reply command codes (LMS -> host). */
#define RSM_LMS_REPLY_POWER_ON 0x90u    /* unsolicited power-on text */
#define RSM_LMS_REPLY_RESET 0x91u       /* confirms 0x10 */
#define RSM_LMS_REPLY_NOT_ACK 0x92u     /* command not accepted (logical) */
#define RSM_LMS_REPLY_MODE 0xA0u        /* result of 0x20 */
#define RSM_LMS_REPLY_VALUES 0xB0u      /* measured values */
#define RSM_LMS_REPLY_STATUS 0xB1u      /* status block (not decoded here) */
#define RSM_LMS_REPLY_TYPE 0xBAu        /* device type text */
#define RSM_LMS_REPLY_VARIANT 0xBBu     /* result of 0x3B */
#define RSM_LMS_REPLY_CONFIG 0xF4u      /* configuration block */
#define RSM_LMS_REPLY_SET_CONFIG 0xF7u  /* result of 0x77 */

/* Operating mode codes, the first data byte of a 0x20 request. */
#define RSM_LMS_MODE_INSTALLATION 0x00u /* setup mode, needs the password */
#define RSM_LMS_MODE_DIAGNOSTIC 0x10u
#define RSM_LMS_MODE_CONTINUOUS 0x24u   /* stream every scan (0xB0) */
#define RSM_LMS_MODE_ON_REQUEST 0x25u   /* values only on 0x30; stops a stream */
#define RSM_LMS_MODE_MEAN 0x26u         /* stream mean values (0xB6) */
#define RSM_LMS_MODE_SUBRANGE 0x27u     /* stream a sub-range (0xB7) */
#define RSM_LMS_MODE_BAUD_38400 0x40u
#define RSM_LMS_MODE_BAUD_19200 0x41u
#define RSM_LMS_MODE_BAUD_9600 0x42u
#define RSM_LMS_MODE_BAUD_500000 0x48u  /* RS-422 only */

/* Installation-mode password length and the factory default password. */
#define RSM_LMS_PASSWORD_LEN 8u
#define RSM_LMS_DEFAULT_PASSWORD "SICK_LMS"

/* Result byte of the 0xA0 mode-change reply. */
#define RSM_LMS_MODE_RESULT_OK 0x00u
#define RSM_LMS_MODE_RESULT_BAD_PASSWORD 0x01u
#define RSM_LMS_MODE_RESULT_FAULT 0x02u

/* Result byte of the 0xBB variant reply and of the 0xF7 config reply. */
#define RSM_LMS_RESULT_REFUSED 0x00u
#define RSM_LMS_RESULT_ACCEPTED 0x01u

/* Units, as coded in configuration byte E and in bits 14-15 of the 0xB0
 * count word. RSM_LMS_UNITS_AUTO is only meaningful in rsm_lms_b0_format_t. */
#define RSM_LMS_UNITS_CM 0x00u
#define RSM_LMS_UNITS_MM 0x01u
#define RSM_LMS_UNITS_AUTO 0xFFu

/* Measuring modes (configuration byte D). */
#define RSM_LMS_MEAS_8M_FIELDS_AB_DAZZLE 0x00u /* 13 bits; 13 A, 14 B, 15 dazzle */
#define RSM_LMS_MEAS_8M_REFLECTOR 0x01u        /* 13 bits; 13-15 reflector level */
#define RSM_LMS_MEAS_8M_FIELDS_ABC 0x02u       /* 13 bits; 13-15 fields A, B, C */
#define RSM_LMS_MEAS_16M_REFLECTOR 0x03u       /* 14 bits; 14-15 reflector level */
#define RSM_LMS_MEAS_16M_FIELDS_AB 0x04u       /* 14 bits; 14 A, 15 B */
#define RSM_LMS_MEAS_32M_REFLECTOR 0x05u       /* 15 bits; 15 reflector */
#define RSM_LMS_MEAS_32M_FIELD_A 0x06u         /* 15 bits; 15 field A */
#define RSM_LMS_MEAS_32M_IMMEDIATE 0x0Fu       /* 16 bits; no flags */
#define RSM_LMS_MEAS_REFLECTIVITY 0x3Fu        /* reflectivity, not ranges */

/* Configuration block sizes (0xF4 reply / 0x77 request, without CMD). */
#define RSM_LMS_CONFIG_SHORT 32u
#define RSM_LMS_CONFIG_LONG 34u

/* Longest text kept from a 0x90 power-on or 0xBA type reply (21 in every
 * known unit). */
#define RSM_LMS_TEXT_MAX 40u

/* ---- CRC --------------------------------------------------------------- */

/* CRC of the LMS 2xx telegram listing over len bytes (STX up to the last
 * data byte): a 16-bit shift register with generator 0x8005, XORed with the
 * pair (previous byte << 8 | byte) for every byte, zero seed, no reflection,
 * no final XOR. It goes on the wire low byte first.
 * Params: data may be NULL only when len is 0.
 * Returns the CRC (0 for len 0). Pure, reentrant, ISR-safe. */
uint16_t rsm_lms_crc(const uint8_t *data, size_t len);

/* ---- telegram view ----------------------------------------------------- */

/* A verified telegram. It does not own its bytes: frame and data point into
 * the buffer it was made from (the caller's array for rsm_lms_telegram_view,
 * the parser's buffer for a parser event). */
typedef struct rsm_lms_telegram {
    const uint8_t *frame; /* STX .. CRC high byte */
    size_t frame_len;     /* LEN + 6 */
    uint8_t adr;          /* ADR byte as sent (0x80 | address in replies) */
    uint8_t cmd;          /* CMD byte */
    uint16_t len;         /* LEN field: CMD + data bytes */
    const uint8_t *data;  /* bytes after CMD; in replies the status is last */
    size_t data_len;      /* LEN - 1 */
} rsm_lms_telegram_t;

/* Checks one complete telegram held in a caller array and describes it.
 * Params: frame points to len bytes starting at STX; out receives pointers
 * into frame, so frame must outlive every use of *out.
 * Returns RSM_OK; RSM_ERR_INVAL for NULL pointers; RSM_ERR_AGAIN if len is
 * shorter than the telegram its header announces; RSM_ERR_PROTO for a
 * missing STX, LEN of 0 or above RSM_LMS_MAX_LEN, or len longer than the
 * telegram; RSM_ERR_CHECKSUM if the CRC does not verify. *out is written only
 * on RSM_OK. Pure, reentrant. */
int rsm_lms_telegram_view(const uint8_t *frame, size_t len, rsm_lms_telegram_t *out);

/* ---- encoders ---------------------------------------------------------- */
/* Every encoder writes one complete telegram into out[0..cap) and returns
 * its length in bytes (> 0). Errors: RSM_ERR_INVAL for a NULL out or a bad
 * argument (described per function), RSM_ERR_NOMEM if cap is too small.
 * Nothing is written on error. address is the LMS address, 0x00..0x7F
 * (0x00 for a factory-set unit). All are pure and reentrant. */

/* Generic builder: STX, adr, LEN = 1 + data_len, cmd, data, CRC.
 * Params: adr is the raw ADR byte (requests: the LMS address; replies, for
 * simulators and tests: 0x80 | address); data may be NULL if data_len is 0;
 * 1 + data_len must not exceed RSM_LMS_MAX_LEN (RSM_ERR_INVAL).
 * Needs cap >= data_len + 7. */
int rsm_lms_encode(uint8_t *out, size_t cap, uint8_t adr, uint8_t cmd, const uint8_t *data,
                   size_t data_len);

/* 0x20 mode change without parameters: mode is one of
 * RSM_LMS_MODE_DIAGNOSTIC, _CONTINUOUS, _ON_REQUEST, _BAUD_38400,
 * _BAUD_19200, _BAUD_9600, _BAUD_500000. The modes that need parameters
 * (installation, mean, sub-range) and unknown codes give RSM_ERR_INVAL.
 * 8 bytes. */
int rsm_lms_encode_mode(uint8_t *out, size_t cap, uint8_t address, uint8_t mode);

/* 0x20 0x00 installation mode with its password.
 * Params: password points to RSM_LMS_PASSWORD_LEN bytes (no terminator
 * needed), or is NULL for the factory default "SICK_LMS". 16 bytes. */
int rsm_lms_encode_mode_installation(uint8_t *out, size_t cap, uint8_t address,
                                     const uint8_t *password);

/* 0x20 0x26 continuous mean values over samples scans (reply stream 0xB6,
 * not decoded here). samples 0 gives RSM_ERR_INVAL. The listing's upper
 * limit is not in our reference (one implementation allows 2..250); other
 * values are sent as given and the LMS answers 0xA0 with its verdict.
 * 9 bytes. */
int rsm_lms_encode_mode_mean(uint8_t *out, size_t cap, uint8_t address, uint8_t samples);

/* 0x20 0x27 continuous sub-range: readings first..last, 1-based indices
 * into the full scan (reply stream 0xB7, not decoded here). Needs
 * 1 <= first <= last <= 401, else RSM_ERR_INVAL. 12 bytes. */
int rsm_lms_encode_mode_subrange(uint8_t *out, size_t cap, uint8_t address, uint16_t first,
                                 uint16_t last);

/* 0x20 baud-rate change: baud is 9600, 19200, 38400 or 500000 (RS-422
 * only), else RSM_ERR_INVAL. Not stored across power-up; the 0xA0 reply
 * still comes at the old rate. 8 bytes. */
int rsm_lms_encode_mode_baud(uint8_t *out, size_t cap, uint8_t address, uint32_t baud);

/* 0x30 0x01: send the measured values of one complete scan (reply 0xB0).
 * 8 bytes. */
int rsm_lms_encode_request_scan(uint8_t *out, size_t cap, uint8_t address);

/* 0x31: request the status block (reply 0xB1). 7 bytes. */
int rsm_lms_encode_request_status(uint8_t *out, size_t cap, uint8_t address);

/* 0x3A: request the device type text (reply 0xBA). 7 bytes. */
int rsm_lms_encode_request_type(uint8_t *out, size_t cap, uint8_t address);

/* 0x3B: set the variant. Legal pairs (angle_deg, resolution_cdeg in 1/100
 * deg): (180, 100) 181 values, (180, 50) 361, (100, 100) 101, (100, 50)
 * 201, (100, 25) 401. Anything else, including 180 deg at 0.25 deg, gives
 * RSM_ERR_INVAL. 11 bytes. */
int rsm_lms_encode_variant(uint8_t *out, size_t cap, uint8_t address, uint16_t angle_deg,
                           uint16_t resolution_cdeg);

/* 0x74: read the configuration block (reply 0xF4). 7 bytes. */
int rsm_lms_encode_request_config(uint8_t *out, size_t cap, uint8_t address);

/* 0x10: software reset (reply 0x91, later 0x90). 7 bytes. */
int rsm_lms_encode_reset(uint8_t *out, size_t cap, uint8_t address);

/* ---- configuration block ----------------------------------------------- */

/* The configuration block as read with 0x74 and written with 0x77. Named
 * fields are the ones our reference documents; the rest of the block is kept
 * raw so that a read-modify-write leaves it unchanged. */
typedef struct rsm_lms_config {
    uint8_t block[RSM_LMS_CONFIG_LONG]; /* raw block; bytes >= block_len unused */
    size_t block_len;                   /* RSM_LMS_CONFIG_SHORT or _LONG */
    uint16_t blanking;                  /* A, bytes 0-1 (u16, LSB first) */
    uint8_t stop_threshold;             /* B, byte 2 (LMS200) */
    uint8_t peak_threshold;             /* B, byte 3 (LMS211/221/291) */
    uint8_t availability;               /* C, byte 4; bit 1 = real-time indices */
    uint8_t measuring_mode;             /* D, byte 5: RSM_LMS_MEAS_* */
    uint8_t units;                      /* E, byte 6: RSM_LMS_UNITS_CM / _MM */
    uint8_t status;                     /* status byte of the reply */
} rsm_lms_config_t;

/* 0x77: write a configuration block (installation mode only; the LMS stores
 * it in EEPROM, so do this once, not at every start). Bytes 0-6 come from the
 * named fields of cfg, bytes 7..block_len-1 from cfg->block unchanged.
 * RSM_ERR_INVAL if cfg is NULL, block_len is not 32 or 34, units is not
 * cm/mm (Player also writes 0x02 for 10 cm; that code is unverified and
 * refused here) or measuring_mode is not a listed RSM_LMS_MEAS_* code.
 * block_len + 7 bytes. */
int rsm_lms_encode_config(uint8_t *out, size_t cap, uint8_t address, const rsm_lms_config_t *cfg);

/* ---- incremental receiver ---------------------------------------------- */

/* Receiver counters. They only grow (wrapping at 2^32). Once the receiver
 * holds no bytes (after rsm_lms_parser_timeout returns 0), every byte ever fed
 * is accounted for exactly once:
 *     fed = bytes_skipped + acks + naks + bytes of published telegrams. */
typedef struct rsm_lms_parser_stats {
    uint32_t bytes_skipped; /* bytes dropped: garbage between telegrams and the
                               STX of every rejected or abandoned candidate */
    uint32_t crc_errors;    /* candidates whose CRC did not verify */
    uint32_t bad_length;    /* candidates with LEN 0 or > RSM_LMS_MAX_LEN */
    uint32_t truncated;     /* partial candidates abandoned by a timeout */
    uint32_t telegrams_ok;  /* telegrams published */
    uint32_t acks;          /* ACK bytes reported */
    uint32_t naks;          /* NAK bytes reported */
} rsm_lms_parser_stats_t;

/* Receiver state, owned by the caller (RSM_LMS_MAX_TELEGRAM bytes plus
 * about 50). Initialise with rsm_lms_parser_init; treat the members as private
 * except stats, which may be read at any time. buf[head..pos) is the
 * candidate telegram being assembled, buf[pos..wr) bytes received but not yet
 * examined (they exist after a rejected candidate is re-scanned). */
typedef struct rsm_lms_parser {
    uint8_t buf[RSM_LMS_MAX_TELEGRAM];
    size_t head;
    size_t pos;
    size_t wr;
    rsm_lms_parser_stats_t stats;
} rsm_lms_parser_t;

typedef enum rsm_lms_event_type {
    RSM_LMS_EVENT_NONE = 0,
    RSM_LMS_EVENT_TELEGRAM = 1, /* a telegram whose CRC verified */
    RSM_LMS_EVENT_ACK = 2,      /* an unframed 0x06 between telegrams */
    RSM_LMS_EVENT_NAK = 3       /* an unframed 0x15 between telegrams */
} rsm_lms_event_type_t;

/* One receiver event. For RSM_LMS_EVENT_TELEGRAM, telegram points into the
 * parser's buffer and stays valid until the next call on that parser. */
typedef struct rsm_lms_event {
    rsm_lms_event_type_t type;
    rsm_lms_telegram_t telegram; /* zeroed unless type is TELEGRAM */
} rsm_lms_event_t;

/* Sets *p to the empty hunting state with all counters zero.
 * Returns RSM_OK, or RSM_ERR_INVAL if p is NULL. Reentrant (per parser).
 * A macro, as rsm_localizer_init: it passes the caller's
 * sizeof(rsm_lms_parser_t) and RSM_CONFIG_FINGERPRINT, so that a caller
 * compiled with other capacities than the library (RSM_LMS_MAX_TELEGRAM
 * sizes the parser) gets RSM_ERR_CONFIG, with p unchanged. */
#define rsm_lms_parser_init(p) \
    rsm_lms_parser_init_checked((p), sizeof(rsm_lms_parser_t), (unsigned long)RSM_CONFIG_FINGERPRINT)

int rsm_lms_parser_init_checked(rsm_lms_parser_t *p, size_t p_size, unsigned long fingerprint);

/* Feeds received bytes, in chunks of any size, and stops at the first event.
 *
 * Framing: between telegrams the receiver hunts for STX followed by a reply
 * ADR byte (bit 7 set, any address); reads LEN and rejects 0 or more than
 * RSM_LMS_MAX_LEN (bad_length); collects CMD, data and CRC and publishes the
 * telegram only if the CRC verifies (else crc_errors). A rejected candidate
 * costs only its STX byte: every byte after it is examined again, so a
 * telegram hidden inside or behind a corrupted one is still found. No byte
 * is ever read or written outside p->buf or data[0..len).
 *
 * ACK/NAK: a 0x06 or 0x15 byte met while hunting (never inside a candidate,
 * but possibly among the bytes re-examined after a rejected candidate) is
 * reported as an ACK or NAK event and counted. The receiver cannot tell
 * such a byte from line noise of the same value; it only means something
 * while the driver awaits the answer to a request, so the driver decides
 * (e.g. ignores ACK/NAK events in streaming mode).
 *
 * Params: data may be NULL if len is 0 (to drain bytes pending after an
 * event); *consumed receives how many bytes of data were taken; *out
 * receives the event when 1 is returned (out->type is NONE otherwise).
 * Returns 1 when an event was published (the caller handles it, then calls
 * again with data + *consumed, len - *consumed, even if that is 0 bytes);
 * 0 when all of data was consumed and examined (an incomplete telegram
 * may stay buffered for the next call); RSM_ERR_INVAL for NULL p, consumed
 * or out, or NULL data with len > 0 (nothing taken).
 * Ownership: the receiver copies what it needs and keeps no pointer to data.
 * Reentrant per parser (distinct parsers are independent); one parser must
 * not be fed from two contexts at once. */
int rsm_lms_parser_feed(rsm_lms_parser_t *p, const uint8_t *data, size_t len, size_t *consumed,
                        rsm_lms_event_t *out);

/* Tells the receiver that the line has been silent long enough that a
 * partial telegram will never be completed (the driver's inter-byte or reply
 * timeout). The partial candidate is abandoned (truncated, its STX skipped)
 * and the bytes after its STX are examined again, which may publish events.
 * Call it repeatedly until it returns 0:
 *     while (rsm_lms_parser_timeout(p, &ev) == 1) { handle(&ev); }
 * Returns 1 with an event in *out, 0 once the receiver holds no bytes (it is
 * then hunting with an empty buffer), RSM_ERR_INVAL for NULL pointers.
 * Reentrant per parser. */
int rsm_lms_parser_timeout(rsm_lms_parser_t *p, rsm_lms_event_t *out);

/* Drops every buffered byte without examining it (e.g. after the host port
 * changed its baud rate); they are counted in bytes_skipped.
 * Returns the number of bytes dropped (>= 0), RSM_ERR_INVAL if p is NULL. */
int rsm_lms_parser_flush(rsm_lms_parser_t *p);

/* Bytes held: the start of a telegram not yet complete (0 between
 * telegrams). Lets a caller stamp a telegram with the arrival of its first
 * byte. Returns 0 for NULL. */
size_t rsm_lms_parser_pending(const rsm_lms_parser_t *p);

/* ---- decoders ---------------------------------------------------------- */
/* Every decoder takes a verified telegram (parser event or
 * rsm_lms_telegram_view), checks CMD and the data length, and fills *out.
 * Errors: RSM_ERR_INVAL for NULL pointers, RSM_ERR_PROTO for a different CMD
 * or a data length or field value the reply cannot have. On error *out is
 * not touched. All are pure and reentrant. */

/* Status byte (last data byte of every reply). Only bits 0-2, 6 and 7 are
 * documented well enough to act on; raw keeps the others (bit 4 is set in
 * normal replies, bit 5 reportedly means "restart required"). */
typedef struct rsm_lms_status_byte {
    uint8_t raw;
    uint8_t severity;    /* bits 0-2: RSM_LMS_SEVERITY_* (5-7 reserved) */
    uint8_t implausible; /* bit 6: implausible measured values (0/1) */
    uint8_t pollution;   /* bit 7: front screen dirty (0/1) */
} rsm_lms_status_byte_t;

#define RSM_LMS_SEVERITY_NONE 0u
#define RSM_LMS_SEVERITY_INFO 1u
#define RSM_LMS_SEVERITY_WARNING 2u
#define RSM_LMS_SEVERITY_ERROR 3u
#define RSM_LMS_SEVERITY_FATAL 4u

/* Splits a status byte into its fields. Returns RSM_OK, or RSM_ERR_INVAL if
 * out is NULL. Pure. */
int rsm_lms_decode_status_byte(uint8_t status, rsm_lms_status_byte_t *out);

/* What the 0xB0 decoder needs to know from the configuration. */
typedef struct rsm_lms_b0_format {
    uint8_t units;         /* RSM_LMS_UNITS_AUTO: take the units from the count
                              word (default); _CM or _MM: require them */
    uint8_t distance_bits; /* 13, 14, 15 or 16 low bits are the distance; the
                              bits above are flags (default 13) */
    uint8_t index_bytes;   /* 0..2 real-time/telegram index bytes between the
                              last value and the status (default 0) */
} rsm_lms_b0_format_t;

/* The default 0xB0 format: units from the count word, 13 distance bits with
 * flags in bits 13-15 (measuring modes 0x00-0x02, the factory setting), no
 * index bytes. Returns RSM_OK, or RSM_ERR_INVAL if fmt is NULL. Pure. */
int rsm_lms_b0_format_default(rsm_lms_b0_format_t *fmt);

/* Derives the 0xB0 format from a configuration block: distance bits from
 * byte D (0x00-0x02 -> 13, 0x03-0x04 -> 14, 0x05-0x06 -> 15, 0x0F -> 16),
 * units from byte E, and 2 index bytes when bit 1 of byte C is set (our
 * reference gives "up to 2" for that option; the exact count is unverified).
 * Returns RSM_OK; RSM_ERR_INVAL for NULL pointers; RSM_ERR_PROTO if D is
 * 0x3F (reflectivity, not ranges) or another unlisted code, or E is not
 * cm/mm. *fmt untouched on error. Pure. */
int rsm_lms_b0_format_from_config(const rsm_lms_config_t *cfg, rsm_lms_b0_format_t *fmt);

/* Why a reading is not a range. 0 means a valid range. The codes are the
 * top nine values of the distance field: for 13 bits 0x1FFF no echo,
 * 0x1FFE dazzled, 0x1FFD overflow, 0x1FFB signal-to-noise too low, 0x1FFA
 * channel-1 error, 0x1FF7 larger than the maximum, 0x1FF8/0x1FF9/0x1FFC
 * reserved; the same offsets below 0x3FFF, 0x7FFF, 0xFFFF for 14, 15, 16
 * bits (the 16-bit codes are an extrapolation, unverified). */
typedef enum rsm_lms_reading_code {
    RSM_LMS_READING_OK = 0,
    RSM_LMS_READING_NO_ECHO = 1,
    RSM_LMS_READING_DAZZLED = 2,
    RSM_LMS_READING_OVERFLOW = 3,
    RSM_LMS_READING_SNR_LOW = 4,
    RSM_LMS_READING_CHANNEL_ERROR = 5,
    RSM_LMS_READING_TOO_FAR = 6,
    RSM_LMS_READING_RESERVED = 7
} rsm_lms_reading_code_t;

/* One reading of a 0xB0 telegram (8 bytes). */
typedef struct rsm_lms_reading {
    float range_m; /* distance in metres when code is OK; 0.0f otherwise,
                      never to be used as a range */
    uint16_t raw;  /* the value word as sent */
    uint8_t flags; /* the bits above the distance field, shifted down to bit 0
                      (mode 0x00: bit 0 field A, bit 1 field B, bit 2 dazzle) */
    uint8_t code;  /* rsm_lms_reading_code_t */
} rsm_lms_reading_t;

/* A decoded 0xB0 measured-values telegram. */
typedef struct rsm_lms_scan {
    rsm_lms_reading_t reading[RSM_MAX_BEAMS];
    size_t count;            /* readings in reading[] (count word bits 0-9) */
    uint16_t count_word;     /* the count word as sent */
    uint16_t distance_mask;  /* (1 << distance_bits) - 1: raw & mask is the
                                distance in telegram units (or the code) */
    uint8_t units;           /* RSM_LMS_UNITS_CM or _MM (bits 14-15) */
    uint8_t partial;         /* bit 13: part of an interlaced scan (0/1) */
    uint8_t partial_index;   /* bits 11-12: which 0.25 deg offset */
    uint8_t status;          /* status byte */
    uint8_t index[2];        /* optional index bytes, as sent */
    uint8_t index_len;       /* how many of index[] are present */
    /* Scanner angle of reading i is start_cdeg + i * step_cdeg, in 1/100 deg.
     * Known only for full scans (partial bit clear) of a listed size:
     * 181 -> 0 deg step 1 deg; 361 -> 0 deg step 0.5 deg (both over 180 deg);
     * 101 -> 40 deg step 1 deg; 201 -> 40 deg step 0.5 deg;
     * 401 -> 40 deg step 0.25 deg (all three over 100 deg, 40..140 deg).
     * For other counts step_cdeg is 0 and the angles are unknown. */
    uint16_t start_cdeg;
    uint16_t step_cdeg;
} rsm_lms_scan_t;

/* A 0xB0 reply checked and read up to its readings: its header, and where
 * its values are, so that the readings decode one at a time
 * (rsm_lms_b0_reading) into whatever the caller keeps (rsm_lms_decode_b0:
 * an rsm_lms_scan_t; the LMS driver: the caller's rsm_scan_t, with no copy
 * between). Fields as in rsm_lms_scan_t. */
typedef struct rsm_lms_b0_view {
    const uint8_t *values;   /* the 2 * count value bytes, in the telegram
                                (borrowed: valid while the telegram is) */
    size_t count;
    uint16_t count_word;
    uint16_t distance_mask;
    uint8_t distance_bits;
    uint8_t units;
    uint8_t partial;
    uint8_t partial_index;
    uint8_t status;
    uint8_t index[2];
    uint8_t index_len;
    uint16_t start_cdeg;
    uint16_t step_cdeg;
} rsm_lms_b0_view_t;

/* Checks a 0xB0 reply as rsm_lms_decode_b0 does (same codes) and fills
 * *out (untouched on error). Pure. */
int rsm_lms_b0_open(const rsm_lms_telegram_t *t, const rsm_lms_b0_format_t *fmt, rsm_lms_b0_view_t *out);

/* Reading i (< v->count) of an opened reply, decoded as rsm_lms_decode_b0
 * describes. Pure. */
rsm_lms_reading_t rsm_lms_b0_reading(const rsm_lms_b0_view_t *v, size_t i);

/* Decodes a 0xB0 reply (rsm_lms_b0_open, then every reading).
 * Params: fmt may be NULL for rsm_lms_b0_format_default; out must hold
 * RSM_MAX_BEAMS readings.
 * Checks: data_len == 2 (count word) + 2 * count + fmt->index_bytes + 1
 * (status), units bits 0 or 1 and equal to fmt->units unless AUTO, else
 * RSM_ERR_PROTO; count > RSM_MAX_BEAMS gives RSM_ERR_NOMEM; an fmt with
 * distance_bits outside 13..16, index_bytes > 2 or unknown units gives
 * RSM_ERR_INVAL. Distances are raw & distance_mask scaled by the units
 * (1 mm or 1 cm); the top nine distance values are error codes and give an
 * invalid reading (code != OK, range_m 0). Flag bits never invalidate a
 * reading. Returns RSM_OK; *out untouched on error.
 * A macro, as rsm_localizer_init: it passes the caller's
 * sizeof(rsm_lms_scan_t) and RSM_CONFIG_FINGERPRINT, so that a caller
 * compiled with other capacities than the library (RSM_MAX_BEAMS sizes
 * the scan) gets RSM_ERR_CONFIG, with out unchanged, instead of readings
 * written past its struct. */
#define rsm_lms_decode_b0(t, fmt, out) \
    rsm_lms_decode_b0_checked((t), (fmt), (out), sizeof(rsm_lms_scan_t), (unsigned long)RSM_CONFIG_FINGERPRINT)

int rsm_lms_decode_b0_checked(const rsm_lms_telegram_t *t, const rsm_lms_b0_format_t *fmt, rsm_lms_scan_t *out,
                              size_t out_size, unsigned long fingerprint);

/* Scanner-frame angle of reading i of a decoded scan, in radians (0 right,
 * pi/2 ahead, pi left). Returns RSM_OK; RSM_ERR_INVAL for NULL pointers;
 * RSM_ERR_RANGE if i >= count or the scan's angles are unknown
 * (step_cdeg 0). *angle_rad untouched on error. Pure. */
int rsm_lms_scan_angle(const rsm_lms_scan_t *scan, size_t i, float *angle_rad);

/* 0xA0 reply to a mode change. */
typedef struct rsm_lms_mode_reply {
    uint8_t result; /* RSM_LMS_MODE_RESULT_* (other values passed through) */
    uint8_t status; /* status byte */
} rsm_lms_mode_reply_t;

/* Decodes a 0xA0 reply: result byte then status (data_len must be 2).
 * Params: t a verified telegram; out written on success only.
 * Returns RSM_OK, RSM_ERR_INVAL (NULL), RSM_ERR_PROTO (other CMD or length).
 * Pure, reentrant. */
int rsm_lms_decode_mode_reply(const rsm_lms_telegram_t *t, rsm_lms_mode_reply_t *out);

/* 0xBB reply to a variant change. On refusal the LMS keeps, and echoes, its
 * old variant. */
typedef struct rsm_lms_variant_reply {
    uint8_t result;           /* RSM_LMS_RESULT_ACCEPTED or _REFUSED */
    uint16_t angle_deg;       /* angular range, degrees */
    uint16_t resolution_cdeg; /* angular resolution, 1/100 degree */
    uint8_t status;           /* status byte */
} rsm_lms_variant_reply_t;

/* Decodes a 0xBB reply: result, u16 angle, u16 resolution, status
 * (data_len must be 6).
 * Params: t a verified telegram; out written on success only.
 * Returns RSM_OK, RSM_ERR_INVAL (NULL), RSM_ERR_PROTO (other CMD or length).
 * Pure, reentrant. */
int rsm_lms_decode_variant_reply(const rsm_lms_telegram_t *t, rsm_lms_variant_reply_t *out);

/* Decodes a 0x91 reply to a reset, which carries only the status byte
 * (data_len must be 1).
 * Params: t a verified telegram; *status written on success only.
 * Returns RSM_OK, RSM_ERR_INVAL (NULL), RSM_ERR_PROTO (other CMD or length).
 * Pure, reentrant. */
int rsm_lms_decode_reset_reply(const rsm_lms_telegram_t *t, uint8_t *status);

/* Decodes a 0x92 "command not accepted" reply: a logical rejection of the
 * last request, distinct from the NAK byte. The status byte is the last data
 * byte; bytes before it are not documented in our reference and are ignored
 * (data_len >= 1).
 * Params: t a verified telegram; *status written on success only.
 * Returns RSM_OK, RSM_ERR_INVAL (NULL), RSM_ERR_PROTO (other CMD, no data).
 * Pure, reentrant. */
int rsm_lms_decode_not_ack(const rsm_lms_telegram_t *t, uint8_t *status);

/* Text replies: 0x90 power-on telegram and 0xBA device type, both ASCII
 * text (e.g. "LMS200;301063;V02.10 ") then the status byte. */
typedef struct rsm_lms_text_reply {
    char text[RSM_LMS_TEXT_MAX + 1]; /* bytes as sent (not interpreted), then
                                        NUL padding */
    size_t text_len;                 /* bytes of text, data_len - 1 */
    uint8_t status;                  /* status byte */
} rsm_lms_text_reply_t;

/* Decodes a 0x90 power-on telegram (sent unsolicited after power-up or a
 * reset): text then status (data_len >= 1).
 * Params: t a verified telegram; out written on success only.
 * Returns RSM_OK, RSM_ERR_INVAL (NULL), RSM_ERR_PROTO (other CMD, no data),
 * RSM_ERR_NOMEM (text longer than RSM_LMS_TEXT_MAX). Pure, reentrant. */
int rsm_lms_decode_power_on(const rsm_lms_telegram_t *t, rsm_lms_text_reply_t *out);

/* Decodes a 0xBA device-type reply: text then status (data_len >= 1).
 * Params and returns as rsm_lms_decode_power_on. Pure, reentrant. */
int rsm_lms_decode_type_reply(const rsm_lms_telegram_t *t, rsm_lms_text_reply_t *out);

/* Decodes a 0xF4 reply: the configuration block then status (data_len 33 or
 * 35). Fills the raw block, the named fields and the status.
 * Params: t a verified telegram; out written on success only.
 * Returns RSM_OK, RSM_ERR_INVAL (NULL), RSM_ERR_PROTO (other CMD or length).
 * Field values are not range-checked here (see
 * rsm_lms_b0_format_from_config and rsm_lms_encode_config). Pure, reentrant. */
int rsm_lms_decode_config(const rsm_lms_telegram_t *t, rsm_lms_config_t *out);

/* 0xF7 reply to a configuration write. */
typedef struct rsm_lms_config_reply {
    uint8_t result;          /* RSM_LMS_RESULT_ACCEPTED or _REFUSED */
    rsm_lms_config_t config; /* the echoed block (its status is the reply's) */
} rsm_lms_config_reply_t;

/* Decodes a 0xF7 reply: result, the echoed block, status (data_len 34 or
 * 36). Allow several seconds for it after a 0x77 (the LMS writes EEPROM).
 * Params: t a verified telegram; out written on success only.
 * Returns RSM_OK, RSM_ERR_INVAL (NULL), RSM_ERR_PROTO (other CMD or length).
 * Pure, reentrant. */
int rsm_lms_decode_config_reply(const rsm_lms_telegram_t *t, rsm_lms_config_reply_t *out);

#ifdef __cplusplus
}
#endif

#endif /* RSM_LMS_H */
