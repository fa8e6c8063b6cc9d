/*
 * Internal support: error reporting, checked allocation, threads.
 * Everything here is private to liblayerlab (hidden visibility).
 */
#ifndef LL_SUPPORT_H
#define LL_SUPPORT_H

#include <stddef.h>
#include <stdio.h>
#include <stdint.h>
#include "layerlab/ll_common.h"

#if defined(__GNUC__)
#  define LL_PRINTF(a, b) __attribute__((format(printf, a, b)))
#  define LL_INTERNAL __attribute__((visibility("hidden")))
#else
#  define LL_PRINTF(a, b)
#  define LL_INTERNAL
#endif

/* Record a failure for ll_last_error_message() on this thread and return
 * status, so that call sites read `return ll_fail(LL_ERROR_..., "...", ...)`. */
LL_INTERNAL ll_status ll_fail(ll_status status, const char *fmt, ...) LL_PRINTF(2, 3);

/* Capacity of the message buffer, and a copy of this thread's message (so
 * that a parallel loop can carry a worker's message to the caller). */
#define LL_MESSAGE_CAPACITY 1024
LL_INTERNAL void ll_message_copy(char *dst, size_t capacity);

/* Overflow-checked size arithmetic: return 0 on overflow, else 1 and *out. */
LL_INTERNAL int ll_size_mul(size_t a, size_t b, size_t *out);
LL_INTERNAL int ll_size_add(size_t a, size_t b, size_t *out);

/* The one allocator (support/alloc.c): every allocation in src/ goes
 * through these, never through malloc/calloc/realloc/strdup/free directly
 * (tests/alloc_check.sh). A request of 0 bytes gives a valid 1-byte block;
 * NULL means out of memory (or, in a test, an injected failure). */
LL_INTERNAL void *ll_malloc(size_t bytes);
LL_INTERNAL void *ll_calloc(size_t count, size_t size); /* checks count * size */
LL_INTERNAL void *ll_realloc(void *block, size_t bytes);
LL_INTERNAL void ll_free(void *block);
/* A block of megabytes that look-ups read at random (the tables of a table
 * file): with the C library's allocator on Linux, aligned to 2 MiB and its
 * whole 2 MiB pages marked for transparent huge pages, so that a look-up's
 * scattered reads do not also miss the TLB and walk the page tables; else,
 * and for blocks under 2 MiB, ll_malloc. Freed with ll_free. */
LL_INTERNAL void *ll_malloc_large(size_t bytes);
LL_INTERNAL char *ll_strdup(const char *s);
/* getline(3) through ll_realloc: the length read, -1 at end of file, -2 when
 * out of memory (*line stays valid and is the caller's to ll_free). */
LL_INTERNAL long ll_getline(char **line, size_t *capacity, FILE *f);
/* realpath(3) of path, in a block of ours (ll_free); NULL if it cannot be
 * resolved or on out of memory. */
LL_INTERNAL char *ll_realpath(const char *path);

/* malloc/calloc/realloc of count * size bytes with the multiplication
 * checked; NULL on overflow or failure (count == 0 gives a valid 1-byte
 * block). */
LL_INTERNAL void *ll_alloc_array(size_t count, size_t size);
LL_INTERNAL void *ll_calloc_array(size_t count, size_t size);
LL_INTERNAL void *ll_realloc_array(void *block, size_t count, size_t size);
/* An array of *capacity elements of size bytes grown for one more: to
 * first elements if it has none, else to twice as many (so that n appends
 * cost O(n)). Returns the grown block and sets *capacity, or NULL on
 * overflow or failure, when block and *capacity are unchanged and the
 * block is still the caller's. */
LL_INTERNAL void *ll_grow_array(void *block, size_t *capacity, size_t first, size_t size);

/* Failure injection, for the statically linked tests only (hidden, in no
 * public header). ll_alloc_fail_after(k): from now on count allocations
 * (ll_malloc, ll_calloc, ll_realloc and what is built on them) over all
 * threads, and make the k-th one return NULL (k = 0: count, fail none);
 * only that one fails. ll_alloc_count: allocations since then;
 * ll_alloc_live: blocks allocated minus blocks freed since then (a call that
 * fails and leaves its output unchanged must leave it at 0);
 * ll_alloc_hook_off: stop counting. Deterministic with
 * ll_set_thread_count(1). */
LL_INTERNAL void ll_alloc_fail_after(size_t k);
LL_INTERNAL void ll_alloc_hook_off(void);
LL_INTERNAL size_t ll_alloc_count(void);
LL_INTERNAL long long ll_alloc_live(void);

/* Size-tagged public structs (support/struct_prefix.c): the caller's
 * struct_size says how much of the struct it has; at least the struct_size
 * field itself, else LL_ERROR_INVALID_ARGUMENT naming fn and type.
 * ll_struct_read: dst (dst_size bytes, the library's struct) holds the
 * defaults; the caller's src is copied over them up to its struct_size and
 * dst's struct_size becomes dst_size. NULL src is an error (callers that
 * allow NULL keep the defaults themselves).
 * ll_struct_write: copy the library's src (src_size bytes) into the
 * caller's dst up to dst's struct_size, leaving struct_size and anything
 * beyond it untouched.
 * ll_struct_check: only the checks, for a struct to be written later. */
LL_INTERNAL ll_status ll_struct_read(void *dst, size_t dst_size, const void *src,
                                     const char *fn, const char *type);
LL_INTERNAL ll_status ll_struct_write(void *dst, const void *src, size_t src_size,
                                      const char *fn, const char *type);
LL_INTERNAL ll_status ll_struct_check(const void *caller, const char *fn, const char *type);

/* Run body(i, ctx) for i in [0, count) on up to ll_get_thread_count() threads
 * (dynamic schedule). Inside body, BLAS/LAPACK run single-threaded, so every
 * item is computed by exactly the same sequence of operations whatever the
 * thread count: results are bit-identical. body returns LL_OK or a status;
 * the first failure (lowest index) is returned and its message kept. */
typedef ll_status (*ll_parallel_body)(size_t index, void *ctx);
LL_INTERNAL ll_status ll_parallel_for(size_t count, ll_parallel_body body, void *ctx);

/* Inside a body of ll_parallel_for: the index, below the caller's
 * ll_get_thread_count(), of the thread that runs it (0 outside a loop), so
 * that items can reuse per-thread scratch (one slot per thread, read before
 * the loop's count of threads is known: size it by the caller's count). */
LL_INTERNAL size_t ll_parallel_slot(void);

/* Helpers for argument checks. */
LL_INTERNAL int ll_is_finite(double x);

#define LL_PI 3.14159265358979323846
#define LL_INV_PI 0.31830988618379067154
#define LL_INV_FOUR_PI 0.07957747154594766788

#endif /* LL_SUPPORT_H */
