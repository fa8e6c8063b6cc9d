/* llbuild's progress display (see progress.h). */
#include "progress.h"

#include <string.h>
#include <time.h>
#include <unistd.h>

static double now_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* m:ss */
static void format_time(double seconds, char *buf, size_t size)
{
    long s = seconds > 0.0 && seconds < 1e9 ? (long)(seconds + 0.5) : 0;
    snprintf(buf, size, "%ld:%02ld", s / 60, s % 60);
}

void ll_progress_init(ll_progress *p, FILE *out, int quiet, double start)
{
    memset(p, 0, sizeof *p);
    p->out = out;
    p->quiet = quiet;
    p->tty = isatty(fileno(out));
    p->start = start;
    p->last_draw = -1.0;
    p->last_decile = -1;
    p->scale = 1.0;
}

void ll_progress_update(ll_progress *p, double fraction, const char *stage)
{
    double now = now_seconds(), elapsed = now - p->start;
    int changed, percent, decile;
    char el[32], eta[32];

    if (p->quiet || strcmp(stage, "done") == 0)
        return;
    fraction *= p->scale;
    changed = strncmp(stage, p->stage, sizeof p->stage - 1) != 0;
    percent = (int)(fraction * 100.0 + 0.5);
    decile = (int)(fraction * 10.0);
    if (changed) {
        strncpy(p->stage, stage, sizeof p->stage - 1);
        p->stage[sizeof p->stage - 1] = '\0';
    }
    format_time(elapsed, el, sizeof el);
    /* The estimate of the remaining time assumes the rest goes at the
     * average pace so far (the fractions are cost-weighted). */
    if (fraction > 0.02)
        format_time(elapsed * (1.0 - fraction) / fraction, eta, sizeof eta);
    else
        strcpy(eta, "?");
    if (p->tty) {
        char bar[31];
        int k, filled = (int)(fraction * 30.0);
        if (!changed && now - p->last_draw < 0.1)
            return;
        for (k = 0; k < 30; ++k)
            bar[k] = k < filled ? '#' : '.';
        bar[30] = '\0';
        fprintf(p->out, "\r[%s] %3d%%  %-20.20s elapsed %s  ETA %s \033[K", bar, percent,
                p->stage, el, eta);
        fflush(p->out);
        p->drawn = 1;
        p->last_draw = now;
    } else if (changed || decile > p->last_decile) {
        fprintf(p->out, "llbuild: %3d%% %s (elapsed %s, ETA %s)\n", percent, p->stage, el,
                eta);
        fflush(p->out);
        p->last_decile = decile;
    }
}

void ll_progress_finish(ll_progress *p, int ok)
{
    if (p->quiet)
        return;
    if (p->tty && p->drawn) {
        fprintf(p->out, "\r\033[K");
        fflush(p->out);
    } else if (!p->tty && ok) {
        char el[32];
        format_time(now_seconds() - p->start, el, sizeof el);
        fprintf(p->out, "llbuild: 100%% done (elapsed %s)\n", el);
    }
}
