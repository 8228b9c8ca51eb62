/* The replay on the host: the trajectory that the target's must equal. */
#include <stdio.h>

#include "replay.h"
#include "rsm/status.h"

static void host_write(void *ctx, const char *s, size_t n)
{
    (void)fwrite(s, 1, n, (FILE *)ctx);
}

int main(void)
{
    static rsm_replay_t replay;
    rsm_replay_io_t io;
    int rc;
    io.write = host_write;
    io.ctx = stdout;
    io.clock_fn = NULL;
    io.clock_ctx = NULL;
    rc = rsm_replay_run(&replay, &io);
    if (rc != RSM_OK) {
        fprintf(stderr, "rsm-replay: %s\n", rsm_strerror(rc));
        return 1;
    }
    return fflush(stdout) == 0 ? 0 : 1;
}
