/*
 * llbuild — compile a layered material description into a .bsdf file.
 *
 *     llbuild [options] MATERIAL.layers -o OUT.bsdf
 *
 * A thin program over the public API: ll_material_parse_file, then
 * ll_material_build (progress on stderr, Ctrl-C cancels; the file is
 * written atomically), and a summary read back from the file.
 * Exit codes: 0 done, 1 bad input, 2 I/O, 3 numerical failure or out of
 * memory; an interrupted build ends by its signal and leaves no file.
 */
#define LL_EXPERIMENTAL /* ll_material_estimate */
#include <layerlab.h>

#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "energy.h"
#include "progress.h"
#include "time_model.h"
#ifndef LLBUILD_NO_MAIN
#include "tables.h"
#endif

#define EXIT_BAD_INPUT 1
#define EXIT_IO 2
#define EXIT_NUMERICAL 3

/* Raised by SIGINT / SIGTERM and returned by the monitor of every library
 * call (below), which the library calls at least every 20 ms while it
 * works; its workers then stop at their next poll, so a build ends within
 * about a second. */
static volatile sig_atomic_t cancel_flag;
static volatile sig_atomic_t cancel_signal;

/* The monitor's callback: the progress bar (user, nullable) and the
 * signal flag, which cancels the call. */
static int watch_build(void *user, double fraction, const char *stage)
{
    if (user)
        ll_progress_update(user, fraction, stage);
    return cancel_flag != 0;
}

/* A monitor showing its progress on bar (NULL: only the signal flag). */
static ll_monitor monitor_for(ll_progress *bar)
{
    ll_monitor monitor = LL_MONITOR_INIT;
    monitor.progress = watch_build;
    monitor.user = bar;
    return monitor;
}

static void on_signal(int sig)
{
    cancel_signal = sig;
    cancel_flag = 1;
}

/* From the start, so that no stage runs with the default action (which
 * would leave a temporary file). SA_RESETHAND: a second signal while the
 * build winds down ends the process at once. */
static void catch_signals(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sa.sa_flags = SA_RESETHAND;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
}

static const char usage[] =
    "usage: llbuild [options] MATERIAL.layers -o OUT.bsdf\n"
    "\n"
    "Compile a layered material (a stack of words, top to bottom) into a .bsdf\n"
    "file for pbrt-v3's \"fourier\" material and layerlab's readers.\n"
    "\n"
    "options:\n"
    "  -o, --output FILE  the .bsdf file to write (required unless --dry-run)\n"
    "  --nodes N          zenith-cosine nodes (even; default: the material's `set`,\n"
    "                     else the largest any layer's heuristic asks for)\n"
    "  --orders M         Fourier orders (default: likewise)\n"
    "  --mono, --rgb      force 1 or 3 colour channels (default: RGB if any number\n"
    "                     has three values or a metal is named, else mono)\n"
    "  --error E          series truncation error of the file (default 1e-3)\n"
    "  --tolerance T      relative error the chosen resolution is within, where the\n"
    "                     BSDF is above 1% of its peak (default 0.01; >= 0.001)\n"
    "  --mu-min C         smallest |cosine| the tolerance holds at (default 0.1)\n"
    "  --threads N        worker threads (default: all processors)\n"
    "  --cache-dir DIR    where chosen resolutions are remembered (default:\n"
    "                     $LAYERLAB_CACHE_DIR, else $XDG_CACHE_HOME/layerlab, else\n"
    "                     ~/.cache/layerlab)\n"
    "  --no-cache         search the resolution again and remember nothing\n"
    "  --max-memory SIZE  memory budget: a build estimated to need more is refused\n"
    "                     before it starts (8G, 500M, 1.5G, 64K or bytes; default:\n"
    "                     half of the physical memory)\n"
    "  --ior-dir DIR      where NAME.eta.spd / NAME.k.spd spectra are (sets\n"
    "                     LAYERLAB_IOR_DIR; searched first)\n"
    "  --format NAME      bsdf (the default) or measured: the warped tables that\n"
    "                     Mitsuba 3's and pbrt-v4's `measured` BSDF read (of an\n"
    "                     opaque, unswept stack; a transmissive or swept one gives\n"
    "                     layerlab's extension, which only layerlab reads)\n"
    "  --theta-i N        measured: incident elevations (default: chosen by the\n"
    "                     table tolerance)\n"
    "  --vndf N           measured: side of the visible-normal grid (default: likewise)\n"
    "  --sample N         measured: side of the sample grid (default: likewise)\n"
    "  --table-tolerance T  measured: the sizes not given grow until the table agrees\n"
    "                     with the layers: 99th percentile of f's relative error <= T,\n"
    "                     95th <= 0.4 T, median <= 0.04 T, albedo within 0.06 T\n"
    "                     (default 0.05; a transmissive stack's 99th and 95th:\n"
    "                     0.6 T and 0.2 T)\n"
    "  --wavelengths START:END:STEP  measured: a spectral file (fields spectra and\n"
    "                     wavelengths, which pbrt-v4 needs), e.g. 360:830:10 nm, within\n"
    "                     360..830, at most 471 wavelengths (without it: RGB)\n"
    "  --dry-run          print the resolution, estimated memory and time (choosing\n"
    "                     the resolution included); build nothing\n"
    "  --quiet            no progress and no summary (errors only)\n"
    "  --version          print the version\n"
    "  --help             this text\n"
    "\n";

