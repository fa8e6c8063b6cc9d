/*
 * llplot — atomic output files: everything is written to a temporary file
 * in the destination's directory and renamed over the destination only
 * when complete, so a failed or interrupted run never leaves a partial
 * picture under the requested name.
 */
#include "llplot.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

int llplot_output_begin(const char *path, llplot_output *out)
{
    const char *slash = strrchr(path, '/');
    size_t dir_len = slash ? (size_t)(slash - path) + 1 : 0;
    const char *base = path + dir_len;
    size_t len = strlen(path);
    mode_t mask;
    int fd;
    out->final_path = NULL;
    out->temp_path = NULL;
    if (base[0] == '\0')
        return llplot_fail(LLPLOT_EXIT_INPUT, "%s: the output path names a directory", path);
    /* "<dir>/.<base>.tmp-XXXXXX": hidden, and in the same file system as
     * the destination so that rename() is atomic. */
    out->temp_path = malloc(len + 16);
    out->final_path = malloc(len + 1);
    if (!out->temp_path || !out->final_path) {
        llplot_output_abort(out);
        return llplot_fail(LLPLOT_EXIT_IO, "out of memory");
    }
    memcpy(out->final_path, path, len + 1);
    memcpy(out->temp_path, path, dir_len);
    sprintf(out->temp_path + dir_len, ".%s.tmp-XXXXXX", base);
    fd = mkstemp(out->temp_path);
    if (fd < 0) {
        int err = errno;
        free(out->temp_path);
        out->temp_path = NULL;
        llplot_output_abort(out);
        return llplot_fail(LLPLOT_EXIT_IO, "%s: cannot create the output file: %s", path,
                           strerror(err));
    }
    /* mkstemp makes the file private (0600); give it the permissions a
     * plain fopen() would have. */
    mask = umask(0);
    umask(mask);
    if (fchmod(fd, 0666 & ~mask) != 0 || close(fd) != 0) {
        int err = errno;
        llplot_output_abort(out);
        return llplot_fail(LLPLOT_EXIT_IO, "%s: cannot create the output file: %s", path,
                           strerror(err));
    }
    return LLPLOT_EXIT_OK;
}

int llplot_output_commit(llplot_output *out)
{
    if (rename(out->temp_path, out->final_path) != 0) {
        int err = errno;
        llplot_fail(LLPLOT_EXIT_IO, "%s: cannot write: %s", out->final_path, strerror(err));
        llplot_output_abort(out);
        return LLPLOT_EXIT_IO;
    }
    free(out->temp_path);
    free(out->final_path);
    out->temp_path = out->final_path = NULL;
    return LLPLOT_EXIT_OK;
}

void llplot_output_abort(llplot_output *out)
{
    if (out->temp_path)
        unlink(out->temp_path);
    free(out->temp_path);
    free(out->final_path);
    out->temp_path = out->final_path = NULL;
}
