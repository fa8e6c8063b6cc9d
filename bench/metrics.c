/* The driver's store of measurements; see metrics.h. */
#include "metrics.h"
#include "bench_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

char *bench_strdup(const char *text)
{
    size_t len = strlen(text);
    char *copy = bench_alloc(len + 1, 1);
    memcpy(copy, text, len + 1);
    return copy;
}

/* Make room for one more element in a growing array. */
static void *grow(void *array, size_t count, size_t *capacity, size_t element)
{
    void *bigger;
    if (count < *capacity)
        return array;
    *capacity = *capacity ? 2 * *capacity : 16;
    if (*capacity > (size_t)-1 / element)
        bench_die("bench store: too many entries");
    bigger = realloc(array, *capacity * element);
    if (!bigger)
        bench_die("bench store: out of memory");
    return bigger;
}

void bench_store_init(bench_store *s) { memset(s, 0, sizeof *s); }

void bench_store_free(bench_store *s)
{
    size_t i;
    for (i = 0; i < s->series_count; ++i) {
        free(s->series[i].id);
        free(s->series[i].unit);
        free(s->series[i].samples);
    }
    for (i = 0; i < s->info_count; ++i) {
        free(s->info[i].key);
        free(s->info[i].text);
    }
    for (i = 0; i < s->error_count; ++i)
        free(s->errors[i]);
    free(s->series);
    free(s->info);
    free(s->errors);
    memset(s, 0, sizeof *s);
}

const bench_metric_series *bench_store_find(const bench_store *s, const char *id)
{
    size_t i;
    for (i = 0; i < s->series_count; ++i)
        if (strcmp(s->series[i].id, id) == 0)
            return &s->series[i];
    return NULL;
}

void bench_store_add(bench_store *s, const char *id, const char *unit, double value)
{
    bench_metric_series *m = (bench_metric_series *)bench_store_find(s, id);
    if (!m) {
        s->series = grow(s->series, s->series_count, &s->series_capacity, sizeof *s->series);
        m = &s->series[s->series_count++];
        memset(m, 0, sizeof *m);
        m->id = bench_strdup(id);
        m->unit = bench_strdup(unit);
    }
    m->samples = grow(m->samples, m->count, &m->capacity, sizeof *m->samples);
    m->samples[m->count++] = value;
}

void bench_store_info(bench_store *s, const char *key, const char *text)
{
    size_t i;
    for (i = 0; i < s->info_count; ++i)
        if (strcmp(s->info[i].key, key) == 0) {
            free(s->info[i].text);
            s->info[i].text = bench_strdup(text);
            return;
        }
    s->info = grow(s->info, s->info_count, &s->info_capacity, sizeof *s->info);
    s->info[s->info_count].key = bench_strdup(key);
    s->info[s->info_count].text = bench_strdup(text);
    ++s->info_count;
}

const char *bench_store_info_get(const bench_store *s, const char *key)
{
    size_t i;
    for (i = 0; i < s->info_count; ++i)
        if (strcmp(s->info[i].key, key) == 0)
            return s->info[i].text;
    return NULL;
}

void bench_store_error(bench_store *s, const char *message)
{
    s->errors = grow(s->errors, s->error_count, &s->error_capacity, sizeof *s->errors);
    s->errors[s->error_count++] = bench_strdup(message);
}

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

bench_stats bench_series_stats(const bench_metric_series *m)
{
    bench_stats st;
    double *sorted;
    st.count = m ? m->count : 0;
    if (st.count == 0) {
        st.median = st.min = st.max = NAN;
        return st;
    }
    sorted = bench_alloc(m->count, sizeof(double));
    memcpy(sorted, m->samples, m->count * sizeof(double));
    qsort(sorted, m->count, sizeof(double), compare_doubles);
    st.min = sorted[0];
    st.max = sorted[m->count - 1];
    st.median = m->count % 2 ? sorted[m->count / 2]
                             : 0.5 * (sorted[m->count / 2 - 1] + sorted[m->count / 2]);
    free(sorted);
    return st;
}

bench_stats bench_store_stats(const bench_store *s, const char *id)
{
    return bench_series_stats(bench_store_find(s, id));
}
