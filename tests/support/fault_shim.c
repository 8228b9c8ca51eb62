/* A preload library for the end-to-end tests: reading one file fails with
 * EIO after a given number of bytes, as a dying disk or a pulled USB stick
 * does. Environment:
 *   RSM_FAULT_PATH   the file (as the program names it to open/fopen)
 *   RSM_FAULT_AFTER  bytes delivered before every read of it fails
 * Files opened with fopen get a stdio stream over the failing reads
 * (glibc's stdio calls its internal read, which a preload cannot replace);
 * files opened with open (zlib's gzopen does) have their read replaced.
 * With RSM_FAULT_REPORT_OPEN set, a stream of that file still open when the
 * program exits is reported on stderr ("fault_shim: ... never closed").
 * Nothing else is touched. Test support only: never linked into a tool. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <unistd.h>

#define SHIM_MAX_FDS 16

typedef int (*open_fn)(const char *, int, ...);
typedef ssize_t (*read_fn)(int, void *, size_t);
typedef FILE *(*fopen_fn)(const char *, const char *);

static int faulty_fd[SHIM_MAX_FDS];
static int streams_open; /* fopen'ed streams of the file not yet closed */
static unsigned long long delivered[SHIM_MAX_FDS];
static int nfaulty;

/* dlsym returns an object pointer; copying it is the portable conversion. */
static void *next_symbol(const char *name)
{
    return dlsym(RTLD_NEXT, name);
}

static int is_fault_path(const char *path)
{
    const char *want = getenv("RSM_FAULT_PATH");
    return path != NULL && want != NULL && strcmp(path, want) == 0;
}

static unsigned long long fault_after(void)
{
    const char *v = getenv("RSM_FAULT_AFTER");
    return v != NULL ? strtoull(v, NULL, 10) : 0ull;
}

static int slot_of(int fd)
{
    int i;
    for (i = 0; i < nfaulty; ++i) {
        if (faulty_fd[i] == fd) {
            return i;
        }
    }
    return -1;
}

/* Each open of the file starts its count afresh (close is not wrapped, so
 * a reused descriptor number is found here again). */
static void track(int fd)
{
    const int slot = slot_of(fd);
    if (slot >= 0) {
        delivered[slot] = 0ull;
        return;
    }
    if (fd >= 0 && nfaulty < SHIM_MAX_FDS) {
        faulty_fd[nfaulty] = fd;
        delivered[nfaulty] = 0ull;
        nfaulty++;
    }
}

static void untrack(int slot)
{
    faulty_fd[slot] = faulty_fd[nfaulty - 1];
    delivered[slot] = delivered[nfaulty - 1];
    nfaulty--;
}

static ssize_t real_read(int fd, void *buf, size_t n)
{
    read_fn f;
    void *p = next_symbol("read");
    memcpy(&f, &p, sizeof f);
    return f(fd, buf, n);
}

/* Reads of a tracked fd: the first RSM_FAULT_AFTER bytes, then EIO. */
static ssize_t limited_read(int slot, int fd, void *buf, size_t n)
{
    const unsigned long long limit = fault_after();
    ssize_t got;
    if (delivered[slot] >= limit) {
        errno = EIO;
        return -1;
    }
    if (n > limit - delivered[slot]) {
        n = (size_t)(limit - delivered[slot]);
    }
    got = real_read(fd, buf, n);
    if (got > 0) {
        delivered[slot] += (unsigned long long)got;
    }
    return got;
}

ssize_t read(int fd, void *buf, size_t n)
{
    const int slot = slot_of(fd);
    return slot >= 0 ? limited_read(slot, fd, buf, n) : real_read(fd, buf, n);
}

static int open_common(const char *sym, const char *path, int flags, mode_t mode)
{
    open_fn f;
    void *p = next_symbol(sym);
    int fd;
    memcpy(&f, &p, sizeof f);
    fd = f(path, flags, mode);
    if (is_fault_path(path)) {
        track(fd);
    } else if (fd >= 0 && slot_of(fd) >= 0) {
        untrack(slot_of(fd)); /* the number of a closed faulty descriptor, reused */
    }
    return fd;
}

/* The mode argument is there only with O_CREAT. */
#define SHIM_OPEN(name)                                         \
    int name(const char *path, int flags, ...)                  \
    {                                                           \
        mode_t mode = 0;                                        \
        if (flags & O_CREAT) {                                  \
            va_list ap;                                         \
            va_start(ap, flags);                                \
            mode = (mode_t)va_arg(ap, int);                     \
            va_end(ap);                                         \
        }                                                       \
        return open_common(#name, path, flags, mode);           \
    }
SHIM_OPEN(open)
SHIM_OPEN(open64)

static ssize_t cookie_read(void *cookie, char *buf, size_t n)
{
    const int fd = (int)(intptr_t)cookie;
    const int slot = slot_of(fd);
    return slot >= 0 ? limited_read(slot, fd, buf, n) : real_read(fd, buf, n);
}

static int cookie_close(void *cookie)
{
    const int fd = (int)(intptr_t)cookie;
    const int slot = slot_of(fd);
    streams_open--;
    if (slot >= 0) {
        untrack(slot);
    }
    return close(fd);
}

static FILE *fopen_common(const char *sym, const char *path, const char *mode)
{
    if (is_fault_path(path) && mode[0] == 'r' && strchr(mode, '+') == NULL) {
        cookie_io_functions_t io;
        int fd;
        memset(&io, 0, sizeof io);
        io.read = cookie_read;
        io.close = cookie_close;
        fd = open_common("open", path, O_RDONLY, 0);
        if (fd < 0) {
            return NULL;
        }
        streams_open++;
        return fopencookie((void *)(intptr_t)fd, mode, io);
    }
    {
        fopen_fn f;
        void *p = next_symbol(sym);
        memcpy(&f, &p, sizeof f);
        return f(path, mode);
    }
}

FILE *fopen(const char *path, const char *mode)
{
    return fopen_common("fopen", path, mode);
}

FILE *fopen64(const char *path, const char *mode)
{
    return fopen_common("fopen64", path, mode);
}

__attribute__((destructor)) static void report_open_streams(void)
{
    if (streams_open > 0 && getenv("RSM_FAULT_REPORT_OPEN") != NULL) {
        fprintf(stderr, "fault_shim: %d stream(s) of %s never closed\n", streams_open, getenv("RSM_FAULT_PATH"));
    }
}
