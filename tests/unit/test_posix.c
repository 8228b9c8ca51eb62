/* Unit tests of the POSIX port (port/posix): the file-descriptor link over
 * pseudo-terminals, regular files and pipes, the automatic open and the
 * monotonic clock. Timing checks assert loose lower bounds only. */
#define _XOPEN_SOURCE 700 /* posix_openpt, grantpt, unlockpt, ptsname */

#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "rsm/hal.h"
#include "rsm/status.h"
#include "rsm_posix.h"
#include "unity.h"

static int master_fd = -1;
static char slave_path[128];
static char tmp_path[64];
static rsm_posix_fd_link_t st;
static rsm_link_t lnk;

/* Opens a pseudo-terminal pair; the slave is opened later by path, by the
 * code under test. */
static void open_pty(void)
{
    const char *name;
    master_fd = posix_openpt(O_RDWR | O_NOCTTY);
    TEST_ASSERT_TRUE(master_fd >= 0);
    TEST_ASSERT_EQUAL_INT(0, grantpt(master_fd));
    TEST_ASSERT_EQUAL_INT(0, unlockpt(master_fd));
    name = ptsname(master_fd);
    TEST_ASSERT_NOT_NULL(name);
    TEST_ASSERT_TRUE(strlen(name) < sizeof slave_path);
    strcpy(slave_path, name);
}

/* Creates a file in the working directory holding len bytes of data. */
static void make_file(const uint8_t *data, size_t len)
{
    int fd;
    strcpy(tmp_path, "test_posix_XXXXXX");
    fd = mkstemp(tmp_path);
    TEST_ASSERT_TRUE(fd >= 0);
    if (len > 0u) {
        TEST_ASSERT_EQUAL_INT((int)len, (int)write(fd, data, len));
    }
    TEST_ASSERT_EQUAL_INT(0, close(fd));
}

/* Writes all of data to the pty master (from the test's side). */
static void master_write(const uint8_t *data, size_t len)
{
    TEST_ASSERT_EQUAL_INT((int)len, (int)write(master_fd, data, len));
}

/* Reads exactly len bytes through the link, in as many calls as it takes. */
static void link_read_exact(uint8_t *out, size_t len)
{
    size_t got = 0;
    int tries = 0;
    while (got < len && tries < 100) {
        const int n = rsm_link_read(&lnk, out + got, len - got, 200000u);
        TEST_ASSERT_TRUE(n >= 0);
        got += (size_t)n;
        tries++;
    }
    TEST_ASSERT_EQUAL_size_t(len, got);
}

static void sleep_ms(long ms)
{
    struct timespec ts;
    ts.tv_sec = ms / 1000;
    ts.tv_nsec = (ms % 1000) * 1000000L;
    while (nanosleep(&ts, &ts) != 0 && errno == EINTR) {
    }
}

void setUp(void)
{
    master_fd = -1;
    slave_path[0] = '\0';
    tmp_path[0] = '\0';
    memset(&st, 0, sizeof st);
    st.fd = -1;
    memset(&lnk, 0, sizeof lnk);
}

void tearDown(void)
{
    (void)rsm_posix_fd_close(&st);
    if (master_fd >= 0) {
        (void)close(master_fd);
    }
    if (tmp_path[0] != '\0') {
        (void)unlink(tmp_path);
    }
}

/* ---- pseudo-terminals --------------------------------------------------------- */

