/*
 * The inside of ll_monitor (layerlab/ll_common.h): one ll_watch per long
 * public call carries the caller's callback, an optional flag raised from
 * outside (a signal handler, the deprecated ll_build_options.cancel) and
 * the progress of the current stage.
 *
 * Threads: the callback runs only on the thread that began the watch (the
 * owner). Every thread polls; a worker only reads the flags, the owner
 * also reports progress, and when the callback asks to stop it raises the
 * internal flag that the workers see at their next poll. Polls sit inside
 * the long loops (per column, per node pair, per doubling step, per root),
 * so a cancel is seen within one such step on every thread.
 *
 * Progress is deterministic apart from time: a stage is `total` units of
 * work, each finished unit is counted (atomically), and the owner reports
 * start + span * done / total when that moved by 1/256 or 20 ms passed.
 */
#ifndef LL_SUPPORT_WATCH_H
#define LL_SUPPORT_WATCH_H

#include "support/support.h"

#include <pthread.h>

typedef struct ll_watch {
    ll_monitor_fn progress;   /* nullable: the caller's callback                 */
    void *user;
    const volatile int *flag; /* nullable: raised from outside (signal handlers)  */
    pthread_t owner;          /* the calling thread, the only one that reports    */
    const char *stage;        /* static stage name (owner only)                   */
    double start, span;       /* the stage's share of [0, 1] (owner only)         */
    size_t total;             /* work units of the stage                          */
    size_t done;              /* atomic: units finished                           */
    int cancelled;            /* atomic: raised once, never lowered               */
    double reported;          /* owner: last fraction reported, -1 before any     */
    double reported_at;       /* owner: when, monotonic seconds                   */
    char stage_text[64];      /* owner: a counted stage's name (ll_watch_stage_of) */
} ll_watch;

/* Begin a watch for a public call named fn on the calling thread. monitor
 * may be NULL; a monitor is read up to its struct_size (an older, smaller
 * struct lacks the later fields), and a struct_size below sizeof(size_t)
 * is refused as uninitialised (LL_ERROR_INVALID_ARGUMENT). */
LL_INTERNAL ll_status ll_watch_begin(ll_watch *w, const ll_monitor *monitor, const char *fn);

/* Begin a watch from the internal parts: a callback (nullable), its user
 * pointer and an outside flag (nullable). Never fails. */
LL_INTERNAL void ll_watch_begin_raw(ll_watch *w, ll_monitor_fn progress, void *user,
                                    const volatile int *flag);

/* Start a stage of `total` units covering [start, start + span] of the
 * call (owner only, outside parallel loops); reports its start. Returns
 * non-zero when the call is cancelled. w may be NULL (then 0). */
LL_INTERNAL int ll_watch_stage(ll_watch *w, const char *stage, double start, double span,
                               size_t total);

/* ll_watch_stage under the name "STAGE K/COUNT" (e.g. "resolution 2/5":
 * the second of five searches), kept in the watch itself. */
LL_INTERNAL int ll_watch_stage_of(ll_watch *w, const char *stage, size_t k, size_t count,
                                  double start, double span, size_t total);
/* Count finished units of the current stage (any thread; NULL is fine). */
LL_INTERNAL void ll_watch_advance(ll_watch *w, size_t units);

/* Non-zero when the call is cancelled (any thread; NULL is fine). On the
 * owner it also reports progress, which may cancel. */
LL_INTERNAL int ll_watch_poll(ll_watch *w);

/* LL_OK, or LL_ERROR_CANCELLED with a message naming fn, if polling says
 * the call is cancelled. */
LL_INTERNAL ll_status ll_watch_check(ll_watch *w, const char *fn);

/* The end of a call that is about to commit its result: with s == LL_OK
 * report 1 (the caller may still cancel there) and return LL_OK or
 * LL_ERROR_CANCELLED; any other s is returned as it is. */
LL_INTERNAL ll_status ll_watch_finish(ll_watch *w, ll_status s, const char *fn);

/* ll_parallel_for, polled: the owner takes items like every thread and,
 * once none are left to take, keeps polling (reporting progress, seeing a
 * cancel) every millisecond until the other threads are done, so a long
 * item on a worker does not silence the callback (without a callback it
 * sleeps until the workers are done, as ll_parallel_for does). w may be NULL. */
LL_INTERNAL ll_status ll_parallel_for_watched(size_t count, ll_parallel_body body, void *ctx,
                                              ll_watch *w);

#endif /* LL_SUPPORT_WATCH_H */
