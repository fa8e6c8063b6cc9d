/*
 * The cost of a swept material's build (ll_material_estimate of a material
 * with axes): every basis as material_estimate.c models one build, less
 * what the builder's cache of word layers saves (material_sweep_build.c:
 * the same LRU of LL_WORD_CACHE_ENTRIES entries keyed by word and
 * parameters, LL_WORD_CACHE_IN_MEMORY of them in memory, simulated in the
 * same order), less the process overhead
 * that all bases share. Memory: the largest basis's peak plus the cache's
 * layers at that time plus the streaming writer's tables and buffers;
 * never all bases.
 */
#include "material/word_table.h"

#include <string.h>

/* The streaming writer's chunk and spill buffer (bsdf_writer.c), and its
 * tables per file node pair: length, offset (the file's), extent, CDF row,
 * plus the n x n scratch of one layer's series lengths (len, tail, ref0). */
#define WRITER_BUFFER_BYTES (1.25 * 1048576.0)
#define WRITER_PAIR_BYTES 16.0
#define WRITER_LAYER_PAIR_BYTES 20.0
/* Coefficients a file keeps per value its layers hold (as the cost model
 * counts them): the series are cut at error_goal while the orders store
 * entries down to 1e-12. Fitted on four files: coated-gold, plastic and
 * dusty-metal at their default resolution and a 4 x 4 coated-gold grid at
 * 40 x 40, whose sizes the estimate then gives to -18%, -6%, +20% and -4%
 * (docs/material-language.md, "Sweeps"). */
#define KEPT_PER_STORED 0.62

double ll_file_bytes_estimate(size_t n, size_t nch, size_t n_bases, size_t n_parameter_values,
                              double stored_values)
{
    double nn = (double)n + 2.0, pairs = nn * nn;
    (void)nch;
    return 64.0 + 4.0 * nn + 8.0 * (double)n_parameter_values + 4.0 * pairs * (double)n_bases +
           8.0 * pairs + 4.0 * KEPT_PER_STORED * stored_values + 2048.0;
}

typedef struct sim_entry {
    size_t word;
    ll_word_params params;
    double bytes;
    unsigned long long used;
    int full;
} sim_entry;

/* Look up (word, p) in the simulated cache; on a miss insert it. Returns 1
 * on a hit. */
static int sim_lookup(sim_entry *cache, unsigned long long *clock, size_t word,
                      const ll_word_params *p, double bytes)
{
    size_t k, victim = 0;
    for (k = 0; k < LL_WORD_CACHE_ENTRIES; ++k)
        if (cache[k].full && cache[k].word == word && ll_word_params_equal(&cache[k].params, p)) {
            cache[k].used = ++*clock;
            return 1;
        }
    for (k = 0; k < LL_WORD_CACHE_ENTRIES; ++k) {
        if (!cache[k].full) {
            victim = k;
            break;
        }
        if (cache[k].used < cache[victim].used)
            victim = k;
    }
    cache[victim].full = 1;
    cache[victim].word = word;
    cache[victim].params = *p;
    cache[victim].bytes = bytes;
    cache[victim].used = ++*clock;
    return 0;
}

ll_status ll_material_cost_bases(const ll_material *m, size_t n, size_t orders, size_t nch,
                                 size_t threads, ll_cost_plan *out)
{
    size_t bases = ll_material_basis_count(m), b, a, values = 0;
    sim_entry cache[LL_WORD_CACHE_ENTRIES];
    unsigned long long clock = 0;
    ll_word *words = ll_alloc_array(m->count, sizeof *words);
    ll_word_params(*params)[3] = ll_calloc_array(m->count, sizeof *params);
    double stored = 0.0, peak = 0.0, nn = (double)n + 2.0;
    ll_status s = LL_OK;

    memset(out, 0, sizeof *out);
    memset(cache, 0, sizeof cache);
    if (!words || !params) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_material_estimate: out of memory");
        goto done;
    }
    for (b = 0; b < bases; ++b) {
        ll_material view;
        ll_cost_plan one;
        ll_level_walk lv;
        size_t c, k;
        double cached = 0.0;
        ll_material_basis_view(m, b, words, &view);
        ll_material_params(&view, nch, params);
        ll_material_cost(&view, (const ll_word_params(*)[3])params, n, orders, nch, threads,
                         &one);
        out->layers_built += one.layers_built;
        out->additions += one.additions;
        out->doublings += one.doublings;
        ll_work_add(&out->work, &one.work, 1.0);
        /* Every basis's series are as long as the longest over the bases
         * (the writer's rule): the file holds about bases x the basis that
         * holds the most. */
        if (one.stored_values > stored)
            stored = one.stored_values;
        /* The words the cache gives: as the build visits them, bottom-up. */
        ll_level_walk_begin(&lv, (const ll_word_params(*)[3])params, m->count, nch);
        while (ll_level_walk_next(&lv)) {
            for (c = 0; c < nch; ++c) {
                ll_work work;
                double bytes;
                size_t doublings;
                const ll_word_params *p = &params[lv.word][c];
                if (lv.owner[c] != c || lv.same[c] != c)
                    continue;
                ll_cost_word_detail(p, n, orders, &work, &doublings, &bytes);
                if (sim_lookup(cache, &clock, lv.word, p, bytes)) {
                    out->layers_built--;
                    out->doublings -= doublings;
                    ll_work_add(&out->work, &work, -1.0);
                }
            }
        }
        /* in memory: the most recently used entries */
        for (k = 0; k < LL_WORD_CACHE_ENTRIES; ++k) {
            size_t j, newer = 0;
            if (!cache[k].full)
                continue;
            for (j = 0; j < LL_WORD_CACHE_ENTRIES; ++j)
                newer += cache[j].full && cache[j].used > cache[k].used;
            if (newer < LL_WORD_CACHE_IN_MEMORY)
                cached += cache[k].bytes;
        }
        /* (A builder's basis is built whole, not streamed.) */
        if (one.held_peak_bytes + cached > peak)
            peak = one.held_peak_bytes + cached;
    }
    for (a = 0; a < m->n_axes; ++a)
        values += m->axes[a].count;
    out->n = n;
    out->m = orders;
    out->channels = nch;
    out->threads = threads;
    stored *= (double)bases;
    out->stored_values = stored;
    out->peak_bytes = peak + WRITER_BUFFER_BYTES + WRITER_PAIR_BYTES * nn * nn +
                      WRITER_LAYER_PAIR_BYTES * (double)n * (double)n +
                      (4.0 * nn + 16.0) * (double)bases;
    out->file_bytes = ll_file_bytes_estimate(n, nch, bases, values, stored);
done:
    ll_free(words);
    ll_free(params);
    return s;
}