void test_fd_open_should_pass_bytes_both_ways_over_a_pty(void)
{
    /* Binary bytes that a cooked terminal would mangle (CR, NL, ^C, ^S, DEL). */
    const uint8_t to_link[] = {0xFA, 0xFB, 0x0D, 0x0A, 0x03, 0x13, 0x11, 0x7F, 0x00, 0xFF};
    const uint8_t to_master[] = {0x02, 0x80, 0x0D, 0x00, 0x15, 0x06};
    uint8_t got[16];
    size_t have = 0;
    open_pty();
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_open(&st, slave_path, 38400u, 0u));
    TEST_ASSERT_EQUAL_INT(1, st.is_tty);
    TEST_ASSERT_EQUAL_UINT32(38400u, st.baud);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_link(&st, &lnk));

    master_write(to_link, sizeof to_link);
    link_read_exact(got, sizeof to_link);
    TEST_ASSERT_EQUAL_MEMORY(to_link, got, sizeof to_link);

    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_write_all(&lnk, to_master, sizeof to_master, NULL));
    while (have < sizeof to_master) {
        const ssize_t n = read(master_fd, got + have, sizeof to_master - have);
        TEST_ASSERT_TRUE(n > 0);
        have += (size_t)n;
    }
    TEST_ASSERT_EQUAL_MEMORY(to_master, got, sizeof to_master);
}

void test_fd_read_should_return_zero_after_about_the_timeout(void)
{
    uint8_t buf[4];
    uint64_t t0, t1;
    open_pty();
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_open(&st, slave_path, 0u, 0u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_link(&st, &lnk));
    t0 = rsm_posix_clock_now_us(NULL);
    TEST_ASSERT_EQUAL_INT(0, rsm_link_read(&lnk, buf, sizeof buf, 50000u));
    t1 = rsm_posix_clock_now_us(NULL);
    /* Loose lower bound only: never fail because a machine is slow. */
    TEST_ASSERT_GREATER_OR_EQUAL_UINT64(40000u, t1 - t0);
    /* A zero timeout polls and returns at once with nothing. */
    TEST_ASSERT_EQUAL_INT(0, rsm_link_read(&lnk, buf, sizeof buf, 0u));
}

void test_fd_read_should_return_buffered_bytes_with_a_zero_timeout(void)
{
    const uint8_t data[] = {1, 2, 3};
    uint8_t buf[8];
    int n = 0;
    int tries = 0;
    open_pty();
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_open(&st, slave_path, 0u, 0u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_link(&st, &lnk));
    master_write(data, sizeof data);
    /* The pty may need a moment to move the bytes across. */
    while (n == 0 && tries < 200) {
        n = rsm_link_read(&lnk, buf, sizeof buf, 0u);
        if (n == 0) {
            sleep_ms(5);
        }
        tries++;
    }
    TEST_ASSERT_TRUE(n > 0);
    TEST_ASSERT_EQUAL_UINT8(1, buf[0]);
}

void test_fd_set_baud_should_accept_standard_rates_on_a_pty(void)
{
    open_pty();
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_open(&st, slave_path, 9600u, 0u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_link(&st, &lnk));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_set_baud(&lnk, 19200u));
    TEST_ASSERT_EQUAL_UINT32(19200u, st.baud);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_set_baud(&lnk, 38400u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_set_baud(&lnk, 9600u));
    if (rsm_posix_baud_supported(500000u)) {
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_set_baud(&lnk, 500000u));
    }
    if (rsm_posix_baud_supported(115200u)) {
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_set_baud(&lnk, 115200u));
        TEST_ASSERT_EQUAL_UINT32(115200u, st.baud);
    }
}

void test_fd_set_baud_should_refuse_a_nonstandard_rate(void)
{
    rsm_posix_fd_link_t other;
    open_pty();
    TEST_ASSERT_EQUAL_INT(0, rsm_posix_baud_supported(12345u));
    TEST_ASSERT_EQUAL_INT(1, rsm_posix_baud_supported(9600u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_open(&st, slave_path, 9600u, 0u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_link(&st, &lnk));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_link_set_baud(&lnk, 12345u));
    TEST_ASSERT_EQUAL_UINT32(9600u, st.baud);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_link_set_baud(&lnk, 0u));
    /* The same rate refused at open time, descriptor released. */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_posix_fd_open(&other, slave_path, 12345u, 0u));
    TEST_ASSERT_EQUAL_INT(-1, other.fd);
}