/* (Two strings: C99 promises string literals of 4095 characters only.) */
static const char usage_language[] =
    "the language (one word per line, top to bottom; `#` starts a comment):\n"
    "  dielectric eta=E alpha=A      rough dielectric interface; eta relative to\n"
    "                                the medium above (1.5: a coat in air)\n"
    "  conductor eta=NAME|n+ki alpha=A  rough metal: a name from the ior folder\n"
    "                                (Au, Ag, Al, Cu, Cr, ...), a complex index, or\n"
    "                                eta=n with k=k; the metal's own index (vacuum)\n"
    "  diffuse albedo=R              Lambertian base\n"
    "  medium albedo=R tau=T [g=G | phase=isotropic | phase=vmf kappa=K]\n"
    "                                scattering slab of optical thickness tau\n"
    "  measured file=PATH            a MERL .binary BRDF (paths relative to the file)\n"
    "  set nodes=N orders=M channels=1|3 error=E tolerance=T mu_min=C   settings\n"
    "Any number may be one value or three (R,G,B). alpha is the roughness (>= 0.001)\n"
    "of the interface's distribution: dist=beckmann (the default) or dist=ggx.\n"
    "Opaque words (conductor, diffuse, measured) must be the bottom.\n"
    "Any number may be a sweep, alpha=[0.02 0.05 0.1] or alpha=[0.05..0.4:8]\n"
    "(strictly increasing; at most 4): the file is then textured, one basis per\n"
    "combination, axes named LABEL.key for a word given name=LABEL, else INDEX.key\n"
    "(the word's 0-based position from the top).\n"
    "Example:\n"
    "  dielectric  eta=1.5 alpha=0.1\n"
    "  medium      albedo=0.25,0.0,0.95 g=0.5 tau=0.5\n"
    "  conductor   eta=Au alpha=0.1\n"
    "\n"
    "exit codes: 0 done, 1 bad input (also a build over the memory budget), 2 I/O\n"
    "error, 3 numerical failure or out of memory; Ctrl-C stops the build, leaves no\n"
    "output file and ends by the signal.\n"
    "See docs/material-language.md for the whole language.\n";

typedef struct args {
    const char *input, *output, *ior_dir, *cache_dir;
    int no_cache;
    size_t nodes, orders, channels, threads, max_memory;
    double error, tolerance, mu_min;
    int dry_run, quiet, nodes_given, orders_given;
} args;

static int exit_code_for(ll_status s)
{
    switch (s) {
    case LL_ERROR_IO:
    case LL_ERROR_FORMAT:
        return EXIT_IO;
    case LL_ERROR_NUMERICAL:
    case LL_ERROR_OUT_OF_MEMORY:
        return EXIT_NUMERICAL;
    default:
        return EXIT_BAD_INPUT;
    }
}

static int bad_usage(const char *what, const char *value)
{
    fprintf(stderr, "llbuild: %s%s%s\n(llbuild --help lists the options)\n", what,
            value ? ": " : "", value ? value : "");
    return EXIT_BAD_INPUT;
}

/* A whole number option value. */
static int parse_size(const char *text, size_t *out)
{
    char *end;
    unsigned long v;
    if (!text || !*text || *text == '-')
        return 0;
    errno = 0;
    v = strtoul(text, &end, 10);
    if (*end || errno)
        return 0;
    *out = (size_t)v;
    return 1;
}

/* A memory size: a number (fractions allowed) with an optional K, M, G or
 * T suffix (powers of 1024), e.g. 8G, 500M, 1.5G, 1048576. */
