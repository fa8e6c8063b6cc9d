/*
 * layerlab — common definitions: export macros, versions, status codes,
 * error messages, the progress monitor and the allocator. Both libraries
 * (liblayerlab and liblayerlab_reader) export everything declared here.
 *
 * Part of the public API; include <layerlab.h> rather than this file.
 */
#ifndef LAYERLAB_LL_COMMON_H
#define LAYERLAB_LL_COMMON_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* LL_API marks every exported symbol. The library is built with
 * -fvisibility=hidden, so nothing else leaves the shared object. */
#if defined(_WIN32)
#  if defined(LL_BUILDING_LIBRARY)
#    define LL_API __declspec(dllexport)
#  else
#    define LL_API
#  endif
#elif defined(__GNUC__) && __GNUC__ >= 4
#  define LL_API __attribute__((visibility("default")))
#else
#  define LL_API
#endif

/* LL_DEPRECATED(msg) marks a declaration that is kept but should no longer
 * be used: the compiler warns at each use with msg. */
#if defined(__GNUC__) || defined(__clang__)
#  define LL_DEPRECATED(msg) __attribute__((deprecated(msg)))
#elif defined(_MSC_VER)
#  define LL_DEPRECATED(msg) __declspec(deprecated(msg))
#else
#  define LL_DEPRECATED(msg)
#endif

/* ---------------------------------------------------------------- versions
 * The numbers live here and nowhere else: the Makefile reads them from this
 * header. The soname (liblayerlab.so.LL_ABI_VERSION) changes only when the
 * ABI changes incompatibly, never for a release. */
#define LL_VERSION_MAJOR 1
#define LL_VERSION_MINOR 0
#define LL_VERSION_PATCH 0
#define LL_ABI_VERSION 1

#define LL_VERSION_NUMBER \
    (LL_VERSION_MAJOR * 10000 + LL_VERSION_MINOR * 100 + LL_VERSION_PATCH)

#define LL_STRINGIFY_IMPL(x) #x
#define LL_STRINGIFY(x) LL_STRINGIFY_IMPL(x)
#define LL_VERSION_STRING                                   \
    LL_STRINGIFY(LL_VERSION_MAJOR) "." LL_STRINGIFY(LL_VERSION_MINOR) "." \
    LL_STRINGIFY(LL_VERSION_PATCH)

/* True when the headers in use are at least version x.y.z. */
#define LL_AT_LEAST_VERSION(x, y, z) \
    (LL_VERSION_NUMBER >= ((x) * 10000 + (y) * 100 + (z)))

/* The version of the library actually loaded (may differ from the headers'). */
LL_API int ll_version_number(void);
/* Static text such as "1.0.0"; never NULL. */
LL_API const char *ll_version_string(void);

/* ------------------------------------------------------------ status codes
 * Every call that can fail returns an ll_status (0 is success; codes are
 * only ever appended, never renumbered) and hands its values back through
 * out-parameters; on failure those are set to 0 (never NaN) unless the
 * call's documentation says it leaves them unchanged, and
 * ll_last_error_message() says why. Plain getters that can fail only for a
 * NULL argument return their value directly (0 or NULL for NULL). */
typedef int32_t ll_status;

#define LL_OK                      0
#define LL_ERROR_INVALID_ARGUMENT  1  /* an argument is out of its domain     */
#define LL_ERROR_OUT_OF_MEMORY     2  /* an allocation failed or would overflow */
#define LL_ERROR_IO                3  /* a file could not be read or written  */
#define LL_ERROR_FORMAT            4  /* a file's contents are malformed      */
#define LL_ERROR_NUMERICAL         5  /* a factorisation or series failed     */
#define LL_ERROR_UNSUPPORTED       6  /* valid, but not supported by this build */
#define LL_ERROR_PARSE             7  /* a material description has an error  */
#define LL_ERROR_CANCELLED         8  /* the caller's monitor cancelled the call */

/* Static English text for a status ("invalid argument", ...); never NULL. */
LL_API const char *ll_status_string(ll_status status);