void test_fd_flush_should_discard_pending_pty_input(void)
{
    const uint8_t junk[] = {9, 9, 9, 9};
    const uint8_t fresh[] = {7};
    uint8_t buf[8];
    open_pty();
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_open(&st, slave_path, 0u, 0u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_link(&st, &lnk));
    master_write(junk, sizeof junk);
    sleep_ms(20);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_flush(&lnk));
    master_write(fresh, sizeof fresh);
    TEST_ASSERT_EQUAL_INT(1, rsm_link_read(&lnk, buf, sizeof buf, 1000000u));
    TEST_ASSERT_EQUAL_UINT8(7, buf[0]);
}

void test_fd_read_should_report_io_error_when_the_pty_master_closes(void)
{
    uint8_t buf[8];
    uint64_t t0, t1;
    open_pty();
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_open(&st, slave_path, 0u, 0u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_link(&st, &lnk));
    TEST_ASSERT_EQUAL_INT(0, close(master_fd));
    master_fd = -1;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_IO, rsm_link_read(&lnk, buf, sizeof buf, 1000000u));
    TEST_ASSERT_EQUAL_INT(1, st.hangup);
    TEST_ASSERT_EQUAL_INT(0, st.eof);
    TEST_ASSERT_TRUE(st.last_errno != 0);
    /* Sticky and immediate: no wait, no spin on the dead descriptor. A read
     * that waited would take the whole minute; half of it is a bound no
     * loaded machine's stall comes near. */
    t0 = rsm_posix_clock_now_us(NULL);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_IO, rsm_link_read(&lnk, buf, sizeof buf, 60000000u));
    t1 = rsm_posix_clock_now_us(NULL);
    TEST_ASSERT_LESS_THAN_UINT64(30000000u, t1 - t0);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_IO, rsm_link_write_all(&lnk, buf, 1u, NULL));
}

/* ---- files and pipes ------------------------------------------------------------- */

void test_fd_read_should_report_eof_at_the_end_of_a_regular_file(void)
{
    const uint8_t data[] = {0xFA, 0xFB, 3, 0, 0, 0};
    uint8_t buf[64];
    make_file(data, sizeof data);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_open(&st, tmp_path, 9600u, 0u));
    TEST_ASSERT_EQUAL_INT(0, st.is_tty);
    TEST_ASSERT_EQUAL_INT(0, st.writable);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_link(&st, &lnk));
    TEST_ASSERT_EQUAL_INT((int)sizeof data, rsm_link_read(&lnk, buf, sizeof buf, 100000u));
    TEST_ASSERT_EQUAL_MEMORY(data, buf, sizeof data);
    TEST_ASSERT_EQUAL_INT(0, st.eof);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_IO, rsm_link_read(&lnk, buf, sizeof buf, 100000u));
    TEST_ASSERT_EQUAL_INT(1, st.eof);
    TEST_ASSERT_EQUAL_INT(0, st.hangup);
    TEST_ASSERT_EQUAL_INT(0, st.last_errno);
    TEST_ASSERT_EQUAL_UINT32(1u, st.eof_count);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_IO, rsm_link_read(&lnk, buf, sizeof buf, 100000u));
    TEST_ASSERT_EQUAL_UINT32(2u, st.eof_count);
}

void test_fd_link_should_treat_baud_and_flush_as_no_ops_on_a_file(void)
{
    const uint8_t data[] = {1};
    make_file(data, sizeof data);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_open(&st, tmp_path, 0u, 0u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_link(&st, &lnk));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_set_baud(&lnk, 12345u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_flush(&lnk));
    /* A replay file is opened read-only: writing is an I/O error. */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_IO, rsm_link_write_all(&lnk, data, 1u, NULL));
    TEST_ASSERT_EQUAL_INT(EBADF, st.last_errno);
}