static int parse_memory(const char *text, size_t *out)
{
    char *end;
    double v, scale = 1.0;
    if (!text || !*text || *text == '-' || *text == '+')
        return 0;
    errno = 0;
    v = strtod(text, &end);
    if (end == text || errno)
        return 0;
    switch (*end) {
    case 'k': case 'K': scale = 1024.0; ++end; break;
    case 'm': case 'M': scale = 1048576.0; ++end; break;
    case 'g': case 'G': scale = 1073741824.0; ++end; break;
    case 't': case 'T': scale = 1099511627776.0; ++end; break;
    default: break;
    }
    if (*end == 'B' || *end == 'b')
        ++end;
    v *= scale;
    if (*end || !(v >= 1.0) || v >= 18446744073709551615.0 || v > (double)(size_t)-1)
        return 0;
    *out = (size_t)v;
    return 1;
}

static int check_resolution(const args *a);

/* Returns -1 to go on, else an exit code. */
static int parse_args(int argc, char **argv, args *a)
{
    int i;
    memset(a, 0, sizeof *a);
    for (i = 1; i < argc; ++i) {
        const char *o = argv[i], *next = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(o, "--help") || !strcmp(o, "-h")) {
            fputs(usage, stdout);
            fputs(usage_language, stdout);
            return 0;
        } else if (!strcmp(o, "--version")) {
            printf("llbuild (layerlab) %s\n", ll_version_string());
            return 0;
        } else if (!strcmp(o, "-o") || !strcmp(o, "--output")) {
            if (!next)
                return bad_usage("-o needs a file name", NULL);
            a->output = next;
            ++i;
        } else if (!strcmp(o, "--nodes") || !strcmp(o, "--orders") ||
                   !strcmp(o, "--threads")) {
            size_t v;
            if (!parse_size(next, &v))
                return bad_usage(o, "expected a whole number");
            if (!strcmp(o, "--nodes"))
                a->nodes = v, a->nodes_given = 1;
            else if (!strcmp(o, "--orders"))
                a->orders = v, a->orders_given = 1;
            else
                a->threads = v;
            ++i;
        } else if (!strcmp(o, "--error")) {
            char *end;
            if (!next)
                return bad_usage("--error needs a value", NULL);
            a->error = strtod(next, &end);
            if (*end || !(a->error > 0.0 && a->error < 1.0))
                return bad_usage("--error: expected a number in (0, 1)", next);
            ++i;
        } else if (!strcmp(o, "--tolerance") || !strcmp(o, "--mu-min")) {
            char *end;
            double v;
            int tolerance = !strcmp(o, "--tolerance");
            if (!next)
                return bad_usage(o, "needs a value");
            v = strtod(next, &end);
            if (*end || (tolerance ? !(v >= LL_MIN_TOLERANCE && v < 1.0) : !(v > 0.0 && v <= 1.0)))
                return bad_usage(tolerance ? "--tolerance: expected a number in [0.001, 1)"
                                           : "--mu-min: expected a cosine in (0, 1]",
                                 next);
            if (tolerance)
                a->tolerance = v;
            else
                a->mu_min = v;
            ++i;
        } else if (!strcmp(o, "--max-memory")) {
            if (!parse_memory(next, &a->max_memory))
                return bad_usage("--max-memory: expected a size such as 8G, 500M, 1.5G or "
                                 "a byte count",
                                 next ? next : "(missing)");
            ++i;
        } else if (!strcmp(o, "--cache-dir")) {
            if (!next || !*next)
                return bad_usage("--cache-dir needs a directory", NULL);
            a->cache_dir = next;
            ++i;
        } else if (!strcmp(o, "--no-cache")) {
            a->no_cache = 1;
        } else if (!strcmp(o, "--ior-dir")) {
            if (!next)
                return bad_usage("--ior-dir needs a directory", NULL);
            a->ior_dir = next;
            ++i;
        } else if (!strcmp(o, "--mono")) {
            a->channels = 1;
        } else if (!strcmp(o, "--rgb")) {
            a->channels = 3;
        } else if (!strcmp(o, "--dry-run")) {
            a->dry_run = 1;
        } else if (!strcmp(o, "--quiet") || !strcmp(o, "-q")) {
            a->quiet = 1;
        } else if (o[0] == '-' && o[1] != '\0') {
            return bad_usage("unknown option", o);
        } else if (a->input) {
            return bad_usage("more than one material given", o);
        } else {
            a->input = o;
        }
    }
    if (!a->input)
        return bad_usage("no material file given", NULL);
    if (!a->output && !a->dry_run)
        return bad_usage("no output file given (-o OUT.bsdf)", NULL);
    return check_resolution(a);
}

/* --nodes and --orders against what a build accepts, said as the rule
 * (checked before anything is read or searched). Returns -1 to go on. */
