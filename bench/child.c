/* Running one measured program; see child.h. */
#include "child.h"
#include "bench_util.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

/* Read everything from fd into a NUL-terminated buffer. */
static char *read_all(int fd)
{
    size_t size = 0, capacity = 4096;
    char *buf = bench_alloc(capacity, 1);
    for (;;) {
        ssize_t got;
        if (size + 1 >= capacity) {
            char *bigger = realloc(buf, capacity * 2);
            if (!bigger)
                bench_die("driver: out of memory reading a child's output");
            buf = bigger;
            capacity *= 2;
        }
        got = read(fd, buf + size, capacity - size - 1);
        if (got < 0 && errno == EINTR)
            continue;
        if (got <= 0)
            break;
        size += (size_t)got;
    }
    buf[size] = '\0';
    return buf;
}

/* One protocol line into the store. */
static void parse_line(char *line, const char *prefix, bench_store *store)
{
    char id[256], unit[32], key[256], *end;
    double value;
    int used = 0;
    if (sscanf(line, "metric %200s %31s %n", id, unit, &used) == 2 && used > 0) {
        char full[512];
        value = strtod(line + used, &end);
        if (end == line + used)
            return;
        snprintf(full, sizeof full, "%s%s", prefix, id);
        bench_store_add(store, full, unit, value);
    } else if (sscanf(line, "info %200s %n", key, &used) == 1 && used > 0) {
        char full[512];
        snprintf(full, sizeof full, "%s%s", prefix, key);
        bench_store_info(store, full, line + used);
    }
}

static void parse_output(char *text, const char *prefix, bench_store *store)
{
    char *line = text;
    while (line && *line) {
        char *next = strchr(line, '\n');
        if (next)
            *next++ = '\0';
        parse_line(line, prefix, store);
        line = next;
    }
}

int bench_run_child(char *const argv[], char *const env[], const char *prefix,
                    bench_store *store, bench_child_result *result)
{
    int fds[2];
    pid_t pid;
    struct rusage ru;
    double start;
    char *output;

    memset(result, 0, sizeof *result);
    fflush(stdout);
    fflush(stderr);
    if (pipe(fds) != 0)
        bench_die("driver: pipe failed: %s", strerror(errno));
    start = bench_wall_seconds();
    pid = fork();
    if (pid < 0)
        bench_die("driver: fork failed: %s", strerror(errno));
    if (pid == 0) {
        size_t i;
        close(fds[0]);
        if (dup2(fds[1], STDOUT_FILENO) < 0)
            _exit(127);
        close(fds[1]);
        for (i = 0; env && env[i]; ++i)
            if (putenv(env[i]) != 0)
                _exit(127);
        execv(argv[0], argv);
        fprintf(stderr, "driver: cannot run %s: %s\n", argv[0], strerror(errno));
        _exit(127);
    }
    close(fds[1]);
    output = read_all(fds[0]);
    close(fds[0]);
    while (wait4(pid, &result->status, 0, &ru) < 0)
        if (errno != EINTR)
            bench_die("driver: wait4 failed: %s", strerror(errno));
    result->wall = bench_wall_seconds() - start;
    result->cpu = (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec +
                  (double)ru.ru_stime.tv_sec + 1e-6 * (double)ru.ru_stime.tv_usec;
    result->peak_rss_mib = (double)ru.ru_maxrss / 1024.0; /* Linux: KiB */
    result->ok = WIFEXITED(result->status) && WEXITSTATUS(result->status) == 0;
    if (prefix)
        parse_output(output, prefix, store);
    free(output);
    return result->ok;
}
