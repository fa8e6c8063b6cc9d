/*
 * Progress reports and cancellation of long calls (see support/watch.h).
 */
#include "support/watch.h"

#include <stddef.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

/* A report when the fraction moved by this much, or this long passed: a
 * progress bar moves smoothly, and a callback that cancels is asked often
 * enough (the owner polls every few milliseconds at the most). */
#define LL_WATCH_STEP (1.0 / 256.0)
#define LL_WATCH_INTERVAL 0.02

static double now_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

void ll_watch_begin_raw(ll_watch *w, ll_monitor_fn progress, void *user,
                        const volatile int *flag)
{
    memset(w, 0, sizeof *w);
    w->progress = progress;
    w->user = user;
    w->flag = flag;
    w->owner = pthread_self();
    w->stage = "";
    w->reported = -1.0;
}

ll_status ll_watch_begin(ll_watch *w, const ll_monitor *monitor, const char *fn)
{
    ll_monitor caller = LL_MONITOR_INIT;
    ll_status s;
    ll_watch_begin_raw(w, NULL, NULL, NULL);
    if (!monitor)
        return LL_OK;
    /* An older, smaller struct lacks the later fields: they stay NULL. */
    s = ll_struct_read(&caller, sizeof caller, monitor, fn, "ll_monitor");
    if (s != LL_OK)
        return s;
    w->progress = caller.progress;
    w->user = caller.user;
    return LL_OK;
}

static int is_cancelled(ll_watch *w)
{
    if (__atomic_load_n(&w->cancelled, __ATOMIC_ACQUIRE))
        return 1;
    if (w->flag && *w->flag) {
        __atomic_store_n(&w->cancelled, 1, __ATOMIC_RELEASE);
        return 1;
    }
    return 0;
}

/* Owner only: call the callback if forced or due. Fractions never go back. */
static void report(ll_watch *w, int force)
{
    size_t done = __atomic_load_n(&w->done, __ATOMIC_RELAXED);
    double fraction = w->start, now;
    if (w->total > 0)
        fraction += w->span * (double)(done < w->total ? done : w->total) / (double)w->total;
    if (fraction > 1.0)
        fraction = 1.0;
    if (fraction < w->reported)
        fraction = w->reported;
    now = now_seconds();
    if (!force && fraction < w->reported + LL_WATCH_STEP &&
        now - w->reported_at < LL_WATCH_INTERVAL)
        return;
    w->reported = fraction;
    w->reported_at = now;
    if (w->progress(w->user, fraction, w->stage) != 0)
        __atomic_store_n(&w->cancelled, 1, __ATOMIC_RELEASE);
}

static int is_owner(const ll_watch *w) { return pthread_equal(pthread_self(), w->owner); }

int ll_watch_stage(ll_watch *w, const char *stage, double start, double span, size_t total)
{
    if (!w)
        return 0;
    w->stage = stage;
    w->start = start;
    w->span = span;
    w->total = total;
    __atomic_store_n(&w->done, 0, __ATOMIC_RELAXED);
    if (is_cancelled(w))
        return 1;
    if (w->progress && is_owner(w))
        report(w, 1);
    return is_cancelled(w);
}

int ll_watch_stage_of(ll_watch *w, const char *stage, size_t k, size_t count, double start,
                      double span, size_t total)
{
    if (!w)
        return 0;
    snprintf(w->stage_text, sizeof w->stage_text, "%s %zu/%zu", stage, k, count);
    return ll_watch_stage(w, w->stage_text, start, span, total);
}

void ll_watch_advance(ll_watch *w, size_t units)
{
    if (w)
        __atomic_add_fetch(&w->done, units, __ATOMIC_RELAXED);
}

int ll_watch_poll(ll_watch *w)
{
    if (!w)
        return 0;
    if (is_cancelled(w))
        return 1;
    if (w->progress && is_owner(w)) {
        report(w, 0);
        return is_cancelled(w);
    }
    return 0;
}

ll_status ll_watch_check(ll_watch *w, const char *fn)
{
    if (ll_watch_poll(w))
        return ll_fail(LL_ERROR_CANCELLED, "%s: cancelled", fn);
    return LL_OK;
}

ll_status ll_watch_finish(ll_watch *w, ll_status s, const char *fn)
{
    if (s != LL_OK || !w)
        return s;
    if (!is_cancelled(w) && w->progress && is_owner(w)) {
        w->start = 1.0;
        w->span = 0.0;
        w->total = 0;
        report(w, 1);
    }
    return ll_watch_check(w, fn);
}
