/*
 * Non-blocking open of regular input files (regular_file.h).
 */
#include "support/regular_file.h"

#include <errno.h>
#include <fcntl.h>
#include <string.h>
#include <unistd.h>

const char *ll_file_kind(mode_t mode)
{
    if (S_ISREG(mode))
        return "regular file";
    if (S_ISDIR(mode))
        return "directory";
    if (S_ISFIFO(mode))
        return "FIFO (named pipe)";
    if (S_ISCHR(mode))
        return "character device";
    if (S_ISBLK(mode))
        return "block device";
    if (S_ISSOCK(mode))
        return "socket";
    return "special file";
}

ll_status ll_open_regular(const char *path, const char *what, int *fd, struct stat *st)
{
    const char *kind = NULL; /* set when the file is not a regular one */
    int flags, err = 0;
    *fd = open(path, O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
    if (*fd < 0 || fstat(*fd, st) != 0)
        err = errno;
    else if (!S_ISREG(st->st_mode) || st->st_size < 0)
        kind = ll_file_kind(st->st_mode);
    /* A regular file never blocks, but reads of it must not see EAGAIN
     * from a flag left set (some file systems, e.g. FUSE, honour it). */
    else if ((flags = fcntl(*fd, F_GETFL)) < 0 || fcntl(*fd, F_SETFL, flags & ~O_NONBLOCK) != 0)
        err = errno;
    if (!err && !kind)
        return LL_OK;
    if (*fd >= 0)
        close(*fd);
    *fd = -1;
    if (kind)
        return ll_fail(LL_ERROR_IO, "%s \"%s\" is a %s, not a regular file", what, path, kind);
    return ll_fail(LL_ERROR_IO, "%s \"%s\": cannot open: %s", what, path, strerror(err));
}

FILE *ll_fopen_regular(const char *path, const char *what)
{
    struct stat st;
    FILE *f;
    int fd;
    if (ll_open_regular(path, what, &fd, &st) != LL_OK)
        return NULL;
    f = fdopen(fd, "rb");
    if (!f) {
        int err = errno;
        close(fd);
        ll_fail(LL_ERROR_IO, "%s \"%s\": cannot open: %s", what, path, strerror(err));
    }
    return f;
}
