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
    static uint32_t words[RSM_MAPFLASH_REGION / 4u]; /* words: the index is read as such */
    static rsm_mapflash_t state;
    rsm_mapflash_region_t flash;
    rsm_replay_io_t io;
    rsm_mapflash_result_t res;
    int boot;
    io.write = host_write;
    io.ctx = stdout;
    io.clock_fn = NULL;
    io.clock_ctx = NULL;
    flash.bytes = (uint8_t *)words;
    flash.size = (uint32_t)sizeof words;
    memset(words, 0xFF, sizeof words); /* a new part comes erased */
    for (boot = 1; boot <= 2; ++boot) {
        memset(&state, 0, sizeof state);
        printf("%s on host, boot %d\n", RSM_MAPFLASH_NAME, boot);
        res = rsm_mapflash_boot(&state, &flash, &io);
        if (res != (boot == 1 ? RSM_MAPFLASH_RESET : RSM_MAPFLASH_DONE)) {
            fprintf(stderr, "%s host: boot %d ended with %d\n", RSM_MAPFLASH_NAME, boot, (int)res);
            return 1;
        }
    }
    return fflush(stdout) == 0 ? 0 : 1;
}
