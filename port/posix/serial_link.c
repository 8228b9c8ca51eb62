/* rsm_link_t over libserialport for real serial devices, and the automatic
 * choice between it and the file-descriptor link. */
#include "rsm_posix.h"

#include <errno.h>
#include <limits.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#ifdef RSM_HAVE_LIBSERIALPORT
#include <libserialport.h>
#endif

#ifdef RSM_HAVE_LIBSERIALPORT

/* Records a libserialport failure; SP_ERR_FAIL carries an OS error code. */
static int sp_fail(rsm_posix_serial_link_t *s, enum sp_return r)
{
    s->last_sp_error = (int)r;
    if (r == SP_ERR_FAIL) {
        s->last_errno = sp_last_error_code();
        if (s->last_errno == EIO || s->last_errno == ENXIO || s->last_errno == ENODEV) {
            s->hangup = 1;
        }
        return RSM_ERR_IO;
    }
    if (r == SP_ERR_SUPP) {
        return RSM_ERR_NOSYS;
    }
    if (r == SP_ERR_ARG) {
        return RSM_ERR_INVAL;
    }
    return RSM_ERR_IO;
}

static unsigned int us_to_ms_ceil(uint32_t us)
{
    return (unsigned int)(((uint64_t)us + 999u) / 1000u);
}

static int serial_read(void *ctx, uint8_t *buf, size_t cap, uint32_t timeout_us)
{
    rsm_posix_serial_link_t *s = (rsm_posix_serial_link_t *)ctx;
    enum sp_return r;
    if (s == NULL || s->port == NULL) {
        return RSM_ERR_INVAL;
    }
    if (s->hangup) {
        return RSM_ERR_IO;
    }
    if (cap == 0u) {
        return 0;
    }
    if (cap > (size_t)INT_MAX) {
        cap = (size_t)INT_MAX;
    }
    /* libserialport treats a timeout of 0 ms as "wait forever", so a poll
     * must use the non-blocking call. */
    if (timeout_us == 0u) {
        r = sp_nonblocking_read(s->port, buf, cap);
    } else {
        r = sp_blocking_read_next(s->port, buf, cap, us_to_ms_ceil(timeout_us));
    }
    if (r < 0) {
        return sp_fail(s, r);
    }
    return (int)r;
}

static int serial_write(void *ctx, const uint8_t *buf, size_t len)
{
    rsm_posix_serial_link_t *s = (rsm_posix_serial_link_t *)ctx;
    enum sp_return r;
    if (s == NULL || s->port == NULL || (buf == NULL && len > 0u)) {
        return RSM_ERR_INVAL;
    }
    if (s->hangup) {
        return RSM_ERR_IO;
    }
    if (len > (size_t)INT_MAX) {
        len = (size_t)INT_MAX;
    }
    /* A zero timeout would wait forever; the HAL wants a bounded write. */
    r = sp_blocking_write(s->port, buf, len, s->write_timeout_ms == 0u ? 1u : s->write_timeout_ms);
    if (r < 0) {
        return sp_fail(s, r);
    }
    return (int)r;
}

static int serial_set_baud(void *ctx, uint32_t baud)
{
    rsm_posix_serial_link_t *s = (rsm_posix_serial_link_t *)ctx;
    enum sp_return r;
    if (s == NULL || s->port == NULL || baud == 0u || baud > (uint32_t)INT_MAX) {
        return RSM_ERR_INVAL;
    }
    /* Let pending output leave at the old rate, as hal.h asks. */
    (void)sp_drain(s->port);
    r = sp_set_baudrate(s->port, (int)baud);
    if (r < 0) {
        const int status = sp_fail(s, r);
        return status == RSM_ERR_IO && s->last_errno == EINVAL ? RSM_ERR_RANGE : status;
    }
    s->baud = baud;
    return RSM_OK;
}

static int serial_flush(void *ctx)
{
    rsm_posix_serial_link_t *s = (rsm_posix_serial_link_t *)ctx;
    enum sp_return r;
    if (s == NULL || s->port == NULL) {
        return RSM_ERR_INVAL;
    }
    r = sp_flush(s->port, SP_BUF_INPUT);
    return r < 0 ? sp_fail(s, r) : RSM_OK;
}

int rsm_posix_serial_open(rsm_posix_serial_link_t *s, const char *name, uint32_t baud)
{
    enum sp_return r;
    struct sp_port *port = NULL;
    if (s == NULL) {
        return RSM_ERR_INVAL;
    }
    memset(s, 0, sizeof *s);
    s->write_timeout_ms = RSM_POSIX_WRITE_TIMEOUT_MS;
    if (name == NULL || name[0] == '\0' || baud == 0u || baud > (uint32_t)INT_MAX) {
        return RSM_ERR_INVAL;
    }
    r = sp_get_port_by_name(name, &port);
    if (r < 0) {
        return sp_fail(s, r);
    }
    r = sp_open(port, SP_MODE_READ_WRITE);
    if (r < 0) {
        const int status = sp_fail(s, r);
        sp_free_port(port);
        return status;
    }
    /* Raw 8N1, no flow control. */
    if ((r = sp_set_bits(port, 8)) < 0 || (r = sp_set_parity(port, SP_PARITY_NONE)) < 0 ||
        (r = sp_set_stopbits(port, 1)) < 0 || (r = sp_set_flowcontrol(port, SP_FLOWCONTROL_NONE)) < 0) {
        const int status = sp_fail(s, r);
        (void)sp_close(port);
        sp_free_port(port);
        return status;
    }
    if ((r = sp_set_baudrate(port, (int)baud)) < 0) {
        const int status = sp_fail(s, r);
        (void)sp_close(port);
        sp_free_port(port);
        return status == RSM_ERR_IO && s->last_errno == EINVAL ? RSM_ERR_RANGE : status;
    }
    s->port = port;
    s->baud = baud;
    return RSM_OK;
}

