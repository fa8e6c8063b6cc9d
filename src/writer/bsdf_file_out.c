/*
 * Atomic little-endian file output for the .bsdf writer (see
 * bsdf_file_out.h): write everything to a hidden temporary file in the
 * target's directory, fsync, rename over the target. A reader never sees a
 * half-written file, and a failed write (full disk, file size limit, I/O
 * error) leaves the old file in place.
 *
 * What the target's directory sees, as users expect of `cp` or a compiler:
 *  - the temporary is "<dir>/.<name>.XXXXXX.tmp" (hidden; XXXXXX random),
 *    with <name> cut to fit the file system's NAME_MAX when the target's
 *    own name is close to it (the target keeps its name);
 *  - temporaries of this target left by a writer that was killed are
 *    removed by the next writer of the same target: a file is stale when it
 *    matches the exact pattern above, is a regular file owned by this user
 *    and has not been modified for LL_BSDF_STALE_SECONDS (a live writer
 *    writes continuously, so it is never that old);
 *  - the new file's mode is that of the target it replaces, or 0666 minus
 *    the umask for a new file;
 *  - a target that is a symbolic link is written through: the file the link
 *    points to (followed to the end of the chain) is replaced atomically in
 *    its own directory, and the link stays.
 */
#include "writer/bsdf_file_out.h"
#include "reader/bsdf_format.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#define LL_BSDF_OUT_BUFFER 65536
/* 15 minutes without a write: no live writer pauses that long. */
#define LL_BSDF_STALE_SECONDS (15 * 60)
/* Symbolic links followed at most (the kernel's own limit is 40). */
#define LL_BSDF_MAX_LINKS 40
#define LL_BSDF_TEMP_RANDOM 6
#define LL_BSDF_TEMP_SUFFIX ".tmp"
/* ".", the name, ".", XXXXXX, ".tmp" */
#define LL_BSDF_TEMP_EXTRA (1 + 1 + LL_BSDF_TEMP_RANDOM + 4)

struct ll_bsdf_out {
    int fd;
    int error;                /* first errno, 0 while all is well */
    const char *fn;
    char *path;               /* the target as given (for messages) */
    char *real;               /* the file replaced: path, or where its links lead */
    char *temp;               /* the temporary file */
    size_t used;
    unsigned char buffer[LL_BSDF_OUT_BUFFER];
};

static void out_free(ll_bsdf_out *o)
{
    ll_free(o->path);
    ll_free(o->real);
    ll_free(o->temp);
    ll_free(o);
}

static char *copy_string(const char *s, size_t len)
{
    char *c = ll_malloc(len + 1);
    if (c) {
        memcpy(c, s, len);
        c[len] = '\0';
    }
    return c;
}

/* The directory part of path with a trailing slash ("" for none). */
static size_t directory_length(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? (size_t)(slash - path) + 1 : 0;
}

/* The file that writing to path replaces: path itself, or the end of its
 * chain of symbolic links (which need not exist yet). *real is malloc'ed;
 * 0 with errno set on failure (ELOOP for a cycle). */
static int resolve_links(const char *path, char **real)
{
    char *cur = copy_string(path, strlen(path));
    int hops;
    for (hops = 0; cur; ++hops) {
        struct stat st;
        char *target, *joined;
        ssize_t len;
        size_t dir, size;
        if (lstat(cur, &st) != 0 || !S_ISLNK(st.st_mode)) {
            *real = cur; /* not a link (or absent: created there) */
            return 1;
        }
        if (hops == LL_BSDF_MAX_LINKS) {
            errno = ELOOP;
            break;
        }
        /* st_size is the link's length (0 on some pseudo file systems). */
        size = st.st_size > 0 ? (size_t)st.st_size + 1 : PATH_MAX;
        target = ll_malloc(size);
        if (!target) {
            errno = ENOMEM; /* (the allocator's failure sets no errno) */
            break;
        }
        len = readlink(cur, target, size);
        if (len < 0 || (size_t)len >= size) {
            if (len >= 0)
                errno = ENAMETOOLONG;
            ll_free(target);
            break;
        }
        target[len] = '\0';
        /* A relative link is relative to the link's own directory. */
        dir = target[0] == '/' ? 0 : directory_length(cur);
        joined = ll_malloc(dir + (size_t)len + 1);
        if (joined) {
            memcpy(joined, cur, dir);
            memcpy(joined + dir, target, (size_t)len + 1);
        }
        ll_free(target);
        ll_free(cur);
        cur = joined;
    }
    if (!cur)
        errno = ENOMEM; /* the first copy or a joined path could not be made */
    ll_free(cur);
    return 0;
}

