/*
 * Overflow-checked size arithmetic, and the one allocator of the library:
 * every allocation in src/ comes through here (tests/alloc_check.sh keeps it
 * so), which lets a program supply its own allocator (ll_set_allocator) and
 * the tests fail any chosen allocation.
 *
 * The caller's allocator (ll_common.h) replaces malloc, realloc and free
 * for every block; calloc becomes alloc and a memset. It is a process-wide
 * setting that ll_common.h tells the caller to make before the library
 * allocates, so it is read without synchronisation.
 *
 * Failure injection (tests only; the functions are hidden, not in any public
 * header): ll_alloc_fail_after(k) arms a counter of allocations shared by
 * all threads, and the k-th allocation after it returns NULL. The counter is
 * global and atomic rather than per thread because the parallel loops
 * allocate in OpenMP worker threads, and a per-thread count would never see
 * those; the k-th allocation is then one deterministic call when the test
 * runs with ll_set_thread_count(1) (every item of ll_parallel_for on one
 * thread, in index order). While armed, the hook also counts the blocks
 * allocated minus the blocks freed, so a test sees a leak without a leak
 * checker. Unarmed, each allocation costs one relaxed atomic load of the
 * flag. The hook and the caller's allocator are the only mutable globals of
 * the library besides the thread-local error message; the hook is written
 * only by tests.
 */
#define _XOPEN_SOURCE 700 /* realpath (ll_realpath) */
#define _DEFAULT_SOURCE 1  /* madvise, MADV_HUGEPAGE (ll_malloc_large) */
#include "support/support.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#if defined(__linux__)
#  include <sys/mman.h>
#endif

int ll_size_mul(size_t a, size_t b, size_t *out)
{
    if (a != 0 && b > SIZE_MAX / a)
        return 0;
    *out = a * b;
    return 1;
}

int ll_size_add(size_t a, size_t b, size_t *out)
{
    if (b > SIZE_MAX - a)
        return 0;
    *out = a + b;
    return 1;
}

/* ------------------------------------------------------ failure injection */

#if defined(__GNUC__)
#  define LOAD(x) __atomic_load_n(&(x), __ATOMIC_RELAXED)
#  define STORE(x, v) __atomic_store_n(&(x), (v), __ATOMIC_SEQ_CST)
#  define FETCH_ADD(x, v) __atomic_fetch_add(&(x), (v), __ATOMIC_RELAXED)
#else
/* Without atomics the hook is only exact single-threaded, as the tests run. */
#  define LOAD(x) (x)
#  define STORE(x, v) ((x) = (v))
#  define FETCH_ADD(x, v) (((x) += (v)) - (v))
#endif

static struct {
    int armed;          /* read by every allocation: relaxed load only */
    size_t fail_at;     /* 1-based index of the allocation to fail; 0 = none */
    size_t count;       /* allocations since arming */
    long long live;     /* blocks allocated minus blocks freed since arming */
} hook;

void ll_alloc_fail_after(size_t k)
{
    STORE(hook.armed, 0);
    STORE(hook.fail_at, k);
    STORE(hook.count, 0);
    STORE(hook.live, 0);
    STORE(hook.armed, 1);
}

void ll_alloc_hook_off(void)
{
    STORE(hook.armed, 0);
}

size_t ll_alloc_count(void)
{
    return LOAD(hook.count);
}

long long ll_alloc_live(void)
{
    return LOAD(hook.live);
}

/* 1 when this allocation is to fail; counts it. */
static int injected_failure(void)
{
    size_t index;
    if (!LOAD(hook.armed))
        return 0;
    index = FETCH_ADD(hook.count, 1) + 1;
    return index == LOAD(hook.fail_at);
}

static void note_block(long long delta)
{
    if (LOAD(hook.armed))
        FETCH_ADD(hook.live, delta);
}

/* ------------------------------------------------------- the allocator */

/* The caller's allocator (ll_set_allocator); all NULL: the C library's. */
static ll_allocator user_allocator;

ll_status ll_set_allocator(const ll_allocator *allocator)
{
    ll_allocator a = LL_ALLOCATOR_INIT;
    ll_status s;
    if (!allocator) {
        memset(&user_allocator, 0, sizeof user_allocator);
        return LL_OK;
    }
    s = ll_struct_read(&a, sizeof a, allocator, "ll_set_allocator", "ll_allocator");
    if (s != LL_OK)
        return s;
    if (!a.alloc || !a.realloc || !a.free)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_set_allocator: alloc, realloc and free must all be given");
    user_allocator = a;
    return LL_OK;
}

/* The three primitives, through the caller's allocator when one is set.
 * bytes is never 0 here. */
static void *raw_alloc(size_t bytes)
{
    if (user_allocator.alloc)
        return user_allocator.alloc(user_allocator.user, bytes);
    return malloc(bytes);
}

