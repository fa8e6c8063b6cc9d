/*
 * ll_set_allocator (support/alloc.c): with a counting allocator installed, a
 * small build, write, open, evaluation and sampling take every block of the
 * library from it -- as many blocks as the library's own count of its
 * allocations -- and give every one back to it; the arguments are checked;
 * NULL restores malloc. And ll_grow_array, the library's one growth of an
 * array.
 */
#include "test_util.h"
#include "support/support.h"

/* Every block carries a header with a mark and its size, so that a block the
 * allocator did not make (the C library's, or a pointer into a block) is
 * seen when it comes back. Counted atomically: the build's worker threads
 * allocate too. */
#define MARK 0x6c6c616c6c6f63ull /* "llalloc" */

typedef union header {
    struct {
        uint64_t mark;
        size_t size;
    } h;
    long double align_ld; /* the union's size keeps the payload aligned as malloc's */
    long long align_ll;
    void *align_p;
} header;

typedef struct counts {
    size_t allocs, reallocs, frees, foreign;
    long long live;
} counts;

static void *count_alloc(void *user, size_t size)
{
    counts *c = user;
    header *h;
    __atomic_fetch_add(&c->allocs, 1, __ATOMIC_RELAXED);
    if (size == 0)
        __atomic_fetch_add(&c->foreign, 1, __ATOMIC_RELAXED); /* the contract says never */
    h = malloc(sizeof(header) + size);
    if (!h)
        return NULL;
    h->h.mark = MARK;
    h->h.size = size;
    __atomic_fetch_add(&c->live, 1, __ATOMIC_RELAXED);
    return (char *)h + sizeof(header);
}

static header *header_of(counts *c, void *ptr)
{
    header *h = (header *)(void *)((char *)ptr - sizeof(header));
    if (h->h.mark != MARK) {
        __atomic_fetch_add(&c->foreign, 1, __ATOMIC_RELAXED);
        return NULL;
    }
    return h;
}

static void *count_realloc(void *user, void *ptr, size_t size)
{
    counts *c = user;
    header *h, *bigger;
    __atomic_fetch_add(&c->reallocs, 1, __ATOMIC_RELAXED);
    if (!ptr || size == 0 || !(h = header_of(c, ptr))) {
        __atomic_fetch_add(&c->foreign, 1, __ATOMIC_RELAXED);
        return NULL;
    }
    bigger = realloc(h, sizeof(header) + size);
    if (!bigger)
        return NULL;
    bigger->h.size = size;
    return (char *)bigger + sizeof(header);
}

static void count_free(void *user, void *ptr)
{
    counts *c = user;
    header *h;
    __atomic_fetch_add(&c->frees, 1, __ATOMIC_RELAXED);
    if (!ptr) {
        __atomic_fetch_add(&c->foreign, 1, __ATOMIC_RELAXED);
        return;
    }
    if (!(h = header_of(c, ptr)))
        return;
    h->h.mark = 0;
    __atomic_fetch_sub(&c->live, 1, __ATOMIC_RELAXED);
    free(h);
}

/* A diffuse layer written as a file, opened, evaluated and sampled, and
 * everything freed again. */
static void build_write_open_eval(const char *dir)
{
    char path[600];
    ll_layer *l = ll_test_layer(16, 1);
    const ll_layer *layers[1];
    ll_bsdf *b = NULL;
    double rgb[3], pdf, mu_o, phi, f[3];
    const double u[2] = { 0.25, 0.75 };
    layers[0] = l;
    assert_int_equal(ll_layer_set_diffuse(l, 0.5, NULL), LL_OK);
    snprintf(path, sizeof path, "%s/diffuse.bsdf", dir);
    assert_int_equal(ll_bsdf_write(path, layers, 1, NULL, NULL), LL_OK);
    ll_layer_destroy(l);
    assert_int_equal(ll_bsdf_open(path, NULL, &b), LL_OK);
    assert_int_equal(ll_bsdf_eval(b, 0.6, -0.5, 0.3, NULL, rgb), LL_OK);
    assert_true(rgb[0] > 0.0);
    assert_int_equal(ll_bsdf_pdf(b, 0.6, -0.5, 0.3, NULL, &pdf), LL_OK);
    assert_true(pdf > 0.0);
    assert_int_equal(ll_bsdf_sample(b, 0.6, u, NULL, &mu_o, &phi, &pdf, f), LL_OK);
    assert_true(pdf > 0.0 && f[0] > 0.0);
    ll_bsdf_release(b);
}