void test_fd_adopt_should_read_a_pipe_until_its_writer_closes(void)
{
    int fds[2];
    const uint8_t data[] = {0x06, 0x02, 0x80};
    uint8_t buf[16];
    uint64_t t0, t1;
    TEST_ASSERT_EQUAL_INT(0, pipe(fds));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_adopt(&st, fds[0], 0u, 0u, 1));
    TEST_ASSERT_EQUAL_INT(0, st.is_tty);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_link(&st, &lnk));
    /* Nothing yet: a timeout, not an end. */
    t0 = rsm_posix_clock_now_us(NULL);
    TEST_ASSERT_EQUAL_INT(0, rsm_link_read(&lnk, buf, sizeof buf, 20000u));
    t1 = rsm_posix_clock_now_us(NULL);
    TEST_ASSERT_GREATER_OR_EQUAL_UINT64(15000u, t1 - t0);
    TEST_ASSERT_EQUAL_INT((int)sizeof data, (int)write(fds[1], data, sizeof data));
    TEST_ASSERT_EQUAL_INT(0, close(fds[1]));
    TEST_ASSERT_EQUAL_INT((int)sizeof data, rsm_link_read(&lnk, buf, sizeof buf, 1000000u));
    TEST_ASSERT_EQUAL_MEMORY(data, buf, sizeof data);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_IO, rsm_link_read(&lnk, buf, sizeof buf, 1000000u));
    TEST_ASSERT_EQUAL_INT(1, st.eof);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_close(&st));
    TEST_ASSERT_EQUAL_INT(-1, st.fd);
    /* The descriptor was owned, so it is closed now. */
    TEST_ASSERT_EQUAL_INT(-1, fcntl(fds[0], F_GETFD));
}

void test_fd_adopt_should_refuse_a_closed_descriptor(void)
{
    int fds[2];
    TEST_ASSERT_EQUAL_INT(0, pipe(fds));
    TEST_ASSERT_EQUAL_INT(0, close(fds[0]));
    TEST_ASSERT_EQUAL_INT(0, close(fds[1]));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_posix_fd_adopt(&st, fds[0], 0u, 0u, 0));
    TEST_ASSERT_EQUAL_INT(EBADF, st.last_errno);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_posix_fd_adopt(&st, -1, 0u, 0u, 0));
}

void test_fd_close_should_restore_the_terminal_settings_of_an_adopted_tty(void)
{
    struct termios before, after;
    int slave;
    open_pty();
    slave = open(slave_path, O_RDWR | O_NOCTTY);
    TEST_ASSERT_TRUE(slave >= 0);
    TEST_ASSERT_EQUAL_INT(0, tcgetattr(slave, &before));
    TEST_ASSERT_TRUE((before.c_lflag & ICANON) != 0u); /* a fresh pty is cooked */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_adopt(&st, slave, 0u, 0u, 0));
    TEST_ASSERT_EQUAL_INT(1, st.is_tty);
    TEST_ASSERT_EQUAL_INT(0, tcgetattr(slave, &after));
    TEST_ASSERT_TRUE((after.c_lflag & ICANON) == 0u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_close(&st));
    TEST_ASSERT_EQUAL_INT(0, tcgetattr(slave, &after)); /* not owned: still open */
    TEST_ASSERT_TRUE((after.c_lflag & ICANON) != 0u);
    TEST_ASSERT_EQUAL_INT(0, close(slave));
}

