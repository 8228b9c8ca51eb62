/* The map-in-flash example on the host (mapflash.h): the region an array,
 * two boots in a row with the state cleared between them as a reset
 * clears the target's .bss; the output the target's two boots must match. */
#include <stdio.h>
#include <string.h>

#include "mapflash.h"

static void host_write(void *ctx, const char *s, size_t n)
{
    (void)fwrite(s, 1, n, (FILE *)ctx);
}

int main(void)
{
    static uint8_t bytes[RSM_MAPFLASH_REGION];
    static rsm_mapflash_t state;
    rsm_mapflash_region_t flash;
    rsm_replay_io_t io;
    rsm_mapflash_result_t res;
    int boot;
    io.write = host_write;
    io.ctx = stdout;
    io.clock_fn = NULL;
    io.clock_ctx = NULL;
    flash.bytes = bytes;
    flash.size = (uint32_t)sizeof bytes;
    memset(bytes, 0xFF, sizeof bytes); /* a new part comes erased */
    for (boot = 1; boot <= 2; ++boot) {
        memset(&state, 0, sizeof state);
        printf("rsm mapflash on host, boot %d\n", boot);
        res = rsm_mapflash_boot(&state, &flash, &io);
        if (res != (boot == 1 ? RSM_MAPFLASH_RESET : RSM_MAPFLASH_DONE)) {
            fprintf(stderr, "rsm-mapflash-host: boot %d ended with %d\n", boot, (int)res);
            return 1;
        }
    }
    return fflush(stdout) == 0 ? 0 : 1;
}
