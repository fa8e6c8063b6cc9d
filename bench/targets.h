/*
 * The speed and memory targets, checked against the measured medians. Each
 * target carries the basis of its comparison: the original measured side
 * by side on this machine (driver --original), or its figures in plan.h
 * (measured elsewhere, so only indicative).
 */
#ifndef BENCH_TARGETS_H
#define BENCH_TARGETS_H

#include <stddef.h>

#include "metrics.h"

typedef struct bench_target {
    char what[128];    /* e.g. "coated-gold: speedup over the original" */
    double value;      /* the measured figure (a ratio)                  */
    double goal;       /* the figure aimed at                            */
    int at_least;      /* 1: value >= goal passes; 0: value <= goal      */
    int met;
    char basis[96];    /* what the comparison is against                 */
} bench_target;

#define BENCH_MAX_TARGETS 32

/* Fill targets (up to BENCH_MAX_TARGETS); returns the count. Figures that
 * were not measured give no target. */
size_t bench_compute_targets(const bench_store *store, bench_target *targets);

#endif /* BENCH_TARGETS_H */
