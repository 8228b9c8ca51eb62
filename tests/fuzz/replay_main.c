/* Runs a fuzz target's LLVMFuzzerTestOneInput over every file of its seed
 * corpus, without libFuzzer: the corpus becomes a regression test that any
 * compiler builds, and the sanitizer build runs it under ASan and UBSan
 * (ctest label fuzz). A broken invariant stops the run (CHECK traps).
 *
 *   fuzz_<name>_replay DIR|FILE ...
 */
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static uint8_t input[1u << 20];

static int run_file(const char *path)
{
    FILE *fp = fopen(path, "rb");
    size_t n;
    if (fp == NULL) {
        perror(path);
        return -1;
    }
    n = fread(input, 1u, sizeof input, fp);
    if (ferror(fp) || !feof(fp)) {
        fprintf(stderr, "%s: unreadable or over %zu bytes\n", path, sizeof input);
        fclose(fp);
        return -1;
    }
    fclose(fp);
    (void)LLVMFuzzerTestOneInput(input, n);
    return 1;
}

static int run_path(const char *path)
{
    struct stat st;
    DIR *d;
    struct dirent *e;
    int total = 0;
    if (stat(path, &st) != 0) {
        perror(path);
        return -1;
    }
    if (!S_ISDIR(st.st_mode)) {
        return run_file(path);
    }
    d = opendir(path);
    if (d == NULL) {
        perror(path);
        return -1;
    }
    while ((e = readdir(d)) != NULL) {
        char child[4096];
        int r;
        if (e->d_name[0] == '.') {
            continue;
        }
        if (snprintf(child, sizeof child, "%s/%s", path, e->d_name) >= (int)sizeof child) {
            closedir(d);
            return -1;
        }
        r = run_path(child);
        if (r < 0) {
            closedir(d);
            return -1;
        }
        total += r;
    }
    closedir(d);
    return total;
}

int main(int argc, char **argv)
{
    int i, total = 0;
    for (i = 1; i < argc; ++i) {
        const int r = run_path(argv[i]);
        if (r < 0) {
            return 2;
        }
        total += r;
    }
    printf("%d inputs, every invariant held\n", total);
    /* No input at all is a broken set-up, not a pass. */
    return total > 0 ? 0 : 1;
}
