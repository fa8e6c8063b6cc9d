/*
 * llbuild-mpi — llbuild across MPI ranks, for builds that outgrow one
 * machine (docs/mpi.md):
 *
 *     mpirun -n N llbuild-mpi [llbuild options] MATERIAL.layers -o OUT.bsdf
 *
 * The same options, messages, summary and exit codes as llbuild, whose
 * source it includes for them (tools/llbuild/llbuild.c without its main),
 * so the two cannot drift apart. One material is built by
 * ll_material_build_layers_distributed over an MPI ll_distribution
 * (mpi_hook.c: its Fourier orders split between the ranks), a textured one
 * basis by basis across the ranks (textured.c); rank 0 prints, shows the progress and writes the file
 * with ll_material_write, byte for byte llbuild's for every N. Every
 * outcome is agreed between the ranks, so all exit with the same code; a
 * dead rank makes mpirun end the others, and no file is left (rank 0
 * writes only once it holds the whole stack, through the atomic writer).
 */
#define LLBUILD_NO_MAIN
/* Helpers of llbuild's own main that this main does not call. */
#pragma GCC diagnostic ignored "-Wunused-function"
#include "../llbuild/llbuild.c"
#pragma GCC diagnostic warning "-Wunused-function"

#include "mpi_hook.h"
#include "textured.h"

#include <mpi.h>

#define MESSAGE_SIZE 1200

/* Ranks other than 0 print nothing: what goes wrong on them reaches rank
 * 0 through the agreements, and rank 0 says it once. */
static void silence_other_ranks(int rank)
{
    if (rank != 0) {
        if (!freopen("/dev/null", "w", stdout) || !freopen("/dev/null", "w", stderr))
            return;
    }
}

/* llbuild's refused_by_budget, for the share of each rank. */
static int refused_per_rank(const ll_material *m, const ll_build_options *o, int ranks)
{
    ll_build_estimate e = LL_BUILD_ESTIMATE_INIT;
    ll_monitor signals = monitor_for(NULL);
    return ll_material_estimate(m, o, &e, &signals) == LL_OK &&
           e.peak_bytes / (double)ranks > (double)e.max_memory_bytes;
}

static int finish(int code)
{
    MPI_Finalize();
    return code >= 0 ? code : die_cancelled();
}

int main(int argc, char **argv)
{
    args a;
    ll_material *m = NULL;
    ll_build_options o = LL_BUILD_OPTIONS_INIT, built;
    ll_build_estimate plan = LL_BUILD_ESTIMATE_INIT;
    ll_layer *layers[3] = { NULL, NULL, NULL };
    ll_distribution dist;
    size_t n_channels = 0, c;
    ll_progress bar;
    ll_monitor monitor = monitor_for(&bar);
    mpi_job job;
    char message[MESSAGE_SIZE];
    double start = now_seconds(), sent = 0.0;
    unsigned long transfers = 0;
    ll_status s;
    int code, textured;

    job.bytes_sent = 0.0;
    job.calls = 0;
    if (MPI_Init(&argc, &argv) != MPI_SUCCESS) {
        fprintf(stderr, "llbuild-mpi: MPI_Init failed\n");
        return EXIT_IO;
    }
    MPI_Comm_rank(MPI_COMM_WORLD, &job.rank);
    MPI_Comm_size(MPI_COMM_WORLD, &job.size);
    silence_other_ranks(job.rank);
    catch_signals();
    /* The arguments are the same on every rank: so is this outcome. */
    code = parse_args(argc, argv, &a);
    if (code >= 0)
        return finish(code);
    if (a.ior_dir && setenv("LAYERLAB_IOR_DIR", a.ior_dir, 1) != 0)
        return finish(bad_usage("cannot set LAYERLAB_IOR_DIR", NULL));
    /* Where rank 0 will write, checked before any work. */
    code = job.rank == 0 && a.output ? check_output(a.output) : -1;
    MPI_Bcast(&code, 1, MPI_INT, 0, MPI_COMM_WORLD);
    if (code >= 0)
        return finish(code);
    /* Every rank reads the material (across machines, each its own copy). */
    s = mpi_agree(&job, ll_material_parse_file(a.input, &m), NULL, message, sizeof message);
    if (s != LL_OK) {
        fprintf(stderr, "llbuild: %s\n", message);
        ll_material_destroy(m);
        return finish(exit_code_for(s));
    }
    options_from_args(&a, &o);
    textured = ll_material_axis_count(m) > 0;
    if (a.dry_run) {
        if (job.rank == 0) {
            code = print_resolution(m, &o);
            if (code == 0)
                printf("per rank     about 1/%d of the layers' memory on each of %d ranks\n",
                       job.size, job.size);
        }
        MPI_Bcast(&code, 1, MPI_INT, 0, MPI_COMM_WORLD);
        ll_material_destroy(m);
        return finish(cancel_flag ? -1 : code);
    }

    ll_progress_init(&bar, stderr, a.quiet || job.rank != 0, start);
    bar.scale = 0.97;
    mpi_distribution(&job, &dist);
    /* Every rank chooses the same resolution (the search is deterministic). */
    built = o;
    ll_progress_update(&bar, 0.0, "choosing the resolution");
    choose_resolution(m, &built, &plan, &bar);
    if (textured) {
        /* Bases across the ranks (textured.c); the bar shows the bases
         * written, not each basis's own progress. */
        bar.scale = 1.0;
        s = textured_build(&job, m, &built, a.output, &cancel_flag,
                           job.rank == 0 ? &monitor : NULL, message, sizeof message);
    } else {
        /* (Each rank's monitor sees its signal flag: a cancel on any rank
         * stops all.) */
        s = ll_material_build_layers_distributed(m, &built, &monitor, &dist, layers,
                                                 &n_channels, NULL);
        snprintf(message, sizeof message, "%s", ll_last_error_message());
    }
    /* The bytes all ranks sent, for the summary. */
    MPI_Reduce(&job.bytes_sent, &sent, 1, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
    MPI_Reduce(&job.calls, &transfers, 1, MPI_UNSIGNED_LONG, MPI_SUM, 0, MPI_COMM_WORLD);
    if (s == LL_OK && !textured) {
        bar.scale = 1.0;
        ll_progress_update(&bar, 0.97, "writing");
        if (job.rank == 0)
            s = ll_material_write(m, &built, layers, n_channels, a.output, &monitor);
        s = mpi_agree(&job, s, NULL, message, sizeof message);
    }
    if (s == LL_OK)
        file_is_complete();
    ll_progress_finish(&bar, s == LL_OK);
    if (s == LL_ERROR_CANCELLED) {
        code = -1;
    } else if (s != LL_OK) {
        fprintf(stderr, "llbuild: %s\n", message);
        code = s == LL_ERROR_OUT_OF_MEMORY && refused_per_rank(m, &o, job.size)
                   ? EXIT_BAD_INPUT
                   : exit_code_for(s);
    } else {
        if (!a.quiet && job.rank == 0) {
            if (textured)
                print_textured_summary(&a, m, &o, &plan, now_seconds() - start);
            else {
                channel_summary sum;
                memset(&sum, 0, sizeof sum);
                for (c = 0; c < n_channels; ++c)
                    remember_channel(&sum, c, layers[c]);
                print_summary(&a, m, &o, &plan, &sum, now_seconds() - start);
            }
            printf("ranks        %d (MPI): %.1f MiB sent between them in %lu transfers\n",
                   job.size, sent / 1048576.0, transfers);
        }
        code = 0;
    }
    for (c = 0; c < 3; ++c)
        ll_layer_destroy(layers[c]);
    ll_material_destroy(m);
    return finish(code);
}
