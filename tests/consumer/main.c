/* Links against an installed rsm and checks a few calls give real answers.
 * Built twice: as is, and with EXPECT_MISMATCH and a capacity the library
 * was not built with, where starting a localizer, laying out a scan and
 * starting an aligner must fail cleanly (RSM_ERR_CONFIG) instead of writing
 * past the application's objects. */
#include <stdio.h>
#include <string.h>

#include "rsm/rsm.h"

/* Whether this program runs under AddressSanitizer (gcc and clang spell it
 * differently); the install check requires "on" in the sanitizer build. */
#if defined(__SANITIZE_ADDRESS__)
#define CONSUMER_ASAN "on"
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define CONSUMER_ASAN "on"
#endif
#endif
#ifndef CONSUMER_ASAN
#define CONSUMER_ASAN "off"
#endif

#ifndef EXPECT_MISMATCH
#define EXPECT_MISMATCH 0
#endif

static rsm_localizer_t loc;
static rsm_localizer_config_t cfg;
static rsm_scan_t scan;
static rsm_sync_config_t scfg;
static rsm_sync_t aligner;

int main(void)
{
    const rsm_pose_t x0 = {0.0f, 0.0f, 0.0f};
    const int want = EXPECT_MISMATCH ? RSM_ERR_CONFIG : RSM_OK;
    int rc;
    if (strcmp(rsm_strerror(RSM_ERR_CHECKSUM), "checksum mismatch") != 0) {
        fprintf(stderr, "unexpected strerror text\n");
        return 1;
    }
    cfg = rsm_localizer_config_default();
    rc = rsm_localizer_init(&loc, &cfg, &x0, NULL);
    if (rc != want) {
        fprintf(stderr, "rsm_localizer_init: %d (%s), expected %d\n", rc, rsm_strerror(rc), want);
        return 1;
    }
    rc = rsm_scan_set_uniform(&scan, 181u, -1.5707964f, 0.017453292f);
    if (rc != want) {
        fprintf(stderr, "rsm_scan_set_uniform: %d (%s), expected %d\n", rc, rsm_strerror(rc), want);
        return 1;
    }
    scfg = rsm_sync_config_default();
    rc = rsm_sync_init(&aligner, &loc, &scfg, NULL, NULL);
    if (rc != want) {
        fprintf(stderr, "rsm_sync_init: %d (%s), expected %d\n", rc, rsm_strerror(rc), want);
        return 1;
    }
    printf("rsm consumer ok (%d beams, localizer %lu bytes: %s; AddressSanitizer %s)\n", RSM_MAX_BEAMS,
           (unsigned long)sizeof loc, rsm_strerror(rc), CONSUMER_ASAN);
    return 0;
}