static void every_block_goes_through_the_allocator(void **state)
{
    counts c;
    ll_allocator a = LL_ALLOCATOR_INIT;
    char dir[512];
    size_t library_count;
    (void)state;
    memset(&c, 0, sizeof c);
    a.alloc = count_alloc;
    a.realloc = count_realloc;
    a.free = count_free;
    a.user = &c;
    ll_test_mkdtemp(dir, sizeof dir);
    assert_int_equal(ll_set_allocator(&a), LL_OK);
    ll_alloc_fail_after(0); /* the library's own count of its allocations */
    build_write_open_eval(dir);
    library_count = ll_alloc_count();
    assert_int_equal(ll_alloc_live(), 0);
    ll_alloc_hook_off();
    assert_int_equal(ll_set_allocator(NULL), LL_OK);
    ll_test_rmdir(dir);

    assert_true(c.allocs > 0);
    /* Every allocation of the library (malloc, calloc and realloc) was one
     * call of the hook's alloc or realloc ... */
    if (c.allocs + c.reallocs != library_count)
        fail_msg("the library made %zu allocations, the allocator saw %zu allocs and %zu "
                 "reallocs", library_count, c.allocs, c.reallocs);
    /* ... every block came back to its free, and nothing else did. */
    assert_int_equal(c.foreign, 0);
    assert_int_equal(c.live, 0);
    assert_int_equal(c.frees, c.allocs);

    /* Back on malloc: the same work, and the hook sees nothing more. */
    {
        size_t before = c.allocs + c.reallocs + c.frees;
        ll_test_mkdtemp(dir, sizeof dir);
        build_write_open_eval(dir);
        ll_test_rmdir(dir);
        assert_int_equal(c.allocs + c.reallocs + c.frees, before);
    }
}

/* A failing alloc is the library's out of memory. */
static void *refuse_alloc(void *user, size_t size)
{
    (void)user;
    (void)size;
    return NULL;
}

static void failing_allocator_is_out_of_memory(void **state)
{
    counts c;
    ll_allocator a = LL_ALLOCATOR_INIT;
    ll_bsdf *b = NULL;
    (void)state;
    memset(&c, 0, sizeof c);
    a.alloc = refuse_alloc;
    a.realloc = count_realloc;
    a.free = count_free;
    a.user = &c;
    assert_int_equal(ll_set_allocator(&a), LL_OK);
    assert_int_equal(ll_bsdf_open(LL_SOURCE_DIR "/tests/data/roughgold_alpha_0.2.bsdf", NULL, &b),
                     LL_ERROR_OUT_OF_MEMORY);
    assert_int_equal(ll_set_allocator(NULL), LL_OK);
    assert_null(b);
    assert_int_equal(c.frees, 0);
    assert_int_equal(ll_bsdf_open(LL_SOURCE_DIR "/tests/data/roughgold_alpha_0.2.bsdf", NULL, &b),
                     LL_OK);
    ll_bsdf_release(b);
}

static void arguments_are_checked(void **state)
{
    counts c;
    ll_allocator a = LL_ALLOCATOR_INIT, missing = LL_ALLOCATOR_INIT;
    (void)state;
    memset(&c, 0, sizeof c);
    a.alloc = count_alloc;
    a.realloc = count_realloc;
    a.free = count_free;
    a.user = &c;
    missing = a;
    missing.realloc = NULL;
    assert_int_equal(ll_set_allocator(&missing), LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "ll_set_allocator"));
    a.struct_size = sizeof a.struct_size - 1;
    assert_int_equal(ll_set_allocator(&a), LL_ERROR_INVALID_ARGUMENT);
    /* Neither call installed anything: the library still uses malloc. */
    {
        ll_bsdf *b = NULL;
        assert_int_equal(
            ll_bsdf_open(LL_SOURCE_DIR "/tests/data/roughgold_alpha_0.2.bsdf", NULL, &b), LL_OK);
        ll_bsdf_release(b);
        assert_int_equal(c.allocs + c.reallocs + c.frees, 0);
    }
    assert_int_equal(ll_set_allocator(NULL), LL_OK);
}

/* ll_grow_array: first elements, then doubling; an overflowing or failed
 * growth leaves the block and its capacity as they were. */
static void arrays_grow_geometrically(void **state)
{
    size_t cap = 0, k, huge = SIZE_MAX / 4 + 1;
    int *a = NULL, *grown;
    (void)state;
    a = ll_grow_array(a, &cap, 4, sizeof *a);
    assert_non_null(a);
    assert_int_equal(cap, 4);
    for (k = 0; k < 4; ++k)
        a[k] = (int)k;
    a = ll_grow_array(a, &cap, 4, sizeof *a);
    assert_non_null(a);
    assert_int_equal(cap, 8);
    for (k = 0; k < 4; ++k)
        assert_int_equal(a[k], (int)k); /* (kept) */
    /* Twice the capacity overflows size_t: refused, nothing changed. */
    cap = huge * 2;
    assert_null(ll_grow_array(a, &cap, 4, 1));
    assert_int_equal(cap, huge * 2);
    /* Twice the elements' bytes overflow: likewise. */
    cap = huge;
    assert_null(ll_grow_array(a, &cap, 4, sizeof *a));
    assert_int_equal(cap, huge);
    /* A failed allocation: likewise, and the block is still whole. */
    cap = 8;
    ll_alloc_fail_after(1);
    grown = ll_grow_array(a, &cap, 4, sizeof *a);
    ll_alloc_fail_after(0);
    assert_null(grown);
    assert_int_equal(cap, 8);
    assert_int_equal(a[3], 3);
    ll_free(a);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(every_block_goes_through_the_allocator),
        cmocka_unit_test(failing_allocator_is_out_of_memory),
        cmocka_unit_test(arguments_are_checked),
        cmocka_unit_test(arrays_grow_geometrically),
    };
    return cmocka_run_group_tests_name("allocator", tests, NULL, NULL);
}