static int check_resolution(const args *a)
{
    if (a->nodes_given && (a->nodes % 2 || a->nodes < LL_BUILD_MIN_NODES ||
                           a->nodes > LL_BUILD_MAX_RESOLUTION)) {
        size_t lo = a->nodes % 2 ? a->nodes - 1 : a->nodes, hi = lo + 2;
        fprintf(stderr,
                "llbuild: --nodes %zu: the node count must be even, from %d to %d", a->nodes,
                LL_BUILD_MIN_NODES, LL_BUILD_MAX_RESOLUTION);
        if (a->nodes % 2 && lo >= LL_BUILD_MIN_NODES && hi <= LL_BUILD_MAX_RESOLUTION)
            fprintf(stderr, " (--nodes %zu or %zu)", lo, hi);
        fprintf(stderr, "\n");
        return EXIT_BAD_INPUT;
    }
    if (a->orders_given && (a->orders < 1 || a->orders > LL_BUILD_MAX_RESOLUTION)) {
        fprintf(stderr, "llbuild: --orders %zu: the order count must be from 1 to %d\n",
                a->orders, LL_BUILD_MAX_RESOLUTION);
        return EXIT_BAD_INPUT;
    }
    return -1;
}

/* Where the file goes, checked before any work: -o names a file (not a
 * directory) in a directory that exists and that we may write (the
 * library writes a spill file and the output beside each other there).
 * Returns -1 to go on, else the exit code (I/O, as a failed write). */
static int check_output(const char *out)
{
    struct stat st;
    char *dir;
    const char *slash;
    size_t len = strlen(out);
    int code = -1, found;
    if (len == 0 || out[len - 1] == '/' || (stat(out, &st) == 0 && S_ISDIR(st.st_mode))) {
        fprintf(stderr, "llbuild: -o %s names a directory; name the file to write, e.g. -o "
                        "%s%sNAME.bsdf\n",
                out, out, len && out[len - 1] == '/' ? "" : "/");
        return EXIT_IO;
    }
    slash = strrchr(out, '/');
    if (!slash)
        return access(".", W_OK | X_OK) == 0 ? -1
                                              : (fprintf(stderr,
                                                         "llbuild: the current directory is "
                                                         "not writable (%s)\n",
                                                         strerror(errno)),
                                                 EXIT_IO);
    dir = malloc((size_t)(slash - out) + 2);
    if (!dir)
        return EXIT_NUMERICAL;
    memcpy(dir, out, (size_t)(slash - out) + 1);
    /* Shown with its slash; looked at without it (else a file named as
     * the directory reads as missing), except the root itself. */
    dir[slash - out] = '\0';
    found = stat(slash == out ? "/" : dir, &st) == 0;
    dir[slash - out] = '/';
    dir[slash - out + 1] = '\0';
    if (!found) {
        fprintf(stderr, "llbuild: the output directory '%s' does not exist\n", dir);
        code = EXIT_IO;
    } else if (!S_ISDIR(st.st_mode)) {
        fprintf(stderr, "llbuild: the output directory '%s' is not a directory\n", dir);
        code = EXIT_IO;
    } else if (access(dir, W_OK | X_OK) != 0) {
        fprintf(stderr, "llbuild: the output directory '%s' is not writable (%s)\n", dir,
                strerror(errno));
        code = EXIT_IO;
    }
    free(dir);
    return code;
}

#ifndef LLBUILD_NO_MAIN
/* The memory budget for a given node count, before any search: with the
 * orders given, the build's own estimate; with only the nodes, the
 * smallest build at that many nodes (1 order), whose refusal no search can
 * change. Returns -1 to go on. */
static int check_budget(const ll_material *m, const ll_build_options *o)
{
    ll_build_options lowest = *o;
    ll_build_estimate e = LL_BUILD_ESTIMATE_INIT;
    if (!o->n_nodes)
        return -1;
    if (!lowest.n_orders)
        lowest.n_orders = 1;
    if (ll_material_axis_count(m) > 0 || ll_material_estimate(m, &lowest, &e, NULL) != LL_OK ||
        !e.over_budget)
        return -1;
    fprintf(stderr,
            "llbuild: %zu nodes x %zu order%s%s needs about %.0f MiB at its peak, more than the "
            "memory budget of %.0f MiB (raise it with --max-memory SIZE, or lower the "
            "resolution)\n",
            lowest.n_nodes, lowest.n_orders, lowest.n_orders == 1 ? "" : "s",
            o->n_orders ? "" : " (the fewest orders)", e.peak_bytes / 1048576.0,
            (double)e.max_memory_bytes / 1048576.0);
    return EXIT_BAD_INPUT;
}
#endif /* LLBUILD_NO_MAIN */

