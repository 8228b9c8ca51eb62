/* rsm_link_t over a plain file descriptor: termios for terminals (real ones
 * and pseudo-terminals), nothing special for files, pipes and FIFOs. */
#include "rsm_posix.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <poll.h>
#include <string.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

/* ---- baud rates ------------------------------------------------------------- */

typedef struct baud_entry {
    uint32_t baud;
    speed_t code;
} baud_entry_t;

/* Only the rates the platform's termios.h defines; anything else is refused
 * rather than approximated (a wrong rate gives garbage, not an error). */
static const baud_entry_t baud_table[] = {
    {50u, B50},         {75u, B75},         {110u, B110},       {134u, B134},
    {150u, B150},       {200u, B200},       {300u, B300},       {600u, B600},
    {1200u, B1200},     {1800u, B1800},     {2400u, B2400},     {4800u, B4800},
    {9600u, B9600},     {19200u, B19200},   {38400u, B38400},
#ifdef B57600
    {57600u, B57600},
#endif
#ifdef B115200
    {115200u, B115200},
#endif
#ifdef B230400
    {230400u, B230400},
#endif
#ifdef B460800
    {460800u, B460800},
#endif
#ifdef B500000
    {500000u, B500000},
#endif
#ifdef B576000
    {576000u, B576000},
#endif
#ifdef B921600
    {921600u, B921600},
#endif
#ifdef B1000000
    {1000000u, B1000000},
#endif
#ifdef B1500000
    {1500000u, B1500000},
#endif
#ifdef B2000000
    {2000000u, B2000000},
#endif
#ifdef B3000000
    {3000000u, B3000000},
#endif
#ifdef B4000000
    {4000000u, B4000000},
#endif
};

static int baud_lookup(uint32_t baud, speed_t *code)
{
    size_t i;
    for (i = 0; i < sizeof baud_table / sizeof baud_table[0]; ++i) {
        if (baud_table[i].baud == baud) {
            *code = baud_table[i].code;
            return 1;
        }
    }
    return 0;
}

int rsm_posix_baud_supported(uint32_t baud)
{
    speed_t code;
    return baud_lookup(baud, &code);
}

/* ---- helpers ------------------------------------------------------------------ */

static void state_reset(rsm_posix_fd_link_t *s)
{
    memset(s, 0, sizeof *s);
    s->fd = -1;
    s->write_timeout_ms = RSM_POSIX_WRITE_TIMEOUT_MS;
}

static uint64_t mono_ms(void)
{
    return rsm_posix_clock_now_us(NULL) / 1000u;
}

/* Raw 8N1, no flow control, no echo, no translation: every byte passes
 * untouched (a CR inside a binary frame must not become a NL). VMIN 1 and
 * VTIME 0 make a read after poll() return what is there. */
static int tty_setup(rsm_posix_fd_link_t *s, uint32_t baud)
{
    struct termios tio;
    speed_t code = 0;
    if (baud != 0u && !baud_lookup(baud, &code)) {
        return RSM_ERR_RANGE;
    }
    if (tcgetattr(s->fd, &tio) != 0) {
        s->last_errno = errno;
        return RSM_ERR_IO;
    }
    if (!s->saved_valid) {
        s->saved_tio = tio;
        s->saved_valid = 1;
    }
    tio.c_iflag &= ~(tcflag_t)(IGNBRK | BRKINT | PARMRK | ISTRIP | INLCR | IGNCR | ICRNL | IXON |
                               IXOFF | IXANY | INPCK);
    tio.c_oflag &= ~(tcflag_t)OPOST;
    tio.c_lflag &= ~(tcflag_t)(ECHO | ECHONL | ICANON | ISIG | IEXTEN);
    tio.c_cflag &= ~(tcflag_t)(CSIZE | PARENB | CSTOPB);
#ifdef CRTSCTS
    tio.c_cflag &= ~(tcflag_t)CRTSCTS;
#endif
    tio.c_cflag |= (tcflag_t)(CS8 | CREAD | CLOCAL);
    tio.c_cc[VMIN] = 1;
    tio.c_cc[VTIME] = 0;
    if (baud != 0u) {
        if (cfsetispeed(&tio, code) != 0 || cfsetospeed(&tio, code) != 0) {
            s->last_errno = errno;
            return RSM_ERR_RANGE;
        }
    }
    if (tcsetattr(s->fd, TCSANOW, &tio) != 0) {
        s->last_errno = errno;
        return RSM_ERR_IO;
    }
    if (baud != 0u) {
        s->baud = baud;
    }
    return RSM_OK;
}

