/* POSIX port: byte links over file descriptors (ttys, pseudo-terminals,
 * regular files, pipes, FIFOs, stdin) and over libserialport (real serial
 * devices), plus a monotonic clock, each filling the HAL structs of
 * rsm/hal.h.
 *
 * All state lives in structs owned by the caller; the port has no globals,
 * so any number of links may be open at once. A filled rsm_link_t keeps a
 * pointer to its state struct in link->ctx: the state must stay valid, and
 * must not move, while the link is used.
 *
 * Error reporting: every function returns an rsm status (rsm/status.h).
 * When the operating system reported the failure, the state keeps the
 * errno in last_errno (0 when the failure was not an OS error), so that a
 * tool can print strerror(last_errno) next to rsm_strerror(status).
 *
 * End of stream and vanished devices (hal.h convention): the end of a
 * regular file, or of a pipe or FIFO whose writers all closed, is reported
 * by read as RSM_ERR_IO with eof set to 1 and last_errno 0. A device that
 * goes away (pty master closed, USB adapter unplugged: EIO, ENXIO, POLLHUP
 * without data) is reported as RSM_ERR_IO with eof 0 and last_errno set.
 * Neither ever blocks past the timeout nor spins: every later read returns
 * the same error at once.
 *
 * Thread safety: none of these functions touches shared data; one link
 * must not be used from two threads at once. Nothing here is ISR-safe. */
#ifndef RSM_POSIX_H
#define RSM_POSIX_H

#include <stddef.h>
#include <stdint.h>
#include <termios.h>

#include "rsm/hal.h"
#include "rsm/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- open flags ------------------------------------------------------------ */

/* Open for reading only (captures, stdin, read-only devices); write then
 * fails with RSM_ERR_IO and last_errno EBADF. Regular files and FIFOs are
 * always opened read-only. */
#define RSM_POSIX_OPEN_RDONLY 0x0001u
/* Refuse anything that is not a terminal: RSM_ERR_INVAL, last_errno ENOTTY. */
#define RSM_POSIX_OPEN_REQUIRE_TTY 0x0002u
/* rsm_posix_link_open_auto only: never use libserialport, even for real
 * serial devices. */
#define RSM_POSIX_OPEN_NO_SERIALPORT 0x0004u

/* Transmit timeout used by write when the device does not accept bytes, in
 * milliseconds (write then returns 0, which rsm_link_write_all turns into
 * RSM_ERR_TIMEOUT). */
#define RSM_POSIX_WRITE_TIMEOUT_MS 1000u

/* ---- file-descriptor link ---------------------------------------------------- */

/* State of a link over a file descriptor. Fill it with rsm_posix_fd_open or
 * rsm_posix_fd_adopt; read the public fields at any time, never write them. */
typedef struct rsm_posix_fd_link {
    int fd;             /* the descriptor, -1 when closed */
    int owns_fd;        /* 1: rsm_posix_fd_close closes fd */
    int is_tty;         /* 1: a terminal (termios raw 8N1 applied) */
    int readable;       /* 1: opened with read access */
    int writable;       /* 1: opened with write access */
    int eof;            /* 1 once end of file/pipe was seen (sticky) */
    int hangup;         /* 1 once the device vanished (sticky) */
    int last_errno;     /* errno of the last OS failure, 0 if none */
    uint32_t baud;      /* current line rate for ttys, 0 otherwise */
    uint32_t eof_count; /* reads that returned end of stream */
    uint32_t write_timeout_ms; /* see RSM_POSIX_WRITE_TIMEOUT_MS; may be changed
                                  by the caller between calls */
    int saved_valid;           /* private: saved_tio holds the settings found */
    struct termios saved_tio;  /* private: terminal settings before set-up,
                                  restored by rsm_posix_fd_close */
} rsm_posix_fd_link_t;

/* Opens path and fills *s. path is borrowed (not kept).
 * baud: for a terminal, the line rate to set (0 keeps the current rate);
 * ignored for other files. flags: RSM_POSIX_OPEN_*.
 * Terminals are opened read-write (unless RSM_POSIX_OPEN_RDONLY), with
 * O_NOCTTY and O_NONBLOCK, and put in raw 8N1 mode without flow control;
 * pending input is kept. Regular files and FIFOs are opened read-only; a
 * FIFO open blocks until a writer appears, as for any reader.
 * Returns RSM_OK, or on error (s->fd is -1, last_errno set where the OS
 * failed):
 *   RSM_ERR_INVAL  NULL s or path; not a tty with RSM_POSIX_OPEN_REQUIRE_TTY
 *                  (last_errno ENOTTY); a directory (EISDIR);
 *   RSM_ERR_RANGE  baud not a rate this platform supports (tty only);
 *   RSM_ERR_IO     open or termios failed: ENOENT (no such path), EACCES
 *                  (permission denied), EBUSY, ...
 * Not reentrant with respect to errno only. */