static double now_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* CPU seconds of the process so far (every thread). */
static double cpu_seconds(void)
{
    struct timespec t;
    if (clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t) != 0)
        return 0.0;
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* The axes of a swept material, one line each. */
static void print_axes(const ll_material *m)
{
    size_t k, n = ll_material_axis_count(m);
    for (k = 0; k < n; ++k) {
        ll_material_axis axis = LL_MATERIAL_AXIS_INIT;
        if (ll_material_get_axis(m, k, &axis) != LL_OK)
            continue;
        printf("axis %zu       %s: %zu values, %g to %g\n", k, axis.name, axis.n_values,
               axis.positions[0], axis.positions[axis.n_values - 1]);
    }
}

/* The nodes and orders were given (set nodes= orders=, --nodes --orders),
 * not chosen by the tolerance. */
static int resolution_given(const ll_material *m, const ll_build_options *o)
{
    double tolerance = 0.0, mu_min = 0.0;
    int chosen = 0;
    return ll_material_goal(m, o, &tolerance, &mu_min, &chosen) == LL_OK && !chosen;
}

/* The goal the resolution met: the tolerance and the error measured
 * (ll_build_estimate.resolution_error: against twice the resolution, HUGE_VAL
 * when some word is beyond the search's reach), or that it was given.
 * choose_seconds < 0: not timed. */
static void print_goal(const ll_material *m, const ll_build_options *o, size_t n, size_t orders,
                       double error, double choose_seconds)
{
    double tolerance = 0.0, mu_min = 0.0;
    int chosen = 0;
    char timed[64] = "";
    if (ll_material_goal(m, o, &tolerance, &mu_min, &chosen) != LL_OK)
        return;
    if (choose_seconds >= 0.0)
        snprintf(timed, sizeof timed, ", %.2f s", choose_seconds);
    if (!chosen)
        printf("tolerance    not checked: the resolution is given (set nodes= orders=, or "
               "--nodes --orders)\n");
    else if (error >= 0.0 && error <= tolerance)
        printf("tolerance    %g (relative, where the BSDF is above 1%% of its peak, |mu| >= "
               "%g): met by %zu nodes x %zu orders, %.2g against twice that resolution "
               "(every word's lobes probed%s)\n",
               tolerance, mu_min, n, orders, error, timed);
    else
        printf("tolerance    %g (|mu| >= %g): NOT verified at %zu nodes x %zu orders: a word "
               "is beyond the resolution search's reach (|g| > 0.95, more than 8000 nodes, or "
               "a measured table sharper than its cells), so its heuristic's answer is used%s; "
               "give the resolution with --nodes --orders to choose it yourself\n",
               tolerance, mu_min, n, orders, timed);
}

/* The monitor of the resolution's choice: the bar (nullable) shows the
 * searches' own progress ("resolution 2/5": the second of five words to
 * probe), and only that (a choice from the cache or the options reports
 * no search). */
static int watch_choice(void *user, double fraction, const char *stage)
{
    if (user && strncmp(stage, "resolution", 10) == 0)
        ll_progress_update(user, fraction, stage);
    return cancel_flag != 0;
}

/* Choose the resolution once, before the build (the build then does not
 * search again): plan receives the estimate, o the chosen nodes and orders
 * when the estimate succeeds (a failure is left for the build to report).
 * bar (nullable) shows the searches' progress, then starts again for the
 * build. Returns the seconds it took. */
static double choose_resolution(const ll_material *m, ll_build_options *o,
                                ll_build_estimate *plan, ll_progress *bar)
{
    double start = now_seconds(), scale = bar ? bar->scale : 1.0;
    ll_monitor choice = LL_MONITOR_INIT;
    ll_status s;
    choice.progress = watch_choice;
    choice.user = bar;
    if (bar)
        bar->scale = 1.0; /* (the search's own fraction) */
    s = ll_material_estimate(m, o, plan, &choice);
    if (bar) {
        ll_progress_init(bar, bar->out, bar->quiet, now_seconds());
        bar->scale = scale;
    }
    if (s == LL_OK) {
        o->n_nodes = plan->n_nodes;
        o->n_orders = plan->n_orders;
    } else {
        plan->n_nodes = 0;
    }
    return now_seconds() - start;
}