/* How many bytes of the target's name the temporary's name keeps: all of
 * them unless that would pass the directory's NAME_MAX. */
static size_t kept_name_length(const char *real, size_t dir, size_t name_len)
{
    long name_max;
    char *dir_name = dir ? copy_string(real, dir) : copy_string(".", 1);
    errno = 0;
    name_max = dir_name ? pathconf(dir_name, _PC_NAME_MAX) : -1;
    ll_free(dir_name);
    if (name_max <= 0)
        name_max = NAME_MAX;
    if (name_max <= LL_BSDF_TEMP_EXTRA + 1)
        return 1;
    return name_len + LL_BSDF_TEMP_EXTRA <= (size_t)name_max ? name_len
                                                             : (size_t)name_max - LL_BSDF_TEMP_EXTRA;
}

/* Is entry (a name in the target's directory) one of this target's
 * temporaries: "." + prefix + "." + 6 letters or digits + ".tmp"? */
static int is_our_temporary(const char *entry, const char *prefix, size_t prefix_len)
{
    size_t k, len = strlen(entry);
    if (len != prefix_len + LL_BSDF_TEMP_EXTRA || entry[0] != '.' ||
        memcmp(entry + 1, prefix, prefix_len) != 0 || entry[1 + prefix_len] != '.' ||
        strcmp(entry + len - 4, LL_BSDF_TEMP_SUFFIX) != 0)
        return 0;
    for (k = 0; k < LL_BSDF_TEMP_RANDOM; ++k) {
        char c = entry[2 + prefix_len + k];
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9')))
            return 0;
    }
    return 1;
}

/* Remove this target's stale temporaries (best effort: a directory that
 * cannot be listed is left alone). temp holds "<dir>/.<prefix>." already. */
static void remove_stale(const char *temp, size_t dir, size_t prefix_len)
{
    char *dir_name = dir ? copy_string(temp, dir) : copy_string(".", 1);
    char *path = ll_malloc(dir + prefix_len + LL_BSDF_TEMP_EXTRA + 1);
    time_t now = time(NULL);
    DIR *d = dir_name ? opendir(dir_name) : NULL;
    struct dirent *e;
    while (d && path && (e = readdir(d)) != NULL) {
        struct stat st;
        if (!is_our_temporary(e->d_name, temp + dir + 1, prefix_len))
            continue;
        memcpy(path, temp, dir);
        strcpy(path + dir, e->d_name);
        if (lstat(path, &st) == 0 && S_ISREG(st.st_mode) && st.st_uid == geteuid() &&
            now - st.st_mtime >= LL_BSDF_STALE_SECONDS)
            (void)unlink(path);
    }
    if (d)
        closedir(d);
    ll_free(path);
    ll_free(dir_name);
}

/* Create the temporary: XXXXXX from the clock, the process and the attempt
 * (no shared state), O_EXCL so that an existing name is never reused. */
static int create_temporary(char *temp, size_t at, mode_t mode)
{
    static const char digits[] =
        "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789";
    struct timespec ts;
    unsigned long long x;
    int attempt, k, fd = -1;
    clock_gettime(CLOCK_REALTIME, &ts);
    x = (unsigned long long)ts.tv_nsec * 0x9E3779B97F4A7C15ull ^
        (unsigned long long)ts.tv_sec << 20 ^ (unsigned long long)getpid() << 40 ^
        (unsigned long long)(uintptr_t)temp;
    for (attempt = 0; attempt < 100; ++attempt) {
        unsigned long long r;
        x += 0x9E3779B97F4A7C15ull;
        r = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
        r = (r ^ (r >> 27)) * 0x94D049BB133111EBull;
        r ^= r >> 31;
        for (k = 0; k < LL_BSDF_TEMP_RANDOM; ++k, r /= 62)
            temp[at + (size_t)k] = digits[r % 62];
        fd = open(temp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOCTTY, mode);
        if (fd >= 0 || errno != EEXIST)
            break;
    }
    return fd;
}