int rsm_posix_serial_link(rsm_posix_serial_link_t *s, rsm_link_t *link)
{
    if (s == NULL || link == NULL) {
        return RSM_ERR_INVAL;
    }
    link->read = serial_read;
    link->write = serial_write;
    link->set_baud = serial_set_baud;
    link->flush = serial_flush;
    link->ctx = s;
    return RSM_OK;
}

int rsm_posix_serial_close(rsm_posix_serial_link_t *s)
{
    if (s == NULL) {
        return RSM_ERR_INVAL;
    }
    if (s->port != NULL) {
        (void)sp_close(s->port);
        sp_free_port(s->port);
        s->port = NULL;
    }
    return RSM_OK;
}

#else /* !RSM_HAVE_LIBSERIALPORT */

int rsm_posix_serial_open(rsm_posix_serial_link_t *s, const char *name, uint32_t baud)
{
    (void)name;
    (void)baud;
    if (s != NULL) {
        memset(s, 0, sizeof *s);
    }
    return RSM_ERR_NOSYS;
}

int rsm_posix_serial_link(rsm_posix_serial_link_t *s, rsm_link_t *link)
{
    (void)s;
    (void)link;
    return RSM_ERR_NOSYS;
}

int rsm_posix_serial_close(rsm_posix_serial_link_t *s)
{
    return s == NULL ? RSM_ERR_INVAL : RSM_OK;
}

#endif /* RSM_HAVE_LIBSERIALPORT */

/* ---- automatic choice ------------------------------------------------------------ */

int rsm_posix_link_open_auto(rsm_posix_auto_link_t *s, const char *path, uint32_t baud,
                             unsigned flags, rsm_link_t *link)
{
    struct stat st;
    int status;
    if (s == NULL) {
        return RSM_ERR_INVAL;
    }
    memset(s, 0, sizeof *s);
    s->kind = RSM_POSIX_LINK_NONE;
    s->fd.fd = -1;
    if (path == NULL || path[0] == '\0' || link == NULL) {
        return RSM_ERR_INVAL;
    }
    if (strcmp(path, "-") == 0) {
        status = rsm_posix_fd_adopt(&s->fd, STDIN_FILENO, baud, flags | RSM_POSIX_OPEN_RDONLY, 0);
        s->last_errno = s->fd.last_errno;
        if (status == RSM_OK) {
            s->kind = RSM_POSIX_LINK_FD;
            (void)rsm_posix_fd_link(&s->fd, link);
        }
        return status;
    }
    if (stat(path, &st) != 0) {
        s->last_errno = errno;
        return RSM_ERR_IO;
    }
#ifdef RSM_HAVE_LIBSERIALPORT
    if (S_ISCHR(st.st_mode) && baud != 0u && (flags & RSM_POSIX_OPEN_NO_SERIALPORT) == 0u &&
        (flags & RSM_POSIX_OPEN_RDONLY) == 0u) {
        /* A real serial device goes through libserialport. It refuses
         * pseudo-terminals (and non-serial character devices); those fall
         * through to the fd backend, which reports its own errors. */
        status = rsm_posix_serial_open(&s->serial, path, baud);
        if (status == RSM_OK) {
            s->kind = RSM_POSIX_LINK_SERIAL;
            (void)rsm_posix_serial_link(&s->serial, link);
            return RSM_OK;
        }
        if (status == RSM_ERR_RANGE) {
            s->last_errno = s->serial.last_errno;
            return status;
        }
    }
#endif
    status = rsm_posix_fd_open(&s->fd, path, baud, flags);
    s->last_errno = s->fd.last_errno;
    if (status == RSM_OK) {
        s->kind = RSM_POSIX_LINK_FD;
        (void)rsm_posix_fd_link(&s->fd, link);
    }
    return status;
}

int rsm_posix_auto_errno(const rsm_posix_auto_link_t *s)
{
    if (s == NULL) {
        return 0;
    }
    if (s->kind == RSM_POSIX_LINK_FD) {
        return s->fd.last_errno;
    }
    if (s->kind == RSM_POSIX_LINK_SERIAL) {
        return s->serial.last_errno;
    }
    return s->last_errno;
}

int rsm_posix_auto_eof(const rsm_posix_auto_link_t *s)
{
    return s != NULL && s->kind == RSM_POSIX_LINK_FD && s->fd.eof ? 1 : 0;
}

int rsm_posix_link_close(rsm_posix_auto_link_t *s)
{
    int status = RSM_OK;
    if (s == NULL) {
        return RSM_ERR_INVAL;
    }
    if (s->kind == RSM_POSIX_LINK_FD) {
        status = rsm_posix_fd_close(&s->fd);
    } else if (s->kind == RSM_POSIX_LINK_SERIAL) {
        status = rsm_posix_serial_close(&s->serial);
    }
    s->kind = RSM_POSIX_LINK_NONE;
    return status;
}
