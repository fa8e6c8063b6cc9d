/*
 * llbuild's progress display on stderr: on a terminal one redrawn line
 * (bar, percent, stage, elapsed, ETA); otherwise plain lines, one per stage
 * change or 10% step, so that logs stay readable.
 */
#ifndef LLBUILD_PROGRESS_H
#define LLBUILD_PROGRESS_H

#include <stdio.h>

typedef struct ll_progress {
    FILE *out;
    int quiet, tty;
    double start;        /* seconds, monotonic clock        */
    double scale;        /* shown fraction = fraction * scale (the build's
                            share; writing takes the rest)  */
    double last_draw;    /* when the line was last drawn    */
    int last_decile;     /* plain mode: last 10% step shown */
    char stage[64];
    int drawn;           /* a terminal line is on screen    */
} ll_progress;

void ll_progress_init(ll_progress *p, FILE *out, int quiet, double start);
/* Show the fraction done and the stage (a monitor's report). The
 * library's final "done" is not shown (writing follows). */
void ll_progress_update(ll_progress *p, double fraction, const char *stage);
/* Clear the terminal line (or print the final plain line). */
void ll_progress_finish(ll_progress *p, int ok);

#endif