/* --dry-run: the estimate; exit 1 when a build would be refused. */
static int print_resolution(const ll_material *m, const ll_build_options *o)
{
    ll_build_estimate e = LL_BUILD_ESTIMATE_INIT;
    ll_monitor signals = monitor_for(NULL);
    double start = now_seconds(), start_cpu = cpu_seconds(), wall, cpu, choose_wall, choose_cpu;
    ll_status s = ll_material_estimate(m, o, &e, &signals);
    /* The estimate's own cost is the choice of the resolution (the
     * searches, or looking them up in the cache): measured, not modelled. */
    choose_wall = now_seconds() - start;
    choose_cpu = cpu_seconds() - start_cpu;
    if (s != LL_OK) {
        fprintf(stderr, "llbuild: %s\n", ll_last_error_message());
        return exit_code_for(s);
    }
    printf("resolution   %zu nodes x %zu Fourier orders, %zu channel%s\n", e.n_nodes,
           e.n_orders, e.n_channels, e.n_channels == 1 ? "" : "s");
    print_goal(m, o, e.n_nodes, e.n_orders, e.resolution_error, choose_wall);
    if (ll_material_axis_count(m) > 0) {
        print_axes(m);
        printf("bases        %zu (one textured file)\n", e.n_bases);
    }
    printf("file         about %.2f MiB\n", e.file_bytes / 1048576.0);
    printf("work         %zu layer%s built, %zu addition%s, %zu doubling%s\n", e.layers_built,
           e.layers_built == 1 ? "" : "s", e.additions, e.additions == 1 ? "" : "s",
           e.doublings, e.doublings == 1 ? "" : "s");
    printf("memory       about %.0f MiB at its peak (budget %.0f MiB)\n",
           e.peak_bytes / 1048576.0, (double)e.max_memory_bytes / 1048576.0);
    llbuild_time(&e, &wall, &cpu);
    /* The whole build: the model's figure for building and writing, and
     * the choice of the resolution as it just ran. */
    printf("time         about %.2f s on %zu thread%s, %.2f s of CPU: building %.2f s of CPU "
           "(modelled on the rates of a 2-core x86-64 with OpenBLAS) + choosing the "
           "resolution %.2f s of CPU (measured now)\n",
           wall + choose_wall, e.threads, e.threads == 1 ? "" : "s", cpu + choose_cpu, cpu,
           choose_cpu);
    if (o->cache_dir && choose_cpu >= 0.1)
        printf("cache        the choice is remembered in %s: a build with these options now "
               "skips it\n",
               o->cache_dir);
    if (e.over_budget) {
        fprintf(stderr,
                "llbuild: a build would be refused: it needs more than the memory budget "
                "(raise it with --max-memory SIZE, or lower the resolution)\n");
        return EXIT_BAD_INPUT;
    }
    return 0;
}

/* A build refused by the memory budget before it started is a request
 * beyond what the options allow (bad input), not a failure to allocate. */
static int refused_by_budget(const ll_material *m, const ll_build_options *o)
{
    ll_build_estimate e = LL_BUILD_ESTIMATE_INIT;
    ll_monitor signals = monitor_for(NULL);
    return ll_material_estimate(m, o, &e, &signals) == LL_OK && e.over_budget;
}

/* Directional albedo of the built layers at a few incident angles. */
/* What the summary shows of each channel's finished layer, taken while
 * the build streams it to the file (ll_build_options.channel_done): the
 * library frees each stack once it is written. */
static const double summary_degrees[4] = { 0.0, 30.0, 60.0, 80.0 };

typedef struct channel_summary {
    size_t n_nodes, n_orders, n_channels;
    double R[3][4], T[3][4];
} channel_summary;

static void remember_channel(void *user, size_t channel, const ll_layer *layer)
{
    channel_summary *sum = user;
    size_t a;
    if (channel >= 3)
        return;
    sum->n_nodes = ll_layer_node_count(layer);
    sum->n_orders = ll_layer_order_count(layer);
    if (channel + 1 > sum->n_channels)
        sum->n_channels = channel + 1;
    for (a = 0; a < 4; ++a)
        ll_layer_albedo(layer, cos(summary_degrees[a] * 3.14159265358979323846 / 180.0),
                        &sum->R[channel][a], &sum->T[channel][a]);
}

static void print_albedo(const channel_summary *sum, int transmissive)
{
    size_t a, c, n_channels = sum->n_channels;
    printf("albedo       %s%s\n", n_channels == 3 ? "(R G B) " : "",
           transmissive ? "reflected | transmitted" : "reflected");
    for (a = 0; a < 4; ++a) {
        printf("  %4.0f deg  ", summary_degrees[a]);
        for (c = 0; c < n_channels; ++c)
            printf(" %.4f", sum->R[c][a]);
        if (transmissive) {
            printf("  |");
            for (c = 0; c < n_channels; ++c)
                printf(" %.4f", sum->T[c][a]);
        }
        printf("\n");
    }
}