int rsm_posix_fd_open(rsm_posix_fd_link_t *s, const char *path, uint32_t baud, unsigned flags);

/* Adopts an open descriptor (e.g. STDIN_FILENO, one end of a pipe, a pty
 * master). owns_fd: 1 to let rsm_posix_fd_close close it. Access mode is
 * taken from fcntl(F_GETFL) (restricted by RSM_POSIX_OPEN_RDONLY). A
 * terminal is set to raw 8N1 (and to baud if non-zero) exactly as by
 * rsm_posix_fd_open; O_NONBLOCK is not changed (read waits in poll, so a
 * blocking descriptor is fine). Returns RSM_OK, RSM_ERR_INVAL (NULL s,
 * fd < 0, fd not open: last_errno EBADF, or RSM_POSIX_OPEN_REQUIRE_TTY on a
 * non-tty), RSM_ERR_RANGE (unsupported baud) or RSM_ERR_IO (termios
 * failed). On error *s is closed-looking (fd -1) and fd is left open. */
int rsm_posix_fd_adopt(rsm_posix_fd_link_t *s, int fd, uint32_t baud, unsigned flags, int owns_fd);

/* Fills *link with the fd callbacks and link->ctx = s (kept: s must outlive
 * every use of link). read: poll() then read(); write: loops over partial
 * writes, waiting up to write_timeout_ms for the device to drain;
 * set_baud: termios on a tty, RSM_OK without effect on other files;
 * flush: tcflush(TCIFLUSH) on a tty, RSM_OK without effect otherwise.
 * Returns RSM_OK or RSM_ERR_INVAL (NULL s or link). */
int rsm_posix_fd_link(rsm_posix_fd_link_t *s, rsm_link_t *link);

/* Restores a terminal's settings as they were before open/adopt (so that
 * adopting an interactive stdin does not leave it raw), then closes the
 * descriptor if owned; s->fd becomes -1. Safe to call twice.
 * Returns RSM_OK, RSM_ERR_INVAL (NULL s) or RSM_ERR_IO (close failed;
 * the descriptor is released anyway, last_errno set). */
int rsm_posix_fd_close(rsm_posix_fd_link_t *s);

/* Returns 1 if baud (bits per second) is a rate the platform's termios can
 * set (standard rates 50..4000000 where defined, e.g. 9600, 19200, 38400,
 * 57600, 115200, 230400, 460800, 500000), 0 otherwise. Pure. */
int rsm_posix_baud_supported(uint32_t baud);

/* ---- libserialport link -------------------------------------------------------- */

struct sp_port; /* libserialport's opaque port */

/* State of a link over libserialport. Only usable when the port was built
 * with RSM_HAVE_LIBSERIALPORT; otherwise every function returns
 * RSM_ERR_NOSYS. Public fields are read-only for the caller. */
typedef struct rsm_posix_serial_link {
    struct sp_port *port; /* NULL when closed */
    int hangup;           /* 1 once the device vanished (sticky) */
    int last_errno;       /* errno from the last SP_ERR_FAIL, 0 if none */
    int last_sp_error;    /* last libserialport return code (< 0), 0 if none */
    uint32_t baud;        /* current line rate */
    uint32_t write_timeout_ms; /* transmit timeout, RSM_POSIX_WRITE_TIMEOUT_MS */
} rsm_posix_serial_link_t;

/* Opens a real serial device by port name (e.g. the device path) with
 * libserialport, read-write, raw 8N1, no flow control, at baud (must be
 * non-zero). name is borrowed. libserialport cannot open pseudo-terminals:
 * use rsm_posix_fd_open or rsm_posix_link_open_auto for those.
 * Returns RSM_OK, or RSM_ERR_INVAL (NULL/empty arguments, baud 0),
 * RSM_ERR_RANGE (rate refused), RSM_ERR_IO (open failed, last_errno set),
 * RSM_ERR_NOSYS (built without libserialport). s->port is NULL on error. */