static void *raw_realloc(void *block, size_t bytes)
{
    if (!block)
        return raw_alloc(bytes);
    if (user_allocator.realloc)
        return user_allocator.realloc(user_allocator.user, block, bytes);
    return realloc(block, bytes);
}

static void raw_free(void *block)
{
    if (user_allocator.free)
        user_allocator.free(user_allocator.user, block);
    else
        free(block);
}

void *ll_malloc(size_t bytes)
{
    void *p;
    if (injected_failure())
        return NULL;
    p = raw_alloc(bytes ? bytes : 1);
    if (p)
        note_block(1);
    return p;
}

/* Transparent huge pages (Linux, when the system offers them on request):
 * the alignment of ll_malloc_large's blocks and the unit they are marked
 * in. */
#define LL_HUGE_PAGE ((size_t)2 << 20)

void *ll_malloc_large(size_t bytes)
{
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    void *p = NULL;
    /* Only the C library's allocator: a caller's gives blocks of its own
     * making, and a block from posix_memalign is one that free (the default
     * ll_free) takes back. */
    if (user_allocator.alloc || bytes < LL_HUGE_PAGE)
        return ll_malloc(bytes);
    if (injected_failure())
        return NULL;
    if (posix_memalign(&p, LL_HUGE_PAGE, bytes) != 0)
        return NULL;
    /* The whole huge pages of the block only, so that none holds memory
     * the block does not use; marked before the first touch, so that they
     * are made huge as they are faulted in. Refused (no THP, or "never"),
     * the block keeps ordinary pages. */
    (void)madvise(p, bytes - bytes % LL_HUGE_PAGE, MADV_HUGEPAGE);
    note_block(1);
    return p;
#else
    return ll_malloc(bytes);
#endif
}

void *ll_calloc(size_t count, size_t size)
{
    size_t bytes;
    void *p;
    if (!ll_size_mul(count, size, &bytes))
        return NULL;
    if (injected_failure())
        return NULL;
    if (!bytes)
        bytes = 1;
    if (user_allocator.alloc) {
        p = user_allocator.alloc(user_allocator.user, bytes);
        if (p)
            memset(p, 0, bytes);
    } else {
        p = calloc(bytes, 1);
    }
    if (p)
        note_block(1);
    return p;
}

void *ll_realloc(void *block, size_t bytes)
{
    void *p;
    if (injected_failure())
        return NULL;
    p = raw_realloc(block, bytes ? bytes : 1);
    if (p && !block)
        note_block(1);
    return p;
}

void ll_free(void *block)
{
    if (block) {
        note_block(-1);
        raw_free(block);
    }
}

void *ll_alloc_array(size_t count, size_t size)
{
    size_t bytes;
    if (!ll_size_mul(count, size, &bytes))
        return NULL;
    return ll_malloc(bytes);
}

void *ll_calloc_array(size_t count, size_t size)
{
    return ll_calloc(count, size);
}

void *ll_realloc_array(void *block, size_t count, size_t size)
{
    size_t bytes;
    if (!ll_size_mul(count, size, &bytes))
        return NULL;
    return ll_realloc(block, bytes);
}

void *ll_grow_array(void *block, size_t *capacity, size_t first, size_t size)
{
    size_t count = first;
    void *grown;
    if (*capacity && !ll_size_mul(*capacity, 2, &count))
        return NULL;
    grown = ll_realloc_array(block, count, size);
    if (grown)
        *capacity = count;
    return grown;
}

char *ll_strdup(const char *s)
{
    size_t len = strlen(s);
    char *copy = ll_malloc(len + 1);
    if (copy)
        memcpy(copy, s, len + 1);
    return copy;
}

char *ll_realpath(const char *path)
{
    /* realpath allocates with the C library's malloc: copy the answer into
     * a block of ours so that every block of the library is one kind. */
    char *resolved = realpath(path, NULL), *copy;
    if (!resolved)
        return NULL;
    copy = ll_strdup(resolved);
    free(resolved);
    return copy;
}

long ll_getline(char **line, size_t *capacity, FILE *f)
{
    size_t len = 0;
    int c;
    if (!*line || *capacity == 0) {
        char *fresh = ll_realloc(*line, 128);
        if (!fresh)
            return -2;
        *line = fresh;
        *capacity = 128;
    }
    while ((c = getc(f)) != EOF) {
        if (len + 2 > *capacity) {
            size_t grown;
            char *bigger;
            if (!ll_size_mul(*capacity, 2, &grown) || !(bigger = ll_realloc(*line, grown)))
                return -2;
            *line = bigger;
            *capacity = grown;
        }
        (*line)[len++] = (char)c;
        if (c == '\n')
            break;
    }
    (*line)[len] = '\0';
    return len == 0 && c == EOF ? -1 : (long)len;
}
