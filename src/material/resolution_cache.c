/*
 * The resolution search's choices remembered between processes: one small
 * file per word, in a directory the caller names (ll_build_options.
 * cache_dir; ll_material_cache_dir gives the user's cache directory).
 *
 * The key is the word as its search sees it (name, choice, the values the
 * search reads, written exactly as hexadecimal floats; where its search
 * started, if not at its own first guess; a measured table's path, size
 * and modification time), the tolerance, mu_min, the
 * library's version and the search's revision (LL_SEARCH_REVISION): a new
 * version or search may choose differently, so it searches again. The file's name is a hash of the key; the file holds the key
 * itself (a hash collision is a miss, not a wrong answer), the answer and
 * a checksum of both, so a truncated or damaged entry is ignored and
 * rewritten, never trusted. Writers make a temporary file in the directory
 * and rename it over the entry: concurrent builds each write a whole entry
 * and the last rename wins, which is right, since all write the same
 * answer. Nothing here fails a build: a cache that cannot be read or
 * written is a cache miss.
 */
/* mkstemp and st_mtim are POSIX 2008, strtoull C99. */
#include "material/material.h"
#include "material/word_table.h"
#include "search/probe.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define CACHE_MAGIC "layerlab resolution cache 1"
/* An entry is a few hundred bytes; anything longer is not one. */
#define ENTRY_MAX 4096
#define KEY_MAX 1024

/* FNV-1a, 64 bits: the file name and the checksum (detects damage, not
 * an adversary: the directory is the user's own). */
static unsigned long long fnv1a(const char *text, size_t len)
{
    unsigned long long h = 14695981039346656037ULL;
    size_t k;
    for (k = 0; k < len; ++k) {
        h ^= (unsigned char)text[k];
        h *= 1099511628211ULL;
    }
    return h;
}

/* The key, or 0 when it does not fit (then the word is not cached). */
static int make_key(const ll_word_params *p, const size_t *start, double tolerance,
                    double mu_min, char *key, size_t size)
{
    unsigned reads = p->desc->resolution_reads;
    size_t used, k;
    int len = snprintf(key, size, "layerlab %s search %d; %s choice %d; tolerance %a; mu_min %a;",
                       ll_version_string(), LL_SEARCH_REVISION, p->desc->name, p->choice,
                       tolerance, mu_min);
    if (len < 0 || (size_t)len >= size)
        return 0;
    used = (size_t)len;
    for (k = 0; k < LL_WORD_MAX_VALUES; ++k) {
        if (reads != 0 && !(reads >> k & 1u))
            continue;
        len = snprintf(key + used, size - used, " v%zu %a", k, p->v[k]);
        if (len < 0 || (size_t)len >= size - used)
            return 0;
        used += (size_t)len;
    }
    if (start && (start[0] || start[1])) {
        /* Where the search started (another channel's answer): the answer
         * may depend on it, and a build must choose the same whatever
         * other materials left in the cache. */
        len = snprintf(key + used, size - used, " start %zu %zu", start[0], start[1]);
        if (len < 0 || (size_t)len >= size - used)
            return 0;
        used += (size_t)len;
    }
    if (p->file) {
        /* The table's identity as the search reads it: its absolute path
         * (two folders' "gold.binary" are two tables) and, so that a
         * replaced file is searched again, its size and time. */
        struct stat st;
        char *path = ll_realpath(p->file);
        if (!path || stat(path, &st) != 0) {
            ll_free(path);
            return 0;
        }
        len = snprintf(key + used, size - used, " file %s size %lld mtime %lld.%09ld", path,
                       (long long)st.st_size, (long long)st.st_mtim.tv_sec,
                       (long)st.st_mtim.tv_nsec);
        ll_free(path);
        if (len < 0 || (size_t)len >= size - used)
            return 0;
        used += (size_t)len;
    }
    /* (The key is one line of the entry.) */
    return strchr(key, '\n') == NULL;
}

/* dir/res-HASH, or 0 when it does not fit. */
static int entry_path(const char *dir, const char *key, char *path, size_t size)
{
    int len = snprintf(path, size, "%s/res-%016llx", dir, fnv1a(key, strlen(key)));
    return len > 0 && (size_t)len < size;
}

/* The entry's text: the magic, the key, the answer, then the checksum of
 * the lines before it. */
static int format_entry(const char *key, size_t n, size_t m, double error, char *text,
                        size_t size)
{
    int len = snprintf(text, size, "%s\n%s\n%zu %zu %a\n", CACHE_MAGIC, key, n, m, error);
    int sum;
    if (len < 0 || (size_t)len >= size)
        return -1;
    sum = snprintf(text + len, size - (size_t)len, "%016llx\n", fnv1a(text, (size_t)len));
    if (sum < 0 || (size_t)sum >= size - (size_t)len)
        return -1;
    return len + sum;
}