/* ---- callbacks ------------------------------------------------------------------ */

static int is_hangup_errno(int e)
{
    return e == EIO || e == ENXIO || e == ENODEV || e == EPIPE || e == ECONNRESET;
}

static int fd_read(void *ctx, uint8_t *buf, size_t cap, uint32_t timeout_us)
{
    rsm_posix_fd_link_t *s = (rsm_posix_fd_link_t *)ctx;
    const uint64_t deadline_ms = mono_ms() + ((uint64_t)timeout_us + 999u) / 1000u;
    if (s == NULL || s->fd < 0) {
        return RSM_ERR_INVAL;
    }
    if (s->eof || s->hangup) {
        /* Sticky: a caller that ignores the first error gets it again at
         * once, never a wait and never a busy poll on a dead descriptor. */
        if (s->eof) {
            s->eof_count++;
        }
        return RSM_ERR_IO;
    }
    if (!s->readable) {
        s->last_errno = EBADF;
        return RSM_ERR_IO;
    }
    if (cap == 0u) {
        return 0;
    }
    for (;;) {
        struct pollfd pfd;
        uint64_t now = mono_ms();
        int wait_ms = 0;
        int pr;
        ssize_t n;
        if (deadline_ms > now) {
            const uint64_t left = deadline_ms - now;
            wait_ms = left > (uint64_t)INT_MAX ? INT_MAX : (int)left;
        }
        pfd.fd = s->fd;
        pfd.events = POLLIN;
        pfd.revents = 0;
        pr = poll(&pfd, 1, wait_ms);
        if (pr < 0) {
            if (errno == EINTR) {
                continue;
            }
            s->last_errno = errno;
            return RSM_ERR_IO;
        }
        if (pr == 0) {
            return 0;
        }
        if (pfd.revents & POLLNVAL) {
            s->last_errno = EBADF;
            s->hangup = 1;
            return RSM_ERR_IO;
        }
        /* POLLIN, POLLHUP or POLLERR: read() tells which (data still
         * buffered is delivered before the hang-up). */
        n = read(s->fd, buf, cap);
        if (n > 0) {
            return (int)n;
        }
        if (n == 0) {
            if (s->is_tty) {
                /* A terminal reads 0 only after a hang-up (VMIN is 1). */
                s->hangup = 1;
                s->last_errno = EIO;
                return RSM_ERR_IO;
            }
            s->eof = 1;
            s->eof_count++;
            s->last_errno = 0;
            return RSM_ERR_IO;
        }
        if (errno == EINTR) {
            continue;
        }
        if (errno == EAGAIN || errno == EWOULDBLOCK) {
            if (pfd.revents & (POLLHUP | POLLERR)) {
                /* Hang-up with nothing to read; retrying would spin. */
                s->hangup = 1;
                s->last_errno = EIO;
                return RSM_ERR_IO;
            }
            continue; /* spurious wake-up: wait again until the deadline */
        }
        s->last_errno = errno;
        if (is_hangup_errno(errno)) {
            s->hangup = 1;
        }
        return RSM_ERR_IO;
    }
}