static void print_summary(const args *a, const ll_material *m, const ll_build_options *o,
                          const ll_build_estimate *plan, const channel_summary *sum,
                          double seconds)
{
    ll_bsdf *b = NULL;
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    if (ll_bsdf_open(a->output, NULL, &b) != LL_OK || ll_bsdf_get_info(b, &info) != LL_OK) {
        fprintf(stderr, "llbuild: cannot read back %s: %s\n", a->output,
                ll_last_error_message());
        ll_bsdf_release(b);
        return;
    }
    printf("%s -> %s\n", a->input, a->output);
    printf("resolution   %zu nodes x %zu Fourier orders, %zu channel%s\n",
           sum->n_nodes, sum->n_orders, sum->n_channels, sum->n_channels == 1 ? "" : "s");
    if (plan->n_nodes)
        print_goal(m, o, plan->n_nodes, plan->n_orders, plan->resolution_error, -1.0);
    printf("orders kept  %zu (longest series in the file)\n", info.max_order);
    printf("file         %zu bytes, %zu coefficients\n", info.file_size, info.n_coeffs);
    printf("header       eta %g, alpha %g (top) %g (bottom)\n", info.eta, info.alpha[0],
           info.alpha[1]);
    /* From the stack, not the header's eta: a pane (glass between two
     * airs) has eta 1 and transmits most of the light. */
    print_albedo(sum, ll_material_transmits(m));
    printf("wall time    %.2f s\n", seconds);
    ll_bsdf_release(b);
    fflush(stdout);
    llbuild_warn_energy(stderr, a->output, resolution_given(m, o));
}

static void print_textured_summary(const args *a, const ll_material *m,
                                   const ll_build_options *o, const ll_build_estimate *plan,
                                   double seconds)
{
    ll_bsdf *b = NULL;
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    if (ll_bsdf_open(a->output, NULL, &b) != LL_OK || ll_bsdf_get_info(b, &info) != LL_OK) {
        fprintf(stderr, "llbuild: cannot read back %s: %s\n", a->output,
                ll_last_error_message());
        ll_bsdf_release(b);
        return;
    }
    printf("%s -> %s\n", a->input, a->output);
    print_axes(m);
    printf("bases        %zu (textured file, %zu parameter%s)\n", info.n_bases,
           info.n_parameters, info.n_parameters == 1 ? "" : "s");
    printf("resolution   %zu file nodes, %zu channel%s\n", info.n_nodes, info.n_channels,
           info.n_channels == 1 ? "" : "s");
    if (plan->n_nodes)
        print_goal(m, o, plan->n_nodes, plan->n_orders, plan->resolution_error, -1.0);
    printf("orders kept  %zu (longest series in the file)\n", info.max_order);
    printf("file         %zu bytes, %zu coefficients\n", info.file_size, info.n_coeffs);
    printf("wall time    %.2f s\n", seconds);
    ll_bsdf_release(b);
    fflush(stdout);
    llbuild_warn_energy(stderr, a->output, resolution_given(m, o));
}

/* Stop: no file was written. End by the signal, so that the shell sees
 * it ($? = 128 + 2 = 130 for SIGINT, 143 for SIGTERM) and a script that ran
 * llbuild stops too; 128 + sig should raise return. */
static int die_cancelled(void)
{
    int sig = cancel_signal ? cancel_signal : SIGINT;
    fprintf(stderr, "llbuild: interrupted; no file written\n");
    fflush(stderr);
    signal(sig, SIG_DFL);
    raise(sig);
    return 128 + sig;
}

/* llbuild-mpi (tools/llbuild-mpi) includes this file for the options,
 * messages and summary above and brings its own main. */
/* The file is complete: from here on a signal just ends the program
 * (reading the file back for the summary is not worth waiting for), and one
 * that came during the last step ends it now (llbuild and llbuild-mpi). */
static void file_is_complete(void)
{
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    if (cancel_flag)
        raise(cancel_signal ? cancel_signal : SIGINT);
}

/* The build options the command line asks for (llbuild and llbuild-mpi):
 * the cache of chosen resolutions in the user's cache directory unless
 * --no-cache (none when no directory can be named). */
