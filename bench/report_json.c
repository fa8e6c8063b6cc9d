/* bench/results.json; see report.h. Layout:
 *   { "format": "layerlab-bench-1",
 *     "info":    { key: text, ... }       machine, system load, versions
 *     "metrics": { id: { "unit", "median", "min", "max", "samples": [...] } }
 *     "reference": the original's and pbrt-v3's figures (plan.h)
 *     "targets": [ { "what", "value", "goal", "at_least", "met", "basis" } ]
 *     "errors":  [ text ] } */
#include "plan.h"
#include "report.h"
#include "targets.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static void json_string(FILE *f, const char *text)
{
    const unsigned char *p;
    fputc('"', f);
    for (p = (const unsigned char *)text; *p; ++p) {
        if (*p == '"' || *p == '\\')
            fprintf(f, "\\%c", *p);
        else if (*p < 0x20)
            fprintf(f, "\\u%04x", *p);
        else
            fputc(*p, f);
    }
    fputc('"', f);
}

static void json_number(FILE *f, double x)
{
    if (isfinite(x))
        fprintf(f, "%.6g", x);
    else
        fputs("null", f);
}

static void write_info(FILE *f, const bench_store *s)
{
    size_t i;
    fputs("  \"info\": {", f);
    for (i = 0; i < s->info_count; ++i) {
        fputs(i ? ",\n    " : "\n    ", f);
        json_string(f, s->info[i].key);
        fputs(": ", f);
        json_string(f, s->info[i].text);
    }
    fputs("\n  },\n", f);
}

static void write_metrics(FILE *f, const bench_store *s)
{
    size_t i, k;
    fputs("  \"metrics\": {", f);
    for (i = 0; i < s->series_count; ++i) {
        const bench_metric_series *m = &s->series[i];
        bench_stats st = bench_series_stats(m);
        fputs(i ? ",\n    " : "\n    ", f);
        json_string(f, m->id);
        fputs(": { \"unit\": ", f);
        json_string(f, m->unit);
        fputs(", \"median\": ", f);
        json_number(f, st.median);
        fputs(", \"min\": ", f);
        json_number(f, st.min);
        fputs(", \"max\": ", f);
        json_number(f, st.max);
        fputs(", \"samples\": [", f);
        for (k = 0; k < m->count; ++k) {
            if (k)
                fputs(", ", f);
            json_number(f, m->samples[k]);
        }
        fputs("] }", f);
    }
    fputs("\n  },\n", f);
}

static void write_reference(FILE *f)
{
    size_t i;
    fputs("  \"reference\": {\n    \"source\": \"the original layerlab on another 2-core "
          "machine, whole process, median of 3; pbrt-v3 FourierBSDF on "
          "roughgold_alpha_0.2.bsdf\",\n    \"original\": {",
          f);
    for (i = 0; i < BENCH_RECIPE_COUNT; ++i) {
        fputs(i ? ",\n      " : "\n      ", f);
        json_string(f, bench_recipes[i].name);
        fputs(": { \"wall_s\": ", f);
        json_number(f, bench_recipes[i].original_wall_s);
        fputs(", \"peak_rss_mib\": ", f);
        json_number(f, bench_recipes[i].original_rss_mib);
        fputs(" }", f);
    }
    fputs("\n    },\n    \"pbrt_v3_ns\": {", f);
    for (i = 0; i < BENCH_EVAL_FUNCTION_COUNT; ++i) {
        fputs(i ? ",\n      " : "\n      ", f);
        json_string(f, bench_eval_functions[i].pbrt_name);
        fputs(": [", f);
        json_number(f, bench_eval_functions[i].pbrt_low_ns);
        fputs(", ", f);
        json_number(f, bench_eval_functions[i].pbrt_high_ns);
        fputs("]", f);
    }
    fputs("\n    }\n  },\n", f);
}

static void write_targets(FILE *f, const bench_store *s)
{
    bench_target targets[BENCH_MAX_TARGETS];
    size_t count = bench_compute_targets(s, targets), i;
    fputs("  \"targets\": [", f);
    for (i = 0; i < count; ++i) {
        fputs(i ? ",\n    " : "\n    ", f);
        fputs("{ \"what\": ", f);
        json_string(f, targets[i].what);
        fputs(", \"value\": ", f);
        json_number(f, targets[i].value);
        fputs(", \"goal\": ", f);
        json_number(f, targets[i].goal);
        fprintf(f, ", \"at_least\": %s, \"met\": %s, \"basis\": ",
                targets[i].at_least ? "true" : "false", targets[i].met ? "true" : "false");
        json_string(f, targets[i].basis);
        fputs(" }", f);
    }
    fputs("\n  ],\n", f);
}

static void write_errors(FILE *f, const bench_store *s)
{
    size_t i;
    fputs("  \"errors\": [", f);
    for (i = 0; i < s->error_count; ++i) {
        fputs(i ? ", " : "", f);
        json_string(f, s->errors[i]);
    }
    fputs("]\n", f);
}

int bench_report_json(const char *path, const bench_store *store)
{
    char tmp[1024];
    FILE *f;
    int failed;
    if ((size_t)snprintf(tmp, sizeof tmp, "%s.tmp", path) >= sizeof tmp)
        return 1;
    f = fopen(tmp, "w");
    if (!f) {
        perror(tmp);
        return 1;
    }
    fputs("{\n  \"format\": \"layerlab-bench-1\",\n", f);
    write_info(f, store);
    write_metrics(f, store);
    write_reference(f);
    write_targets(f, store);
    write_errors(f, store);
    fputs("}\n", f);
    failed = ferror(f) != 0;
    failed |= fclose(f) != 0;
    if (failed || rename(tmp, path) != 0) {
        perror(path);
        remove(tmp);
        return 1;
    }
    return 0;
}