int rsm_posix_serial_open(rsm_posix_serial_link_t *s, const char *name, uint32_t baud);

/* Fills *link with the libserialport callbacks and link->ctx = s (kept).
 * read: sp_blocking_read_next (timeout 0: sp_nonblocking_read); write:
 * sp_blocking_write with write_timeout_ms; set_baud: sp_set_baudrate;
 * flush: sp_flush(SP_BUF_INPUT). Returns RSM_OK, RSM_ERR_INVAL or
 * RSM_ERR_NOSYS (built without libserialport). */
int rsm_posix_serial_link(rsm_posix_serial_link_t *s, rsm_link_t *link);

/* Closes and frees the port; s->port becomes NULL. Safe to call twice.
 * Returns RSM_OK, RSM_ERR_INVAL (NULL s) or RSM_ERR_NOSYS. */
int rsm_posix_serial_close(rsm_posix_serial_link_t *s);

/* ---- automatic choice ---------------------------------------------------------- */

typedef enum rsm_posix_link_kind {
    RSM_POSIX_LINK_NONE = 0,   /* not open */
    RSM_POSIX_LINK_FD = 1,     /* rsm_posix_fd_link_t in use */
    RSM_POSIX_LINK_SERIAL = 2  /* rsm_posix_serial_link_t in use */
} rsm_posix_link_kind_t;

/* State for rsm_posix_link_open_auto: one of the two backends. */
typedef struct rsm_posix_auto_link {
    rsm_posix_link_kind_t kind;
    rsm_posix_fd_link_t fd;         /* valid when kind is FD */
    rsm_posix_serial_link_t serial; /* valid when kind is SERIAL */
    int last_errno;                 /* errno of the failure that ended the
                                       open, 0 if none or not an OS error */
} rsm_posix_auto_link_t;

/* Opens path with the backend that fits and fills *link (link->ctx points
 * into *s: s must outlive every use of link).
 *   "-"                 stdin, adopted read-only (not closed on close);
 *   a character device that is a terminal: libserialport when available
 *                       (and RSM_POSIX_OPEN_NO_SERIALPORT not given), else
 *                       or if libserialport cannot open it (pseudo-
 *                       terminals), the fd backend;
 *   anything else (regular file, FIFO, other device): the fd backend.
 * baud: line rate for terminals (0 keeps the current rate; libserialport
 * needs a rate, so baud 0 means the fd backend). flags: RSM_POSIX_OPEN_*.
 * Returns RSM_OK, or on error (kind NONE, last_errno kept):
 *   RSM_ERR_INVAL  NULL argument, empty path, a directory (EISDIR), not a
 *                  terminal with RSM_POSIX_OPEN_REQUIRE_TTY (ENOTTY);
 *   RSM_ERR_RANGE  unsupported baud rate on a terminal;
 *   RSM_ERR_IO     the path does not exist (ENOENT), permission denied
 *                  (EACCES), or another open/termios failure. */
int rsm_posix_link_open_auto(rsm_posix_auto_link_t *s, const char *path, uint32_t baud,
                             unsigned flags, rsm_link_t *link);

/* Returns the errno kept by the backend in use (or by the failed open),
 * 0 if none or for NULL s. */
int rsm_posix_auto_errno(const rsm_posix_auto_link_t *s);

/* Returns 1 if the backend in use reached the end of a file or pipe, 0
 * otherwise (including a vanished device, which is an error, not an end). */
int rsm_posix_auto_eof(const rsm_posix_auto_link_t *s);

/* Closes whichever backend is open; kind becomes NONE. Safe to call twice.
 * Returns RSM_OK, RSM_ERR_INVAL (NULL s) or the backend's close status. */
int rsm_posix_link_close(rsm_posix_auto_link_t *s);

/* ---- clock ----------------------------------------------------------------------- */

/* Microseconds from clock_gettime(CLOCK_MONOTONIC); ctx is ignored. Never
 * decreases; 0 if the clock cannot be read (it always can on POSIX.1-2008
 * systems with the monotonic clock option). Reentrant, thread-safe. */
uint64_t rsm_posix_clock_now_us(void *ctx);

/* Fills *clock with rsm_posix_clock_now_us and ctx NULL. Returns RSM_OK or
 * RSM_ERR_INVAL (NULL clock). */
int rsm_posix_clock_init(rsm_clock_t *clock);

#ifdef __cplusplus
}
#endif

#endif /* RSM_POSIX_H */
