/*
 * Running one measured program in its own process: its whole-process wall
 * time, CPU time (user + system, all threads) and peak resident memory
 * from wait4(), and its report lines (bench_util.h protocol) into a store.
 */
#ifndef BENCH_CHILD_H
#define BENCH_CHILD_H

#include "metrics.h"

typedef struct bench_child_result {
    int ok;             /* exited normally with status 0       */
    int status;         /* the raw wait status                 */
    double wall;        /* seconds from fork to reaped         */
    double cpu;         /* user + system seconds of the child  */
    double peak_rss_mib;/* ru_maxrss in MiB                    */
} bench_child_result;

/* Run argv[0] (a path) with arguments argv (NULL-terminated). env: extra
 * "NAME=value" settings for the child (NULL-terminated list, or NULL).
 * Protocol lines of its stdout are stored with ids and keys prefixed by
 * prefix (NULL: its output is not kept); other lines are ignored. stderr
 * is passed through. Returns result->ok. */
int bench_run_child(char *const argv[], char *const env[], const char *prefix,
                    bench_store *store, bench_child_result *result);

#endif /* BENCH_CHILD_H */
