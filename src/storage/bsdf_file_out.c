/*
 * Atomic little-endian file output for the .bsdf writer (see
 * bsdf_file_out.h): write everything to "<dir>/.<name>.XXXXXX", fsync,
 * rename. A reader never sees a half-written file, and a failed write
 * (full disk, file size limit, I/O error) leaves the old file in place.
 */
#include "storage/bsdf_file_out.h"
#include "storage/bsdf_format.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define LL_BSDF_OUT_BUFFER 65536

struct ll_bsdf_out {
    int fd;
    int error;                /* first errno, 0 while all is well */
    const char *fn;
    char *path;               /* the target */
    char *temp;               /* the temporary file */
    size_t used;
    unsigned char buffer[LL_BSDF_OUT_BUFFER];
};

static void out_free(ll_bsdf_out *o)
{
    ll_free(o->path);
    ll_free(o->temp);
    ll_free(o);
}

/* The directory part of path with a trailing slash ("" for none). */
static size_t directory_length(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? (size_t)(slash - path) + 1 : 0;
}

ll_status ll_bsdf_out_begin(const char *path, const char *fn, ll_bsdf_out **out)
{
    ll_bsdf_out *o;
    size_t len = strlen(path), dir = directory_length(path), temp_size;
    int err;

    *out = NULL;
    if (dir == len)
        return ll_fail(LL_ERROR_IO, "%s: \"%s\" names a directory, not a file", fn, path);
    o = ll_calloc(1, sizeof *o);
    /* "<dir>/.<name>.XXXXXX": hidden, in the same directory (so rename is
     * atomic: same file system). */
    temp_size = len + 1 + 7 + 1;
    if (!o || !(o->path = ll_malloc(len + 1)) || !(o->temp = ll_malloc(temp_size))) {
        if (o)
            out_free(o);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", fn);
    }
    memcpy(o->path, path, len + 1);
    memcpy(o->temp, path, dir);
    snprintf(o->temp + dir, temp_size - dir, ".%s.XXXXXX", path + dir);
    o->fn = fn;
    o->fd = mkstemp(o->temp);
    if (o->fd < 0) {
        err = errno;
        ll_fail(LL_ERROR_IO, "%s: \"%s\": cannot create a temporary file beside it: %s", fn,
                path, strerror(err));
        out_free(o);
        return LL_ERROR_IO;
    }
    /* mkstemp makes the file private (0600); a written .bsdf is an
     * ordinary readable file. */
    if (fchmod(o->fd, 0644) != 0)
        o->error = errno;
    *out = o;
    return LL_OK;
}

static void flush_buffer(ll_bsdf_out *o)
{
    size_t done = 0;
    while (!o->error && done < o->used) {
        ssize_t w = write(o->fd, o->buffer + done, o->used - done);
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0) {
            o->error = w < 0 ? errno : EIO;
            break;
        }
        done += (size_t)w;
    }
    o->used = 0;
}

void ll_bsdf_out_bytes(ll_bsdf_out *o, const void *data, size_t size)
{
    const unsigned char *p = data;
    while (size > 0 && !o->error) {
        size_t room = LL_BSDF_OUT_BUFFER - o->used, n = size < room ? size : room;
        memcpy(o->buffer + o->used, p, n);
        o->used += n;
        p += n;
        size -= n;
        if (o->used == LL_BSDF_OUT_BUFFER)
            flush_buffer(o);
    }
}

void ll_bsdf_out_u32(ll_bsdf_out *o, uint32_t v)
{
    unsigned char bytes[4];
    ll_le_put_u32(bytes, v);
    ll_bsdf_out_bytes(o, bytes, 4);
}

void ll_bsdf_out_f32(ll_bsdf_out *o, float v)
{
    unsigned char bytes[4];
    ll_le_put_f32(bytes, v);
    ll_bsdf_out_bytes(o, bytes, 4);
}

void ll_bsdf_out_abort(ll_bsdf_out *o)
{
    if (!o)
        return;
    if (o->fd >= 0)
        close(o->fd);
    unlink(o->temp);
    out_free(o);
}

/* Make the rename itself durable (best effort: not every file system lets
 * a directory be opened and synced). */
static void sync_directory(const ll_bsdf_out *o)
{
    size_t dir = directory_length(o->path);
    char *name = ll_malloc(dir + 2);
    int fd;
    if (!name)
        return;
    if (dir) {
        memcpy(name, o->path, dir);
        name[dir] = '\0';
    } else {
        strcpy(name, ".");
    }
    fd = open(name, O_RDONLY);
    if (fd >= 0) {
        (void)fsync(fd);
        close(fd);
    }
    ll_free(name);
}

ll_status ll_bsdf_out_commit(ll_bsdf_out *o)
{
    int err;
    flush_buffer(o);
    if (!o->error && fsync(o->fd) != 0)
        o->error = errno;
    if (close(o->fd) != 0 && !o->error)
        o->error = errno;
    o->fd = -1;
    if (!o->error && rename(o->temp, o->path) != 0)
        o->error = errno;
    err = o->error;
    if (err) {
        ll_fail(LL_ERROR_IO, "%s: \"%s\": writing failed: %s", o->fn, o->path, strerror(err));
        ll_bsdf_out_abort(o);
        return LL_ERROR_IO;
    }
    sync_directory(o);
    out_free(o);
    return LL_OK;
}