static void options_from_args(const args *a, ll_build_options *o)
{
    static char cache_dir[4096];
    if (a->no_cache)
        o->cache_dir = NULL;
    else if (a->cache_dir)
        o->cache_dir = a->cache_dir;
    else
        o->cache_dir = ll_material_cache_dir(cache_dir, sizeof cache_dir) == LL_OK ? cache_dir
                                                                                   : NULL;
    o->n_nodes = a->nodes;
    o->n_orders = a->orders;
    o->n_channels = a->channels;
    o->threads = a->threads;
    o->error_goal = a->error;
    o->max_memory_bytes = a->max_memory;
    o->tolerance = a->tolerance;
    o->mu_min = a->mu_min;
}

#ifndef LLBUILD_NO_MAIN
int main(int argc, char **argv)
{
    args a;
    ll_material *m = NULL;
    ll_build_options o = LL_BUILD_OPTIONS_INIT, built;
    ll_build_estimate plan = LL_BUILD_ESTIMATE_INIT;
    channel_summary summary;
    llbuild_tables tables;
    ll_progress bar;
    ll_monitor monitor = monitor_for(&bar);
    double start = now_seconds();
    ll_status s;
    int code;

    catch_signals();
    code = llbuild_tables_take_args(&argc, argv, &tables);
    if (code >= 0)
        return code;
    code = parse_args(argc, argv, &a);
    if (code >= 0)
        return code;
    if (a.ior_dir && setenv("LAYERLAB_IOR_DIR", a.ior_dir, 1) != 0)
        return bad_usage("cannot set LAYERLAB_IOR_DIR", NULL);
    /* Everything that can be checked before the work is checked first. */
    if (a.output && (code = check_output(a.output)) >= 0)
        return code;
    s = ll_material_parse_file(a.input, &m);
    if (s != LL_OK) {
        fprintf(stderr, "llbuild: %s\n", ll_last_error_message());
        return exit_code_for(s);
    }
    code = llbuild_tables_check(&tables, m, a.input);
    if (code >= 0) {
        ll_material_destroy(m);
        return code;
    }
    options_from_args(&a, &o);
    if (!a.dry_run && (code = check_budget(m, &o)) >= 0) {
        ll_material_destroy(m);
        return code;
    }
    if (cancel_flag) {
        ll_material_destroy(m);
        return die_cancelled();
    }
    if (a.dry_run) {
        code = print_resolution(m, &o);
        if (code == 0)
            llbuild_tables_dry_run(&tables);
        ll_material_destroy(m);
        return cancel_flag ? die_cancelled() : code;
    }

    ll_progress_init(&bar, stderr, a.quiet, start);
    /* Writing a file takes a few percent of a build. */
    bar.scale = 0.97;
    built = o;
    ll_progress_update(&bar, 0.0, "choosing the resolution");
    choose_resolution(m, &built, &plan, &bar);
    if (tables.measured) {
        /* The table file instead of the .bsdf (tables.c). */
        bar.scale = 1.0;
        s = llbuild_tables_build(&tables, m, &built, &monitor, a.output);
    } else if (ll_material_axis_count(m) > 0) {
        /* A swept material: its bases one at a time into one textured file
         * (the bar shows "basis 3/64: ..."); the library writes it. */
        bar.scale = 1.0;
        s = ll_material_build(m, &built, &monitor, a.output);
    } else {
        /* Each channel goes to the file as soon as its stack is complete
         * (the summary's albedo is taken from it on the way). */
        memset(&summary, 0, sizeof summary);
        built.channel_done = remember_channel;
        built.channel_done_user = &summary;
        bar.scale = 1.0;
        s = ll_material_build(m, &built, &monitor, a.output);
    }
    if (s == LL_OK)
        file_is_complete();
    ll_progress_finish(&bar, s == LL_OK);
    if (s == LL_ERROR_CANCELLED) {
        /* (A signal after the file was complete is too late to matter: the
         * file is whole and stays.) */
        code = -1;
    } else if (s != LL_OK) {
        fprintf(stderr, "llbuild: %s\n", ll_last_error_message());
        code = s == LL_ERROR_OUT_OF_MEMORY && refused_by_budget(m, &o) ? EXIT_BAD_INPUT
                                                                         : exit_code_for(s);
    } else {
        if (!a.quiet && tables.measured)
            llbuild_tables_summary(&tables, a.input, a.output, now_seconds() - start);
        else if (!a.quiet && ll_material_axis_count(m) > 0)
            print_textured_summary(&a, m, &o, &plan, now_seconds() - start);
        else if (!a.quiet)
            print_summary(&a, m, &o, &plan, &summary, now_seconds() - start);
        code = 0;
    }
    ll_material_destroy(m);
    return code >= 0 ? code : die_cancelled();
}
#endif /* LLBUILD_NO_MAIN */