/* Detail of the last failure of a layerlab call made on the calling thread
 * (e.g. "ll_layer_set_diffuse: albedo 1.5 is outside [0, 1]"). The text
 * stays valid until the next failing call on the same thread. "" when no
 * call has failed yet. Successful calls do not clear it. */
LL_API const char *ll_last_error_message(void);

/* ----------------------------------------------------------------- monitor
 * The one way to watch a long call: every call that can take long has a
 * `const ll_monitor *monitor` as its last argument (NULL: not watched).
 * The callback receives the monitor's user pointer first, the fraction done
 * in [0, 1] and a short stage name; it returns 0 to let the call continue
 * and non-zero to cancel it, which then returns LL_ERROR_CANCELLED and
 * leaves its output unchanged. Why 0 continues: a monitor that only
 * watches returns 0, the same "nothing wrong" value as LL_OK, and the zero
 * of an unset or forgotten flag can never cancel a call by accident.
 *
 * The callback is only ever called from the thread that made the call (never from a worker
 * thread: workers poll an internal flag that the calling thread raises when the callback
 * returns non-zero), at least once with 0 when the work starts and once with 1 just before the
 * result is committed (a cancel at that last report still leaves the output unchanged), and in
 * between as the work advances (fractions never decrease), while the calling thread waits for
 * workers too. Stage names are static strings such as "quadrature", "interface", "phase
 * function", "doubling", "adding", "measured", "writing". The callback must not call layerlab
 * on the object being computed. A monitor may be passed to several calls, also at once from
 * several threads if its callback is thread-safe. */
typedef int (*ll_monitor_fn)(void *user, double fraction, const char *stage);
typedef struct ll_monitor {
    size_t struct_size;     /* sizeof(ll_monitor) */
    ll_monitor_fn progress; /* nullable */
    void *user;
} ll_monitor;
#define LL_MONITOR_INIT { sizeof(ll_monitor), NULL, NULL }

/* --------------------------------------------------------------- allocator
 * Every block of memory the library allocates (objects, tables, scratch,
 * file buffers) comes from one allocator: malloc, realloc and free by
 * default, or the caller's, as zstd's ZSTD_customMem and OpenEXR's
 * alloc_fn. Outside it: what other libraries allocate for themselves
 * (OpenBLAS's buffers, the OpenMP runtime, the C library's thread stacks and
 * FILE buffers).
 *  alloc: as malloc (size is never 0); NULL on failure.
 *  realloc: as realloc (ptr is never NULL, size never 0); NULL on failure,
 *    ptr then still valid.
 *  free: as free; ptr is never NULL.
 *  user: passed first to the three.
 * Blocks need the alignment malloc gives (the library asks for no stricter
 * one). The setting is process-wide and not
 * synchronised: set it before the library allocates anything (before any
 * object exists, and before any other thread calls layerlab), and change it
 * back only when every object made with it is gone. NULL restores malloc.
 * Set struct_size = sizeof(ll_allocator) (the INIT macro does).
 * LL_ERROR_INVALID_ARGUMENT for a struct_size smaller than the first
 * field's end or a NULL function pointer (the allocator is then unchanged). */
typedef struct ll_allocator {
    size_t struct_size;                                   /* sizeof(ll_allocator) */
    void *(*alloc)(void *user, size_t size);              /* as malloc; NULL on failure */
    void *(*realloc)(void *user, void *ptr, size_t size); /* as realloc */
    void (*free)(void *user, void *ptr);                  /* as free; never given NULL */
    void *user;
} ll_allocator;
#define LL_ALLOCATOR_INIT { sizeof(ll_allocator), NULL, NULL, NULL, NULL }

/* Make *allocator the one every later allocation of the library uses (its
 * fields are copied: the struct may go after the call), or restore malloc,
 * realloc and free with NULL. Process-wide and not thread-safe: call it as
 * the rules above say, before anything else of layerlab runs. LL_OK, or
 * LL_ERROR_INVALID_ARGUMENT (the allocator in effect unchanged) for a
 * struct_size smaller than the first field's end or a NULL function
 * pointer. */
LL_API ll_status ll_set_allocator(const ll_allocator *allocator);

#ifdef __cplusplus
}
#endif
#endif /* LAYERLAB_LL_COMMON_H */