static int fd_write(void *ctx, const uint8_t *buf, size_t len)
{
    rsm_posix_fd_link_t *s = (rsm_posix_fd_link_t *)ctx;
    size_t done = 0;
    uint64_t deadline_ms;
    if (s == NULL || s->fd < 0 || (buf == NULL && len > 0u)) {
        return RSM_ERR_INVAL;
    }
    if (s->hangup) {
        return RSM_ERR_IO;
    }
    if (!s->writable) {
        s->last_errno = EBADF;
        return RSM_ERR_IO;
    }
    if (len > (size_t)INT_MAX) {
        len = (size_t)INT_MAX;
    }
    deadline_ms = mono_ms() + s->write_timeout_ms;
    while (done < len) {
        const ssize_t n = write(s->fd, buf + done, len - done);
        if (n > 0) {
            done += (size_t)n;
            continue;
        }
        if (n < 0 && errno == EINTR) {
            continue;
        }
        if (n == 0 || errno == EAGAIN || errno == EWOULDBLOCK) {
            struct pollfd pfd;
            const uint64_t now = mono_ms();
            int pr;
            if (now >= deadline_ms) {
                break; /* report what was written; 0 means "timed out" */
            }
            pfd.fd = s->fd;
            pfd.events = POLLOUT;
            pfd.revents = 0;
            pr = poll(&pfd, 1, (int)(deadline_ms - now > (uint64_t)INT_MAX ? INT_MAX
                                                                          : deadline_ms - now));
            if (pr < 0 && errno != EINTR) {
                s->last_errno = errno;
                return done > 0u ? (int)done : RSM_ERR_IO;
            }
            if (pr > 0 && (pfd.revents & (POLLHUP | POLLERR | POLLNVAL)) &&
                !(pfd.revents & POLLOUT)) {
                s->hangup = 1;
                s->last_errno = EIO;
                return done > 0u ? (int)done : RSM_ERR_IO;
            }
            continue;
        }
        s->last_errno = errno;
        if (is_hangup_errno(errno)) {
            s->hangup = 1;
        }
        /* Bytes already written count; the error shows on the next call. */
        return done > 0u ? (int)done : RSM_ERR_IO;
    }
    return (int)done;
}

static int fd_set_baud(void *ctx, uint32_t baud)
{
    rsm_posix_fd_link_t *s = (rsm_posix_fd_link_t *)ctx;
    struct termios tio;
    speed_t code;
    if (s == NULL || s->fd < 0 || baud == 0u) {
        return RSM_ERR_INVAL;
    }
    if (!s->is_tty) {
        return RSM_OK; /* files and pipes have no line rate */
    }
    if (!baud_lookup(baud, &code)) {
        return RSM_ERR_RANGE;
    }
    if (tcgetattr(s->fd, &tio) != 0) {
        s->last_errno = errno;
        return RSM_ERR_IO;
    }
    if (cfsetispeed(&tio, code) != 0 || cfsetospeed(&tio, code) != 0) {
        s->last_errno = errno;
        return RSM_ERR_RANGE;
    }
    /* TCSADRAIN: bytes already queued leave at the old rate (hal.h). */
    if (tcsetattr(s->fd, TCSADRAIN, &tio) != 0) {
        s->last_errno = errno;
        return RSM_ERR_IO;
    }
    s->baud = baud;
    return RSM_OK;
}

static int fd_flush(void *ctx)
{
    rsm_posix_fd_link_t *s = (rsm_posix_fd_link_t *)ctx;
    if (s == NULL || s->fd < 0) {
        return RSM_ERR_INVAL;
    }
    if (!s->is_tty) {
        return RSM_OK;
    }
    if (tcflush(s->fd, TCIFLUSH) != 0) {
        s->last_errno = errno;
        return RSM_ERR_IO;
    }
    return RSM_OK;
}

/* ---- public ------------------------------------------------------------------------ */

static int finish_setup(rsm_posix_fd_link_t *s, uint32_t baud, unsigned flags)
{
    s->is_tty = isatty(s->fd) ? 1 : 0;
    if (!s->is_tty && (flags & RSM_POSIX_OPEN_REQUIRE_TTY) != 0u) {
        s->last_errno = ENOTTY;
        return RSM_ERR_INVAL;
    }
    if (s->is_tty) {
        return tty_setup(s, baud);
    }
    return RSM_OK;
}

