/* The writers' spill file (bsdf_write_spill.h). */
#include "writer/bsdf_write_spill.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Bytes buffered before a write (1 MiB: few system calls, small beside the
 * tables a writer holds). */
#define LL_SPILL_BUFFER ((size_t)1 << 20)

void ll_spill_init(ll_spill *sp)
{
    memset(sp, 0, sizeof *sp);
    sp->fd = -1;
}

ll_status ll_spill_open(ll_spill *sp, const char *path, const char *fn)
{
    const char *slash = strrchr(path, '/');
    size_t dir = slash ? (size_t)(slash - path) + 1 : 0, name = strlen(path) - dir;
    char *temp = ll_malloc(dir + name + 16);
    int err;
    sp->path = path;
    sp->buffer = ll_malloc(LL_SPILL_BUFFER);
    if (!temp || !sp->buffer) {
        ll_free(temp);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", fn);
    }
    /* ".NAME.spill.XXXXXX" beside NAME: hidden, and on the output's own
     * file system, whose free space the output needs anyway. */
    memcpy(temp, path, dir);
    temp[dir] = '.';
    memcpy(temp + dir + 1, path + dir, name);
    memcpy(temp + dir + 1 + name, ".spill.XXXXXX", 14);
    sp->fd = mkstemp(temp);
    err = errno;
    if (sp->fd >= 0)
        (void)unlink(temp);
    ll_free(temp);
    if (sp->fd < 0)
        return ll_fail(LL_ERROR_IO, "%s: \"%s\": cannot create a spill file beside it: %s", fn,
                       path, strerror(err));
    return LL_OK;
}

void ll_spill_open_memory(ll_spill *sp, const char *path)
{
    ll_spill_init(sp);
    sp->path = path;
}

/* In memory: room for `more` bytes after the buffered ones, the buffer
 * doubled as it fills (so the copies cost as much as the bytes once). */
static ll_status memory_reserve(ll_spill *sp, size_t more, const char *fn)
{
    size_t need, cap = sp->capacity ? sp->capacity : (size_t)1 << 16;
    unsigned char *grown;
    if (!ll_size_add(sp->buffered, more, &need))
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", fn);
    if (need <= sp->capacity)
        return LL_OK;
    while (cap < need)
        if (!ll_size_mul(cap, 2, &cap))
            cap = need;
    grown = ll_realloc(sp->buffer, cap);
    if (!grown)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", fn);
    sp->buffer = grown;
    sp->capacity = cap;
    return LL_OK;
}

unsigned long long ll_spill_tell(const ll_spill *sp)
{
    return sp->flushed + sp->buffered;
}

ll_status ll_spill_flush(ll_spill *sp, const char *fn)
{
    size_t done = 0;
    if (sp->fd < 0)
        return LL_OK; /* in memory: nothing to write out */
    while (done < sp->buffered) {
        ssize_t k = write(sp->fd, sp->buffer + done, sp->buffered - done);
        if (k < 0 && errno == EINTR)
            continue;
        if (k <= 0)
            return ll_fail(LL_ERROR_IO, "%s: \"%s\": writing the spill file beside it: %s", fn,
                           sp->path, strerror(k < 0 ? errno : EIO));
        done += (size_t)k;
    }
    sp->flushed += sp->buffered;
    sp->buffered = 0;
    return LL_OK;
}

ll_status ll_spill_put(ll_spill *sp, const void *data, size_t size, const char *fn)
{
    const unsigned char *p = data;
    if (sp->fd < 0) {
        ll_status s = memory_reserve(sp, size, fn);
        if (s == LL_OK && size > 0)
            memcpy(sp->buffer + sp->buffered, data, size);
        if (s == LL_OK)
            sp->buffered += size;
        return s;
    }
    while (size > 0) {
        size_t room = LL_SPILL_BUFFER - sp->buffered, n = size < room ? size : room;
        memcpy(sp->buffer + sp->buffered, p, n);
        sp->buffered += n;
        p += n;
        size -= n;
        if (sp->buffered == LL_SPILL_BUFFER) {
            ll_status s = ll_spill_flush(sp, fn);
            if (s != LL_OK)
                return s;
        }
    }
    return LL_OK;
}

ll_status ll_spill_read(const ll_spill *sp, unsigned long long at, void *data, size_t size,
                        const char *fn)
{
    unsigned char *p = data;
    if (sp->fd < 0) {
        if (at > sp->buffered || size > sp->buffered - at)
            return ll_fail(LL_ERROR_IO, "%s: \"%s\": reading the spill beyond its end", fn,
                           sp->path);
        if (size > 0)
            memcpy(data, sp->buffer + at, size);
        return LL_OK;
    }
    while (size > 0) {
        ssize_t k = pread(sp->fd, p, size, (off_t)at);
        if (k < 0 && errno == EINTR)
            continue;
        if (k <= 0)
            return ll_fail(LL_ERROR_IO, "%s: \"%s\": reading the spill file beside it: %s", fn,
                           sp->path, k < 0 ? strerror(errno) : "it is shorter");
        p += k;
        at += (unsigned long long)k;
        size -= (size_t)k;
    }
    return LL_OK;
}

void ll_spill_close(ll_spill *sp)
{
    if (sp->fd >= 0)
        close(sp->fd);
    ll_free(sp->buffer);
    ll_spill_init(sp);
}
