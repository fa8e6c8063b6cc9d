/*
 * The benchmark's outputs: the table printed by `make bench` and the JSON
 * file (bench/results.json), both from the driver's store, with the
 * speed and memory targets (targets.h) checked against the figures.
 */
#ifndef BENCH_REPORT_H
#define BENCH_REPORT_H

#include <stdio.h>

#include "metrics.h"

void bench_report_table(FILE *out, const bench_store *store);
/* Returns 0 on success (the file is written whole, then renamed). */
int bench_report_json(const char *path, const bench_store *store);

#endif /* BENCH_REPORT_H */