int ll_resolution_cache_get(const char *dir, const ll_word_params *p, const size_t *start,
                            double tolerance, double mu_min, size_t *n, size_t *m,
                            double *error)
{
    char key[KEY_MAX], path[KEY_MAX + 64], text[ENTRY_MAX + 1], expect[ENTRY_MAX];
    unsigned long long vn, vm;
    double e;
    char *at, *end;
    size_t got;
    int len;
    FILE *f;
    if (!dir || !*dir || !make_key(p, start, tolerance, mu_min, key, sizeof key) ||
        !entry_path(dir, key, path, sizeof path))
        return 0;
    f = fopen(path, "rb");
    if (!f)
        return 0;
    got = fread(text, 1, ENTRY_MAX, f);
    fclose(f);
    text[got] = '\0';
    /* Whole-entry check: the text must be exactly what this key and the
     * answer it holds format to, checksum included. */
    at = strchr(text, '\n');
    if (!at || strncmp(text, CACHE_MAGIC "\n", sizeof CACHE_MAGIC) != 0)
        return 0;
    at = strchr(at + 1, '\n');
    if (!at)
        return 0;
    ++at;
    errno = 0;
    vn = strtoull(at, &end, 10);
    if (end == at || *end != ' ' || errno)
        return 0;
    at = end + 1;
    vm = strtoull(at, &end, 10);
    if (end == at || *end != ' ' || errno)
        return 0;
    at = end + 1;
    e = strtod(at, &end);
    if (end == at || *end != '\n')
        return 0;
    if (vn < LL_MATERIAL_MIN_NODES || vn % 2 || vn > LL_MATERIAL_MAX_RESOLUTION || vm < 1 ||
        vm > LL_MATERIAL_MAX_RESOLUTION || !(e >= 0.0))
        return 0;
    len = format_entry(key, (size_t)vn, (size_t)vm, e, expect, sizeof expect);
    if (len < 0 || (size_t)len != got || memcmp(expect, text, got) != 0)
        return 0;
    *n = (size_t)vn;
    *m = (size_t)vm;
    *error = e;
    return 1;
}

/* mkdir -p with the user's umask; 0 when dir is not a directory after. */
static int make_dirs(const char *dir)
{
    char path[KEY_MAX];
    size_t k, len = strlen(dir);
    struct stat st;
    if (len == 0 || len >= sizeof path)
        return 0;
    memcpy(path, dir, len + 1);
    for (k = 1; k <= len; ++k)
        if (path[k] == '/' || path[k] == '\0') {
            char c = path[k];
            path[k] = '\0';
            if (mkdir(path, 0777) != 0 && errno != EEXIST)
                return 0;
            path[k] = c;
        }
    return stat(dir, &st) == 0 && S_ISDIR(st.st_mode);
}

void ll_resolution_cache_put(const char *dir, const ll_word_params *p, const size_t *start,
                             double tolerance, double mu_min, size_t n, size_t m, double error)
{
    char key[KEY_MAX], path[KEY_MAX + 64], temp[KEY_MAX + 80], text[ENTRY_MAX];
    int len, fd, ok;
    if (!dir || !*dir || !make_key(p, start, tolerance, mu_min, key, sizeof key) ||
        !entry_path(dir, key, path, sizeof path) || !make_dirs(dir))
        return;
    len = format_entry(key, n, m, error, text, sizeof text);
    if (len < 0 || snprintf(temp, sizeof temp, "%s.tmp-XXXXXX", path) >= (int)sizeof temp)
        return;
    fd = mkstemp(temp);
    if (fd < 0)
        return;
    ok = write(fd, text, (size_t)len) == (ssize_t)len;
    if (close(fd) != 0)
        ok = 0;
    /* The rename replaces the entry whole: a reader sees the old entry or
     * the new one, never a part. */
    if (!ok || rename(temp, path) != 0)
        unlink(temp);
}

ll_status ll_material_cache_dir(char *buffer, size_t size)
{
    static const char fn[] = "ll_material_cache_dir";
    const char *env = getenv("LAYERLAB_CACHE_DIR"), *xdg = getenv("XDG_CACHE_HOME");
    const char *home = getenv("HOME");
    int len;
    if (!buffer || size == 0)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: buffer is NULL or empty", fn);
    /* XDG: a relative XDG_CACHE_HOME is invalid and ignored. */
    if (env && *env)
        len = snprintf(buffer, size, "%s", env);
    else if (xdg && xdg[0] == '/')
        len = snprintf(buffer, size, "%s/layerlab", xdg);
    else if (home && *home)
        len = snprintf(buffer, size, "%s/.cache/layerlab", home);
    else
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: no cache directory: none of LAYERLAB_CACHE_DIR, XDG_CACHE_HOME "
                       "and HOME is set",
                       fn);
    if (len < 0 || (size_t)len >= size) {
        buffer[0] = '\0';
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: the cache directory's name needs %d bytes, more than the %zu given",
                       fn, len + 1, size);
    }
    return LL_OK;
}