int rsm_posix_fd_open(rsm_posix_fd_link_t *s, const char *path, uint32_t baud, unsigned flags)
{
    struct stat st;
    int oflags;
    int status;
    if (s == NULL) {
        return RSM_ERR_INVAL;
    }
    state_reset(s);
    if (path == NULL || path[0] == '\0') {
        return RSM_ERR_INVAL;
    }
    if (stat(path, &st) != 0) {
        s->last_errno = errno;
        return RSM_ERR_IO;
    }
    if (S_ISDIR(st.st_mode)) {
        s->last_errno = EISDIR;
        return RSM_ERR_INVAL;
    }
    if (S_ISREG(st.st_mode) || S_ISFIFO(st.st_mode)) {
        if ((flags & RSM_POSIX_OPEN_REQUIRE_TTY) != 0u) {
            s->last_errno = ENOTTY;
            return RSM_ERR_INVAL;
        }
        /* A replay source: never written, and a FIFO opened read-only sees
         * the end of stream when its writers close. */
        oflags = O_RDONLY;
    } else {
        oflags = ((flags & RSM_POSIX_OPEN_RDONLY) != 0u ? O_RDONLY : O_RDWR) | O_NOCTTY | O_NONBLOCK;
    }
    do {
        s->fd = open(path, oflags);
    } while (s->fd < 0 && errno == EINTR);
    if (s->fd < 0) {
        s->last_errno = errno;
        s->fd = -1;
        return RSM_ERR_IO;
    }
    s->owns_fd = 1;
    s->readable = 1;
    s->writable = (oflags & O_ACCMODE) == O_RDWR ? 1 : 0;
    status = finish_setup(s, baud, flags);
    if (status != RSM_OK) {
        const int kept = s->last_errno;
        (void)close(s->fd);
        state_reset(s);
        s->last_errno = kept;
    }
    return status;
}

int rsm_posix_fd_adopt(rsm_posix_fd_link_t *s, int fd, uint32_t baud, unsigned flags, int owns_fd)
{
    int fl;
    int status;
    if (s == NULL) {
        return RSM_ERR_INVAL;
    }
    state_reset(s);
    if (fd < 0) {
        return RSM_ERR_INVAL;
    }
    fl = fcntl(fd, F_GETFL);
    if (fl < 0) {
        s->last_errno = errno;
        return RSM_ERR_INVAL;
    }
    s->fd = fd;
    s->readable = (fl & O_ACCMODE) != O_WRONLY ? 1 : 0;
    s->writable = (fl & O_ACCMODE) != O_RDONLY && (flags & RSM_POSIX_OPEN_RDONLY) == 0u ? 1 : 0;
    status = finish_setup(s, baud, flags);
    if (status != RSM_OK) {
        const int kept = s->last_errno;
        state_reset(s);
        s->last_errno = kept;
        return status;
    }
    s->owns_fd = owns_fd ? 1 : 0;
    return RSM_OK;
}

int rsm_posix_fd_link(rsm_posix_fd_link_t *s, rsm_link_t *link)
{
    if (s == NULL || link == NULL) {
        return RSM_ERR_INVAL;
    }
    link->read = fd_read;
    link->write = fd_write;
    link->set_baud = fd_set_baud;
    link->flush = fd_flush;
    link->ctx = s;
    return RSM_OK;
}

int rsm_posix_fd_close(rsm_posix_fd_link_t *s)
{
    int status = RSM_OK;
    if (s == NULL) {
        return RSM_ERR_INVAL;
    }
    if (s->fd >= 0 && s->is_tty && s->saved_valid && !s->hangup) {
        /* Best effort: a vanished device has no settings to restore. */
        (void)tcsetattr(s->fd, TCSANOW, &s->saved_tio);
    }
    s->saved_valid = 0;
    if (s->fd >= 0 && s->owns_fd) {
        /* POSIX leaves the descriptor state unspecified after EINTR; Linux
         * has released it, so never retry (it could close a reused fd). */
        if (close(s->fd) != 0) {
            s->last_errno = errno;
            status = RSM_ERR_IO;
        }
    }
    s->fd = -1;
    s->owns_fd = 0;
    return status;
}
