/* Links against an installed rsm and checks a few calls give real answers. */
#include <stdio.h>
#include <string.h>

#include "rsm/rsm.h"

int main(void)
{
    if (strcmp(rsm_strerror(RSM_ERR_CHECKSUM), "checksum mismatch") != 0) {
        fprintf(stderr, "unexpected strerror text\n");
        return 1;
    }
    printf("rsm consumer ok (map %d cells a side)\n", RSM_MAP_SIZE);
    return 0;
}
