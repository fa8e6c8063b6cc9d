/*
 * layerlab — common definitions: export macro, versions, status codes,
 * error messages and the per-thread worker count.
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

/* ---------------------------------------------------------------- versions
 * The numbers live here and nowhere else: the Makefile reads them from this
 * header. The soname (liblayerlab.so.LL_ABI_VERSION) changes only when the
 * ABI changes incompatibly, never for a release. */
#define LL_VERSION_MAJOR 0
#define LL_VERSION_MINOR 1
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
/* Static text such as "0.1.0"; never NULL. */
LL_API const char *ll_version_string(void);

/* ------------------------------------------------------------ status codes
 * Every fallible call returns an ll_status. 0 is success; codes are only
 * ever appended, never renumbered. */
typedef int32_t ll_status;

#define LL_OK                      0
#define LL_ERROR_INVALID_ARGUMENT  1  /* an argument is out of its domain     */
#define LL_ERROR_OUT_OF_MEMORY     2  /* an allocation failed or would overflow */
#define LL_ERROR_IO                3  /* a file could not be read or written  */
#define LL_ERROR_FORMAT            4  /* a file's contents are malformed      */
#define LL_ERROR_NUMERICAL         5  /* a factorisation or series failed     */
#define LL_ERROR_UNSUPPORTED       6  /* valid, but not supported by this build */
#define LL_ERROR_PARSE             7  /* a material description has an error  */
#define LL_ERROR_CANCELLED         8  /* the caller's cancel flag was raised  */

/* Static English text for a status ("invalid argument", ...); never NULL. */
LL_API const char *ll_status_string(ll_status status);

/* Detail of the last failure of a layerlab call made on the calling thread
 * (e.g. "ll_layer_set_diffuse: albedo 1.5 is outside [0, 1]"). The text
 * stays valid until the next failing call on the same thread. "" when no
 * call has failed yet. Successful calls do not clear it. */
LL_API const char *ll_last_error_message(void);

/* ----------------------------------------------------------------- threads
 * The number of worker threads that layerlab calls made *from the calling
 * thread* may use (adding, doubling, building interfaces). 0 means all
 * processors (the default). Results never depend on this number: they are
 * bit-identical for any thread count. The setting is per calling thread, so
 * two renderer threads can use different counts without locking. */
LL_API ll_status ll_set_thread_count(size_t n_threads);
/* The effective count for the calling thread (>= 1). */
LL_API size_t ll_get_thread_count(void);

/* ----------------------------------------------------------------- monitor
 * Progress of a long call, as Embree's progress monitor: called on the calling thread with the
 * fraction done in [0, 1] and a short stage name; a non-zero return cancels the call, which then
 * returns LL_ERROR_CANCELLED and leaves its output unchanged.
 *
 * The callback is only ever called from the thread that made the call (never from a worker
 * thread: workers poll an internal flag that the calling thread raises when the callback
 * returns non-zero), at least once with 0 when the work starts and once with 1 just before the
 * result is committed (a cancel at that last report still leaves the output unchanged), and in
 * between as the work advances (fractions never decrease), while the calling thread waits for
 * workers too. Stage names are static strings such as "quadrature", "interface", "phase
 * function", "doubling", "adding", "measured", "writing". The callback must not call layerlab
 * on the layer being computed. A monitor may be passed to several calls, also at once from
 * several threads if its callback is thread-safe. */
typedef int (*ll_monitor_fn)(void *user, double fraction, const char *stage);
typedef struct ll_monitor {
    size_t struct_size;     /* sizeof(ll_monitor) */
    ll_monitor_fn progress; /* nullable */
    void *user;
} ll_monitor;
#define LL_MONITOR_INIT { sizeof(ll_monitor), NULL, NULL }

#ifdef __cplusplus
}
#endif
#endif /* LAYERLAB_LL_COMMON_H */
