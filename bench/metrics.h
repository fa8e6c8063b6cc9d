/*
 * The driver's store of measurements: every sample of every figure, by id,
 * in the order first seen, plus free-text facts ("info") and errors.
 */
#ifndef BENCH_METRICS_H
#define BENCH_METRICS_H

#include <stddef.h>

typedef struct bench_metric_series {
    char *id, *unit;
    double *samples;
    size_t count, capacity;
} bench_metric_series;

typedef struct bench_info_entry {
    char *key, *text;
} bench_info_entry;

typedef struct bench_store {
    bench_metric_series *series;
    size_t series_count, series_capacity;
    bench_info_entry *info;
    size_t info_count, info_capacity;
    char **errors;
    size_t error_count, error_capacity;
} bench_store;

/* Summary of a series. */
typedef struct bench_stats {
    double median, min, max;
    size_t count;
} bench_stats;

void bench_store_init(bench_store *s);
void bench_store_free(bench_store *s);

/* Append one sample to the series id (created with unit on first use). */
void bench_store_add(bench_store *s, const char *id, const char *unit, double value);
/* Set (or replace) an info entry. */
void bench_store_info(bench_store *s, const char *key, const char *text);
/* Record an error message. */
void bench_store_error(bench_store *s, const char *message);

/* The series id, or NULL. */
const bench_metric_series *bench_store_find(const bench_store *s, const char *id);
/* The info text for key, or NULL. */
const char *bench_store_info_get(const bench_store *s, const char *key);

/* Median (mean of the middle two for an even count), min and max; count 0
 * gives NaNs. */
bench_stats bench_series_stats(const bench_metric_series *m);
/* Stats of the series id; all NaN (count 0) when it does not exist. */
bench_stats bench_store_stats(const bench_store *s, const char *id);

/* strdup for C99. */
char *bench_strdup(const char *text);

#endif /* BENCH_METRICS_H */