void test_fd_open_should_read_a_fifo_until_its_writer_closes(void)
{
    const uint8_t data[] = {0xFA, 0xFB, 0x03};
    uint8_t buf[16];
    size_t got = 0;
    pid_t child;
    int wstatus = 0;
    int n;
    strcpy(tmp_path, "test_posix_fifo");
    (void)unlink(tmp_path);
    TEST_ASSERT_EQUAL_INT(0, mkfifo(tmp_path, 0600));
    child = fork();
    TEST_ASSERT_TRUE(child >= 0);
    if (child == 0) {
        /* Writer: opening blocks until the reader opens, then exits. */
        const int fd = open(tmp_path, O_WRONLY);
        if (fd < 0 || write(fd, data, sizeof data) != (ssize_t)sizeof data) {
            _exit(1);
        }
        _exit(close(fd) == 0 ? 0 : 1);
    }
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_open(&st, tmp_path, 9600u, 0u));
    TEST_ASSERT_EQUAL_INT(0, st.is_tty);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_fd_link(&st, &lnk));
    while ((n = rsm_link_read(&lnk, buf + got, sizeof buf - got, 2000000u)) > 0) {
        got += (size_t)n;
    }
    TEST_ASSERT_EQUAL_INT(RSM_ERR_IO, n);
    TEST_ASSERT_EQUAL_INT(1, st.eof);
    TEST_ASSERT_EQUAL_size_t(sizeof data, got);
    TEST_ASSERT_EQUAL_MEMORY(data, buf, sizeof data);
    TEST_ASSERT_EQUAL_INT(child, waitpid(child, &wstatus, 0));
    TEST_ASSERT_TRUE(WIFEXITED(wstatus));
    TEST_ASSERT_EQUAL_INT(0, WEXITSTATUS(wstatus));
}

/* ---- errors at open time ----------------------------------------------------------- */

void test_fd_open_should_report_a_missing_path_with_its_errno(void)
{
    TEST_ASSERT_EQUAL_INT(RSM_ERR_IO, rsm_posix_fd_open(&st, "no-such-dir-rsm/none", 9600u, 0u));
    TEST_ASSERT_EQUAL_INT(ENOENT, st.last_errno);
    TEST_ASSERT_EQUAL_INT(-1, st.fd);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_posix_fd_open(&st, "", 9600u, 0u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_posix_fd_open(&st, NULL, 9600u, 0u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_posix_fd_open(NULL, "x", 9600u, 0u));
}

void test_fd_open_should_refuse_a_directory_and_a_non_tty_when_a_tty_is_required(void)
{
    const uint8_t data[] = {1};
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_posix_fd_open(&st, ".", 0u, 0u));
    TEST_ASSERT_EQUAL_INT(EISDIR, st.last_errno);
    make_file(data, sizeof data);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL,
                          rsm_posix_fd_open(&st, tmp_path, 9600u, RSM_POSIX_OPEN_REQUIRE_TTY));
    TEST_ASSERT_EQUAL_INT(ENOTTY, st.last_errno);
    TEST_ASSERT_EQUAL_INT(-1, st.fd);
}

void test_link_open_auto_should_pick_the_fd_backend_for_ptys_and_files(void)
{
    rsm_posix_auto_link_t a;
    const uint8_t data[] = {0xAB, 0xCD};
    uint8_t buf[8];
    open_pty();
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_link_open_auto(&a, slave_path, 9600u, 0u, &lnk));
    TEST_ASSERT_EQUAL_INT(RSM_POSIX_LINK_FD, a.kind);
    TEST_ASSERT_EQUAL_INT(1, a.fd.is_tty);
    master_write(data, sizeof data);
    TEST_ASSERT_TRUE(rsm_link_read(&lnk, buf, sizeof buf, 1000000u) > 0);
    TEST_ASSERT_EQUAL_UINT8(0xAB, buf[0]);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_link_close(&a));
    TEST_ASSERT_EQUAL_INT(RSM_POSIX_LINK_NONE, a.kind);

    make_file(data, sizeof data);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_link_open_auto(&a, tmp_path, 0u, 0u, &lnk));
    TEST_ASSERT_EQUAL_INT(RSM_POSIX_LINK_FD, a.kind);
    TEST_ASSERT_EQUAL_INT(2, rsm_link_read(&lnk, buf, sizeof buf, 100000u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_IO, rsm_link_read(&lnk, buf, sizeof buf, 100000u));
    TEST_ASSERT_EQUAL_INT(1, rsm_posix_auto_eof(&a));
    TEST_ASSERT_EQUAL_INT(0, rsm_posix_auto_errno(&a));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_link_close(&a));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_link_close(&a));
}