ll_status ll_bsdf_out_begin(const char *path, const char *fn, ll_bsdf_out **out)
{
    ll_bsdf_out *o = NULL;
    size_t len = strlen(path), dir, name_len, kept;
    struct stat st;
    mode_t mode = 0666; /* minus the umask, applied by open */
    int err, keep_mode = 0;
    ll_status s = LL_ERROR_OUT_OF_MEMORY;

    *out = NULL;
    if (len == 0 || directory_length(path) == len)
        return ll_fail(LL_ERROR_IO, "%s: \"%s\" names a directory, not a file", fn, path);
    o = ll_calloc(1, sizeof *o);
    if (!o || !(o->path = copy_string(path, len)))
        goto fail_memory;
    o->fd = -1;
    o->fn = fn;
    if (!resolve_links(path, &o->real)) {
        err = errno;
        if (err == ENOMEM)
            goto fail_memory;
        s = ll_fail(LL_ERROR_IO, "%s: \"%s\": cannot follow its symbolic links: %s", fn, path,
                    strerror(err));
        goto fail;
    }
    dir = directory_length(o->real);
    name_len = strlen(o->real) - dir;
    if (name_len == 0) {
        s = ll_fail(LL_ERROR_IO, "%s: \"%s\" leads to a directory, not a file", fn, path);
        goto fail;
    }
    /* An existing target keeps its permission bits (not its owner: only
     * root could); a directory or other non-file is not replaced. */
    if (stat(o->real, &st) == 0) {
        if (!S_ISREG(st.st_mode)) {
            s = ll_fail(LL_ERROR_IO, "%s: \"%s\" is a %s, not a regular file; not replaced", fn,
                        path, S_ISDIR(st.st_mode) ? "directory" : "special file");
            goto fail;
        }
        mode = st.st_mode & 07777;
        keep_mode = 1;
    }
    kept = kept_name_length(o->real, dir, name_len);
    o->temp = ll_malloc(dir + kept + LL_BSDF_TEMP_EXTRA + 1);
    if (!o->temp)
        goto fail_memory;
    memcpy(o->temp, o->real, dir);
    o->temp[dir] = '.';
    memcpy(o->temp + dir + 1, o->real + dir, kept);
    o->temp[dir + 1 + kept] = '.';
    memcpy(o->temp + dir + 2 + kept + LL_BSDF_TEMP_RANDOM, LL_BSDF_TEMP_SUFFIX, 5);
    remove_stale(o->temp, dir, kept);
    o->fd = create_temporary(o->temp, dir + 2 + kept, keep_mode ? 0600 : mode);
    if (o->fd < 0) {
        err = errno;
        s = ll_fail(LL_ERROR_IO, "%s: \"%s\": cannot create a temporary file beside it: %s", fn,
                    path, strerror(err));
        goto fail;
    }
    /* The umask does not apply to an existing target's own mode. */
    if (keep_mode && fchmod(o->fd, mode) != 0)
        o->error = errno;
    *out = o;
    return LL_OK;
fail_memory:
    s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", fn);
fail:
    if (o)
        out_free(o);
    return s;
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
    size_t dir = directory_length(o->real);
    char *name = dir ? copy_string(o->real, dir) : copy_string(".", 1);
    int fd = name ? open(name, O_RDONLY | O_CLOEXEC) : -1;
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
    if (!o->error && rename(o->temp, o->real) != 0)
        o->error = errno;
    err = o->error;
    if (err) {
        /* The message names the target the caller asked for (and where its
         * links lead), never the temporary, which is gone. */
        if (strcmp(o->path, o->real) != 0)
            ll_fail(LL_ERROR_IO, "%s: \"%s\" (-> \"%s\"): writing failed: %s", o->fn, o->path,
                    o->real, strerror(err));
        else
            ll_fail(LL_ERROR_IO, "%s: \"%s\": writing failed: %s", o->fn, o->path,
                    strerror(err));
        ll_bsdf_out_abort(o);
        return LL_ERROR_IO;
    }
    sync_directory(o);
    out_free(o);
    return LL_OK;
}