void test_link_open_auto_should_report_a_missing_path_with_its_errno(void)
{
    rsm_posix_auto_link_t a;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_IO, rsm_posix_link_open_auto(&a, "no-such-dir-rsm/tty", 9600u, 0u, &lnk));
    TEST_ASSERT_EQUAL_INT(ENOENT, rsm_posix_auto_errno(&a));
    TEST_ASSERT_EQUAL_INT(RSM_POSIX_LINK_NONE, a.kind);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_posix_link_open_auto(&a, "", 9600u, 0u, &lnk));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_posix_link_open_auto(&a, "x", 9600u, 0u, NULL));
}

void test_serial_open_should_refuse_bad_arguments(void)
{
    rsm_posix_serial_link_t s;
    rsm_link_t l;
#ifdef RSM_HAVE_LIBSERIALPORT
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_posix_serial_open(&s, "", 9600u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_posix_serial_open(&s, "x", 0u));
    TEST_ASSERT_TRUE(rsm_posix_serial_open(&s, "no-such-dir-rsm/tty", 9600u) < 0);
    TEST_ASSERT_NULL(s.port);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_serial_link(&s, &l));
#else
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOSYS, rsm_posix_serial_open(&s, "x", 9600u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOSYS, rsm_posix_serial_link(&s, &l));
#endif
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_serial_close(&s));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_posix_serial_close(NULL));
}

/* ---- clock ------------------------------------------------------------------------------ */

void test_clock_now_us_should_be_monotonic_and_advance(void)
{
    rsm_clock_t clk;
    uint64_t a = 0, b = 0, prev;
    int i;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_posix_clock_init(&clk));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_posix_clock_init(NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_clock_now_us(&clk, &a));
    TEST_ASSERT_TRUE(a > 0u);
    prev = a;
    for (i = 0; i < 1000; ++i) {
        const uint64_t t = rsm_posix_clock_now_us(NULL);
        TEST_ASSERT_GREATER_OR_EQUAL_UINT64(prev, t);
        prev = t;
    }
    sleep_ms(20);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_clock_now_us(&clk, &b));
    TEST_ASSERT_GREATER_OR_EQUAL_UINT64(a + 15000u, b);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_fd_open_should_pass_bytes_both_ways_over_a_pty);
    RUN_TEST(test_fd_read_should_return_zero_after_about_the_timeout);
    RUN_TEST(test_fd_read_should_return_buffered_bytes_with_a_zero_timeout);
    RUN_TEST(test_fd_set_baud_should_accept_standard_rates_on_a_pty);
    RUN_TEST(test_fd_set_baud_should_refuse_a_nonstandard_rate);
    RUN_TEST(test_fd_flush_should_discard_pending_pty_input);
    RUN_TEST(test_fd_read_should_report_io_error_when_the_pty_master_closes);
    RUN_TEST(test_fd_read_should_report_eof_at_the_end_of_a_regular_file);
    RUN_TEST(test_fd_link_should_treat_baud_and_flush_as_no_ops_on_a_file);
    RUN_TEST(test_fd_adopt_should_read_a_pipe_until_its_writer_closes);
    RUN_TEST(test_fd_adopt_should_refuse_a_closed_descriptor);
    RUN_TEST(test_fd_close_should_restore_the_terminal_settings_of_an_adopted_tty);
    RUN_TEST(test_fd_open_should_read_a_fifo_until_its_writer_closes);
    RUN_TEST(test_fd_open_should_report_a_missing_path_with_its_errno);
    RUN_TEST(test_fd_open_should_refuse_a_directory_and_a_non_tty_when_a_tty_is_required);
    RUN_TEST(test_link_open_auto_should_pick_the_fd_backend_for_ptys_and_files);
    RUN_TEST(test_link_open_auto_should_report_a_missing_path_with_its_errno);
    RUN_TEST(test_serial_open_should_refuse_bad_arguments);
    RUN_TEST(test_clock_now_us_should_be_monotonic_and_advance);
    return UNITY_END();
}
