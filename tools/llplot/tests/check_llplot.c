/*
 * Tests of the llplot program, run by tests/llplot.sh:
 *     check_llplot PATH/TO/llplot WORK_DIR
 * They write small .bsdf and material files through the public API, run
 * llplot on them, and read the pictures back independently: EXR files with
 * the OpenEXR C API (size, channels, values against closed forms), PNG
 * files with cairo (size, backdrop vs. sphere). Kept small: the whole run
 * takes a few seconds, also under ASan + UBSan.
 *
 * (This file is not part of the llplot program, which the Makefile builds
 * from the .c files directly in tools/llplot/; and the Makefile's cmocka
 * rule links neither OpenEXR nor cairo, so the script builds the checker.)
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <cairo.h>
#include <dirent.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <layerlab.h>

#include "../scene.h"

#if defined(__GNUC__)
#  pragma GCC diagnostic push
#  pragma GCC diagnostic ignored "-Wpedantic"
#endif
#include <openexr.h>
#if defined(__GNUC__)
#  pragma GCC diagnostic pop
#endif

#define PI 3.14159265358979323846

static const char *llplot_path;
static const char *work_dir;
static const double albedo[3] = { 0.8, 0.5, 0.2 };

/* ---------------------------------------------------------------- helpers */

static void path_in_work(char *out, size_t size, const char *name)
{
    snprintf(out, size, "%s/%s", work_dir, name);
}

/* Run llplot with the NULL-terminated arguments; its stderr goes to
 * WORK_DIR/stderr.txt, its stdout nowhere. Returns the exit status. */
static int run_llplot(const char *first, ...)
{
    const char *argv[40];
    char err_path[4096];
    va_list ap;
    int n = 0, status = 0;
    pid_t pid;
    argv[n++] = llplot_path;
    va_start(ap, first);
    for (argv[n] = first; argv[n] && n < 38; argv[++n] = va_arg(ap, const char *))
        ;
    va_end(ap);
    argv[n] = NULL;
    path_in_work(err_path, sizeof err_path, "stderr.txt");
    pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        int fd = open(err_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        int null = open("/dev/null", O_WRONLY);
        if (fd >= 0) {
            dup2(fd, 2);
            close(fd);
        }
        if (null >= 0) {
            dup2(null, 1);
            close(null);
        }
        execv(llplot_path, (char *const *)argv);
        _exit(127);
    }
    assert_int_equal(waitpid(pid, &status, 0), pid);
    assert_true(WIFEXITED(status));
    return WEXITSTATUS(status);
}

static void read_stderr(char *buf, size_t size)
{
    char path[4096];
    FILE *f;
    size_t n;
    path_in_work(path, sizeof path, "stderr.txt");
    f = fopen(path, "r");
    assert_non_null(f);
    n = fread(buf, 1, size - 1, f);
    buf[n] = '\0';
    fclose(f);
}

static int file_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

/* No temporary output file may stay behind in the work directory. */
static void assert_no_temporaries(void)
{
    DIR *d = opendir(work_dir);
    struct dirent *e;
    assert_non_null(d);
    while ((e = readdir(d)) != NULL)
        if (strstr(e->d_name, ".tmp-"))
            fail_msg("temporary file left behind: %s", e->d_name);
    closedir(d);
}

/* Gauss-Lobatto nodes as a layer needs them: the end points +-1 are nodes,
 * so every direction lies inside the node range of the file. */
#define DIFFUSE_NODES 32

/* A Lambertian .bsdf of the per-channel albedo above. */
static void write_diffuse_bsdf(const char *path)
{
    double nodes[DIFFUSE_NODES], weights[DIFFUSE_NODES];
    ll_layer *layers[3];
    int k;
    assert_int_equal(ll_quad_gauss_lobatto(DIFFUSE_NODES, nodes, weights, NULL), LL_OK);
    for (k = 0; k < 3; ++k) {
        assert_int_equal(ll_layer_create(nodes, weights, DIFFUSE_NODES, 1, &layers[k]), LL_OK);
        assert_int_equal(ll_layer_set_diffuse(layers[k], albedo[k], NULL), LL_OK);
    }
    assert_int_equal(ll_bsdf_write(path, (const ll_layer *const *)layers, 3, NULL, NULL), LL_OK);
    for (k = 0; k < 3; ++k)
        ll_layer_destroy(layers[k]);
}

/* A .bsdf file holds no series at its two mu = 0 nodes (the format's
 * convention), and its Catmull-Rom splines reach two nodes to each side:
 * for light arriving closer to grazing than the second positive node, a
 * file of a Lambertian layer is only nearly Lambertian (it falls to 0 at
 * grazing and overshoots by a few percent next to that). The checks of
 * files leave that strip out; the layers themselves are exact. */
static double diffuse_grazing_limit(void)
{
    double nodes[DIFFUSE_NODES], weights[DIFFUSE_NODES];
    assert_int_equal(ll_quad_gauss_lobatto(DIFFUSE_NODES, nodes, weights, NULL), LL_OK);
    return nodes[DIFFUSE_NODES / 2 + 1];
}

static void diffuse_path(char *out, size_t size)
{
    path_in_work(out, size, "diffuse.bsdf");
    if (!file_exists(out))
        write_diffuse_bsdf(out);
}

/* A textured Lambertian file (monochrome) over two parameters, "albedo"
 * sampled at 0 and 1 (albedo 0.2 and 0.8) and "dim" sampled at 0 and 1
 * (the albedo times 1 and 0.5), written with its parameter names. Its
 * BSDF is linear in both weights: at (a, d) the albedo is
 * (0.2 + 0.6 a) (1 - 0.5 d). */
static double textured_albedo(double a, double d) { return (0.2 + 0.6 * a) * (1.0 - 0.5 * d); }

static void textured_path(char *out, size_t size)
{
    double nodes[DIFFUSE_NODES], weights[DIFFUSE_NODES];
    const double positions[4] = { 0.0, 1.0, 0.0, 1.0 };
    const size_t counts[2] = { 2, 2 };
    ll_layer *layers[4];
    ll_bsdf_write_options opts = LL_BSDF_WRITE_OPTIONS_INIT;
    int k;
    path_in_work(out, size, "textured.bsdf");
    if (file_exists(out))
        return;
    opts.metadata = "{\"parameters\": [\"albedo\", \"dim\"]}";
    assert_int_equal(ll_quad_gauss_lobatto(DIFFUSE_NODES, nodes, weights, NULL), LL_OK);
    for (k = 0; k < 4; ++k) { /* parameter 0 fastest */
        assert_int_equal(ll_layer_create(nodes, weights, DIFFUSE_NODES, 1, &layers[k]), LL_OK);
        assert_int_equal(ll_layer_set_diffuse(layers[k], textured_albedo(k % 2, k / 2), NULL), LL_OK);
    }
    assert_int_equal(ll_bsdf_write_textured(out, (const ll_layer *const *)layers, 1, 2, counts,
                                            positions, &opts, NULL),
                     LL_OK);
    for (k = 0; k < 4; ++k)
        ll_layer_destroy(layers[k]);
}

/* ------------------------------------------------------------ EXR reader */

typedef struct exr_picture {
    int width, height, n_channels;
    char names[8][16];
    float *data; /* planar: channel c, row y, column x */
} exr_picture;

static float exr_at(const exr_picture *p, const char *name, int x, int y)
{
    int c;
    for (c = 0; c < p->n_channels; ++c)
        if (strcmp(p->names[c], name) == 0)
            return p->data[((size_t)c * p->height + y) * p->width + x];
    fail_msg("no channel %s", name);
    return 0.0f;
}

static void read_exr(const char *path, exr_picture *p)
{
    exr_context_t ctxt;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    const exr_attr_chlist_t *channels = NULL;
    exr_attr_box2i_t box;
    exr_decode_pipeline_t dec;
    int32_t lines = 0;
    int y, c, initialised = 0;
    assert_int_equal(exr_start_read(&ctxt, path, &init), EXR_ERR_SUCCESS);
    assert_int_equal(exr_get_data_window(ctxt, 0, &box), EXR_ERR_SUCCESS);
    p->width = box.max.x - box.min.x + 1;
    p->height = box.max.y - box.min.y + 1;
    assert_int_equal(exr_get_channels(ctxt, 0, &channels), EXR_ERR_SUCCESS);
    p->n_channels = channels->num_channels;
    assert_true(p->n_channels <= 8);
    for (c = 0; c < p->n_channels; ++c) {
        snprintf(p->names[c], sizeof p->names[c], "%s", channels->entries[c].name.str);
        assert_int_equal(channels->entries[c].pixel_type, EXR_PIXEL_FLOAT);
    }
    p->data = calloc((size_t)p->width * p->height * p->n_channels, sizeof(float));
    assert_non_null(p->data);
    assert_int_equal(exr_get_scanlines_per_chunk(ctxt, 0, &lines), EXR_ERR_SUCCESS);
    memset(&dec, 0, sizeof dec);
    for (y = box.min.y; y <= box.max.y; y += lines) {
        exr_chunk_info_t cinfo;
        assert_int_equal(exr_read_scanline_chunk_info(ctxt, 0, y, &cinfo), EXR_ERR_SUCCESS);
        if (!initialised)
            assert_int_equal(exr_decoding_initialize(ctxt, 0, &cinfo, &dec), EXR_ERR_SUCCESS);
        else
            assert_int_equal(exr_decoding_update(ctxt, 0, &cinfo, &dec), EXR_ERR_SUCCESS);
        for (c = 0; c < dec.channel_count; ++c) {
            int index, k;
            for (index = 0, k = 0; k < p->n_channels; ++k)
                if (strcmp(p->names[k], dec.channels[c].channel_name) == 0)
                    index = k;
            dec.channels[c].decode_to_ptr =
                (uint8_t *)(p->data + ((size_t)index * p->height + (y - box.min.y)) * p->width);
            dec.channels[c].user_pixel_stride = 4;
            dec.channels[c].user_line_stride = 4 * p->width;
            dec.channels[c].user_bytes_per_element = 4;
            dec.channels[c].user_data_type = EXR_PIXEL_FLOAT;
        }
        if (!initialised) {
            assert_int_equal(exr_decoding_choose_default_routines(ctxt, 0, &dec),
                             EXR_ERR_SUCCESS);
            initialised = 1;
        }
        assert_int_equal(exr_decoding_run(ctxt, 0, &dec), EXR_ERR_SUCCESS);
    }
    exr_decoding_destroy(ctxt, &dec);
    exr_finish(&ctxt);
}

/* ------------------------------------------------------------------ tests */

/* ------------------------------------------------- the expected sphere */

#define SPHERE_SIZE 40
#define SUBPIXELS 8      /* per axis, for the pixel integral of the closed form */
#define IRRADIANCE_TABLE 2001

/* The environment's irradiance depends on n_y alone: tabulate it. */
static void irradiance_table(double table[IRRADIANCE_TABLE][3])
{
    int k;
    for (k = 0; k < IRRADIANCE_TABLE; ++k) {
        double ny = -1.0 + 2.0 * k / (IRRADIANCE_TABLE - 1), n[3];
        n[0] = sqrt(1.0 - ny * ny);
        n[1] = ny;
        n[2] = 0.0;
        llplot_env_irradiance(n, table[k]);
    }
}

/* The picture a Lambertian sphere must give: at each point, albedo/pi
 * times the irradiance of the lighting, premultiplied by coverage and
 * averaged over each pixel (8 x 8 points), then passed through the
 * renderer's documented 3 x 3 binomial reconstruction filter. */
static void expected_sphere_columns(double alb[SPHERE_SIZE][3],
                                    float expect[3][SPHERE_SIZE][SPHERE_SIZE])
{
    static double table[IRRADIANCE_TABLE][3];
    static float box[3][SPHERE_SIZE][SPHERE_SIZE], tmp[3][SPHERE_SIZE][SPHERE_SIZE];
    const double half = 0.5 * SPHERE_SIZE, radius = LLPLOT_SPHERE_RADIUS * half;
    const double k[3] = { 0.25, 0.5, 0.25 };
    double key_dir[3], key_e[3];
    int x, y, c, i, j, d;
    irradiance_table(table);
    llplot_key_direction(key_dir);
    llplot_key_irradiance(key_e);
    for (y = 0; y < SPHERE_SIZE; ++y)
        for (x = 0; x < SPHERE_SIZE; ++x) {
            double sum[3] = { 0.0, 0.0, 0.0 };
            for (j = 0; j < SUBPIXELS; ++j)
                for (i = 0; i < SUBPIXELS; ++i) {
                    double sx = (x + (i + 0.5) / SUBPIXELS - half) / radius;
                    double sy = (half - y - (j + 0.5) / SUBPIXELS) / radius;
                    double r2 = sx * sx + sy * sy, n[3], t, cos_key;
                    int lo;
                    if (r2 >= 1.0)
                        continue;
                    n[0] = sx;
                    n[1] = sy;
                    n[2] = sqrt(1.0 - r2);
                    t = (n[1] + 1.0) * 0.5 * (IRRADIANCE_TABLE - 1);
                    lo = (int)t < IRRADIANCE_TABLE - 1 ? (int)t : IRRADIANCE_TABLE - 2;
                    t -= lo;
                    cos_key = n[0] * key_dir[0] + n[1] * key_dir[1] + n[2] * key_dir[2];
                    for (c = 0; c < 3; ++c) {
                        double e = (1.0 - t) * table[lo][c] + t * table[lo + 1][c];
                        sum[c] += alb[x][c] / PI * (e + key_e[c] * (cos_key > 0.0 ? cos_key : 0.0));
                    }
                }
            for (c = 0; c < 3; ++c)
                box[c][y][x] = (float)(sum[c] / (SUBPIXELS * SUBPIXELS));
        }
    for (c = 0; c < 3; ++c)
        for (y = 0; y < SPHERE_SIZE; ++y)
            for (x = 0; x < SPHERE_SIZE; ++x) {
                double v = 0.0;
                for (d = -1; d <= 1; ++d) {
                    int xx = x + d < 0 ? 0 : x + d >= SPHERE_SIZE ? SPHERE_SIZE - 1 : x + d;
                    v += k[d + 1] * box[c][y][xx];
                }
                tmp[c][y][x] = (float)v;
            }
    for (c = 0; c < 3; ++c)
        for (y = 0; y < SPHERE_SIZE; ++y)
            for (x = 0; x < SPHERE_SIZE; ++x) {
                double v = 0.0;
                for (d = -1; d <= 1; ++d) {
                    int yy = y + d < 0 ? 0 : y + d >= SPHERE_SIZE ? SPHERE_SIZE - 1 : y + d;
                    v += k[d + 1] * tmp[c][yy][x];
                }
                expect[c][y][x] = (float)v;
            }
}

/* The same with the albedo above in every column. */
static void expected_sphere(float expect[3][SPHERE_SIZE][SPHERE_SIZE])
{
    static double alb[SPHERE_SIZE][3];
    int x, c;
    for (x = 0; x < SPHERE_SIZE; ++x)
        for (c = 0; c < 3; ++c)
            alb[x][c] = albedo[c];
    expected_sphere_columns(alb, expect);
}

/* Mean and max relative error of the sphere's R, G, B against expect over
 * the pixels well inside the silhouette (r <= 0.8, see below). */
static int compare_sphere(const exr_picture *p, float expect[3][SPHERE_SIZE][SPHERE_SIZE],
                          double *mean_err, double *max_err)
{
    static const char *names[3] = { "R", "G", "B" };
    const double half = 0.5 * SPHERE_SIZE, radius = LLPLOT_SPHERE_RADIUS * half;
    double sum_err = 0.0;
    int x, y, c, inside = 0;
    *max_err = 0.0;
    for (y = 0; y < SPHERE_SIZE; ++y)
        for (x = 0; x < SPHERE_SIZE; ++x) {
            double sx = (x + 0.5 - half) / radius, sy = (half - y - 0.5) / radius;
            if (sqrt(sx * sx + sy * sy) > 0.8)
                continue;
            ++inside;
            for (c = 0; c < 3; ++c) {
                double want = expect[c][y][x], got = exr_at(p, names[c], x, y);
                double err = fabs(got - want) / want;
                sum_err += err;
                if (err > *max_err)
                    *max_err = err;
            }
        }
    *mean_err = sum_err / (3 * inside);
    return inside;
}

/* A Lambertian sphere must shade as albedo/pi times the irradiance of the
 * lighting, channel by channel; coverage is 0 and 1 away from the edge. */
static void test_sphere_exr_diffuse(void **state)
{
    static float expect[3][SPHERE_SIZE][SPHERE_SIZE];
    static const char *names[3] = { "R", "G", "B" };
    char in[4096], out[4096], size_text[16];
    exr_picture p;
    double sum_err = 0.0, max_err = 0.0;
    const double half = 0.5 * SPHERE_SIZE, radius = LLPLOT_SPHERE_RADIUS * half;
    int x, y, c, inside = 0;
    diffuse_path(in, sizeof in);
    path_in_work(out, sizeof out, "sphere.exr");
    snprintf(size_text, sizeof size_text, "%d", SPHERE_SIZE);
    assert_int_equal(run_llplot("--sphere", in, "-o", out, "--size", size_text, "--spp", "256",
                                (char *)NULL),
                     0);
    read_exr(out, &p);
    assert_int_equal(p.width, SPHERE_SIZE);
    assert_int_equal(p.height, SPHERE_SIZE);
    assert_int_equal(p.n_channels, 4);
    assert_string_equal(p.names[0], "A"); /* OpenEXR stores channels sorted by name */
    assert_string_equal(p.names[1], "B");
    assert_string_equal(p.names[2], "G");
    assert_string_equal(p.names[3], "R");
    expected_sphere(expect);
    for (y = 0; y < SPHERE_SIZE; ++y)
        for (x = 0; x < SPHERE_SIZE; ++x) {
            double sx = (x + 0.5 - half) / radius, sy = (half - y - 0.5) / radius;
            double r = sqrt(sx * sx + sy * sy);
            float a = exr_at(&p, "A", x, y);
            /* Pixels whose filter footprint (the pixel and its neighbours)
             * lies wholly outside: transparent black; inside: opaque. */
            if (r > 1.0 + 2.5 / radius) {
                assert_true(a == 0.0f);
                assert_true(exr_at(&p, "R", x, y) == 0.0f);
                continue;
            }
            if (r < 1.0 - 2.5 / radius)
                assert_true(fabs(a - 1.0) < 1e-6);
            /* Values: away from the silhouette, where the light reaches a
             * pixel at grazing angles that a .bsdf file represents only
             * approximately (see diffuse_grazing_limit). */
            if (r > 0.8)
                continue;
            ++inside;
            for (c = 0; c < 3; ++c) {
                double want = expect[c][y][x], got = exr_at(&p, names[c], x, y);
                double err = fabs(got - want) / want;
                sum_err += err;
                if (err > max_err)
                    max_err = err;
            }
        }
    free(p.data);
    assert_true(inside > 600);
    print_message("sphere of a Lambertian .bsdf: %d pixels, relative error mean %.4f, max %.4f\n",
                  inside, sum_err / (3 * inside), max_err);
    assert_true(sum_err / (3 * inside) < 0.01);
    assert_true(max_err < 0.03);
    (void)state;
}

/* The blocks of a diffuse layer: zero in T, albedo/pi |mu_i mu_o| in R
 * (flat albedo/pi with --quantity f). */
static void check_blocks(const char *in, const char *quantity, int n, const double *alb,
                         double grazing)
{
    char out[4096];
    exr_picture p;
    int x, y, c;
    char size[16];
    snprintf(size, sizeof size, "%d", n);
    path_in_work(out, sizeof out, "blocks.exr");
    assert_int_equal(run_llplot("--blocks", in, "-o", out, "--size", size, "--quantity", quantity,
                                (char *)NULL),
                     0);
    read_exr(out, &p);
    assert_int_equal(p.width, 2 * n);
    assert_int_equal(p.height, 2 * n);
    assert_int_equal(p.n_channels, 3);
    for (y = 0; y < 2 * n; ++y)
        for (x = 0; x < 2 * n; ++x) {
            double mu_i = -1.0 + (x + 0.5) / n, mu_o = -1.0 + (y + 0.5) / n;
            int transmission = (mu_i < 0) == (mu_o < 0);
            if (!transmission && fabs(mu_i) < grazing)
                continue;
            for (c = 0; c < 3; ++c) {
                static const char *names[3] = { "R", "G", "B" };
                double got = exr_at(&p, names[c], x, y);
                double expect = transmission ? 0.0
                                : strcmp(quantity, "f") == 0
                                    ? alb[c] / PI
                                    : alb[c] / PI * fabs(mu_i * mu_o);
                if (fabs(got - expect) > 1e-5 + 1e-4 * expect)
                    fail_msg("blocks (%s) pixel (%d, %d) channel %d: %g, expected %g", quantity,
                             x, y, c, got, expect);
            }
        }
    free(p.data);
}

static void test_blocks_exr_diffuse(void **state)
{
    char in[4096];
    diffuse_path(in, sizeof in);
    check_blocks(in, "fcos", 12, albedo, diffuse_grazing_limit());
    check_blocks(in, "f", 12, albedo, diffuse_grazing_limit());
    (void)state;
}

/* The same from a material file, compiled in memory: the blocks come from
 * the layers themselves; the sphere goes through a temporary .bsdf. */
static void test_material_input(void **state)
{
    char in[4096], out[4096], msg[4096];
    FILE *f;
    exr_picture p;
    path_in_work(in, sizeof in, "diffuse.layers");
    f = fopen(in, "w");
    assert_non_null(f);
    fputs("# a Lambertian base\ndiffuse albedo=0.8,0.5,0.2\n", f);
    fclose(f);
    /* The layers themselves are exactly Lambertian, grazing or not. */
    check_blocks(in, "fcos", 10, albedo, 0.0);
    check_blocks(in, "f", 10, albedo, 0.0);

    path_in_work(out, sizeof out, "material-sphere.exr");
    assert_int_equal(run_llplot("--sphere", in, "-o", out, "--size", "16", "--spp", "4",
                                (char *)NULL),
                     0);
    read_exr(out, &p);
    assert_int_equal(p.width, 16);
    assert_true(exr_at(&p, "R", 8, 6) > exr_at(&p, "B", 8, 6)); /* red albedo > blue */
    free(p.data);

    /* A mistake in the material: exit 1, named with line and column. */
    f = fopen(in, "w");
    assert_non_null(f);
    fputs("diffuse albedo=1.5\n", f);
    fclose(f);
    assert_int_equal(run_llplot("--blocks", in, "-o", out, (char *)NULL), 1);
    read_stderr(msg, sizeof msg);
    assert_non_null(strstr(msg, "diffuse.layers:1:"));
    assert_no_temporaries();
    (void)state;
}

/* A transmissive stack: light that enters the sphere must be followed
 * through it (here a rough glass ball, which shows the sky through itself)
 * rather than lost, which would leave only the few percent that the
 * interface reflects. */
static void test_sphere_transmissive(void **state)
{
    char in[4096], out[4096];
    FILE *f;
    exr_picture p;
    double sum = 0.0;
    int x, y, n = 0;
    path_in_work(in, sizeof in, "glass.layers");
    f = fopen(in, "w");
    assert_non_null(f);
    fputs("dielectric eta=1.5 alpha=0.3\n", f);
    fclose(f);
    path_in_work(out, sizeof out, "glass.exr");
    assert_int_equal(run_llplot("--sphere", in, "-o", out, "--size", "24", "--spp", "8",
                                "--nodes", "40", "--orders", "40", (char *)NULL),
                     0);
    read_exr(out, &p);
    for (y = 0; y < 24; ++y)
        for (x = 0; x < 24; ++x)
            if (exr_at(&p, "A", x, y) == 1.0f) {
                float g = exr_at(&p, "G", x, y);
                assert_true(isfinite(g) && g >= 0.0f);
                sum += g;
                ++n;
            }
    free(p.data);
    assert_true(n > 150);
    print_message("rough glass ball: mean green radiance %.3f over %d pixels\n", sum / n, n);
    /* The sky is about 0.5, the ground 0.07; reflection alone gives < 0.05. */
    assert_true(sum / n > 0.15);
    (void)state;
}

/* The polar data of a diffuse .bsdf: albedo/pi cos(theta_o) on both sides. */
static void test_polar_exr_diffuse(void **state)
{
    char in[4096], out[4096];
    exr_picture p;
    int a, k, c;
    const double angles[2] = { 0.0, 60.0 };
    diffuse_path(in, sizeof in);
    path_in_work(out, sizeof out, "polar.exr");
    assert_int_equal(run_llplot("--polar", in, "-o", out, "--size", "90", "--angles", "0,60",
                                (char *)NULL),
                     0);
    read_exr(out, &p);
    assert_int_equal(p.width, 90);
    assert_int_equal(p.height, 2);
    for (a = 0; a < 2; ++a)
        for (k = 0; k < 90; ++k) {
            double theta = (-90.0 + 180.0 * (k + 0.5) / 90.0) * PI / 180.0;
            for (c = 0; c < 3; ++c) {
                static const char *names[3] = { "R", "G", "B" };
                double expect = albedo[c] / PI * cos(theta);
                double got = exr_at(&p, names[c], k, a);
                if (fabs(got - expect) > 1e-5 + 1e-4 * expect)
                    fail_msg("polar angle %g column %d channel %d: %g, expected %g", angles[a], k,
                             c, got, expect);
            }
        }
    free(p.data);
    (void)state;
}

/* PNG figures read back with cairo at the documented sizes. */
static void check_png(const char *path, int width, int height)
{
    cairo_surface_t *s = cairo_image_surface_create_from_png(path);
    assert_int_equal(cairo_surface_status(s), CAIRO_STATUS_SUCCESS);
    assert_int_equal(cairo_image_surface_get_width(s), width);
    if (height > 0)
        assert_int_equal(cairo_image_surface_get_height(s), height);
    cairo_surface_destroy(s);
}

static uint32_t png_pixel(const char *path, int x, int y)
{
    cairo_surface_t *s = cairo_image_surface_create_from_png(path);
    uint32_t v;
    assert_int_equal(cairo_surface_status(s), CAIRO_STATUS_SUCCESS);
    cairo_surface_flush(s);
    v = *(const uint32_t *)(const void *)(cairo_image_surface_get_data(s) +
                                          (size_t)y * cairo_image_surface_get_stride(s) +
                                          4 * (size_t)x);
    cairo_surface_destroy(s);
    return v & 0xffffffu;
}

static void test_png_outputs(void **state)
{
    char in[4096], out[4096];
    uint32_t centre, corner;
    diffuse_path(in, sizeof in);
    path_in_work(out, sizeof out, "sphere.png");
    assert_int_equal(run_llplot("--sphere", in, "-o", out, "--size", "64", "--spp", "16",
                                (char *)NULL),
                     0);
    check_png(out, 64, 64);
    /* The sphere covers the centre, the backdrop the corners. */
    centre = png_pixel(out, 32, 32);
    corner = png_pixel(out, 0, 0);
    assert_true(centre != corner);
    assert_true(((centre >> 16) & 0xff) > ((centre & 0xff) + 40)); /* red albedo > blue */

    path_in_work(out, sizeof out, "blocks.png");
    assert_int_equal(run_llplot("--blocks", in, "-o", out, "--size", "40", (char *)NULL), 0);
    /* Panels are shown at least 160 pixels wide: (2 * 160 + 290) x (2 * 160 + 244). */
    check_png(out, 610, 564);
    assert_int_equal(run_llplot("--blocks", in, "-o", out, "--size", "200", (char *)NULL), 0);
    check_png(out, 690, 644);

    path_in_work(out, sizeof out, "polar.png");
    assert_int_equal(run_llplot("--polar", in, "-o", out, "--size", "400", (char *)NULL), 0);
    check_png(out, 400, 340); /* height = 0.4 size + 180 */
    assert_no_temporaries();
    (void)state;
}

/* Same seed, any thread count: the same picture, byte for byte. */
static void test_sphere_reproducible(void **state)
{
    char in[4096], a[4096], b[4096];
    FILE *fa, *fb;
    int ca, cb;
    diffuse_path(in, sizeof in);
    path_in_work(a, sizeof a, "repro1.exr");
    path_in_work(b, sizeof b, "repro2.exr");
    assert_int_equal(run_llplot("--sphere", in, "-o", a, "--size", "24", "--spp", "8",
                                "--threads", "1", (char *)NULL),
                     0);
    assert_int_equal(run_llplot("--sphere", in, "-o", b, "--size", "24", "--spp", "8",
                                "--threads", "3", (char *)NULL),
                     0);
    fa = fopen(a, "rb");
    fb = fopen(b, "rb");
    assert_non_null(fa);
    assert_non_null(fb);
    do {
        ca = fgetc(fa);
        cb = fgetc(fb);
        assert_int_equal(ca, cb);
    } while (ca != EOF);
    fclose(fa);
    fclose(fb);
    /* A different seed gives a different (noisy) picture. */
    assert_int_equal(run_llplot("--sphere", in, "-o", b, "--size", "24", "--spp", "8", "--seed",
                                "7", (char *)NULL),
                     0);
    {
        exr_picture p, q;
        int x, y, differ = 0;
        read_exr(a, &p);
        read_exr(b, &q);
        for (y = 0; y < 24; ++y)
            for (x = 0; x < 24; ++x)
                differ += exr_at(&p, "G", x, y) != exr_at(&q, "G", x, y);
        assert_true(differ > 0);
        free(p.data);
        free(q.data);
    }
    (void)state;
}

/* Bad input: exit 1 with the file named; I/O failures: exit 2; never an
 * output file (or a temporary one) after a failure. */
static void test_errors(void **state)
{
    char in[4096], bad[4096], out[4096], missing[4096], nodir[4096], msg[4096];
    FILE *f;
    diffuse_path(in, sizeof in);
    path_in_work(out, sizeof out, "never.png");
    path_in_work(missing, sizeof missing, "no-such-file.bsdf");
    path_in_work(bad, sizeof bad, "corrupt.bsdf");
    path_in_work(nodir, sizeof nodir, "no-such-dir/out.png");

    assert_int_equal(run_llplot("--sphere", missing, "-o", out, (char *)NULL), 2);
    read_stderr(msg, sizeof msg);
    assert_non_null(strstr(msg, "no-such-file.bsdf"));

    f = fopen(bad, "wb");
    assert_non_null(f);
    fputs("SCATFUN\001 this is not a table", f);
    fclose(f);
    assert_int_equal(run_llplot("--blocks", bad, "-o", out, (char *)NULL), 1);
    read_stderr(msg, sizeof msg);
    assert_non_null(strstr(msg, "corrupt.bsdf"));

    assert_int_equal(run_llplot("--blocks", in, "-o", nodir, (char *)NULL), 2);
    read_stderr(msg, sizeof msg);
    assert_non_null(strstr(msg, "no-such-dir/out.png"));

    /* Usage mistakes. */
    assert_int_equal(run_llplot("--blocks", in, "-o", "x.jpg", (char *)NULL), 1);
    assert_int_equal(run_llplot("--blocks", in, (char *)NULL), 1);
    assert_int_equal(run_llplot(in, "-o", out, (char *)NULL), 1);
    assert_int_equal(run_llplot("--blocks", "--sphere", in, "-o", out, (char *)NULL), 1);
    assert_int_equal(run_llplot("--blocks", in, "-o", out, "--spp", "4", (char *)NULL), 1);
    assert_int_equal(run_llplot("--sphere", in, "-o", out, "--size", "-3", (char *)NULL), 1);
    assert_int_equal(run_llplot("--polar", in, "-o", out, "--angles", "0,95", (char *)NULL), 1);
    assert_int_equal(run_llplot("--polar", in, "-o", out, "--bogus", "1", (char *)NULL), 1);
    assert_int_equal(run_llplot("--help", (char *)NULL), 0);

    assert_false(file_exists(out));
    assert_no_temporaries();
    (void)state;
}


/* --sphere --vary: column x shows the parameter at the sphere's horizontal
 * position of its centre (smallest sample at the left edge, largest at the
 * right), the other parameter at the middle of its range or at --param; a
 * Lambertian file then shades column by column as its albedo there. */
static void test_sphere_vary(void **state)
{
    static float expect[3][SPHERE_SIZE][SPHERE_SIZE];
    static double alb[SPHERE_SIZE][3];
    const double half = 0.5 * SPHERE_SIZE, radius = LLPLOT_SPHERE_RADIUS * half;
    const double dims[2] = { 0.5, 1.0 }; /* the middle, then --param dim=1 */
    char in[4096], out[4096], size_text[16];
    int x, c, run;
    textured_path(in, sizeof in);
    path_in_work(out, sizeof out, "vary.exr");
    snprintf(size_text, sizeof size_text, "%d", SPHERE_SIZE);
    for (run = 0; run < 2; ++run) {
        exr_picture p;
        double mean_err, max_err;
        int inside;
        if (run == 0)
            assert_int_equal(run_llplot("--sphere", in, "--vary", "albedo", "-o", out, "--size",
                                        size_text, "--spp", "256", (char *)NULL),
                             0);
        else
            assert_int_equal(run_llplot("--sphere", in, "--vary", "albedo", "--param", "dim=1",
                                        "-o", out, "--size", size_text, "--spp", "256",
                                        (char *)NULL),
                             0);
        for (x = 0; x < SPHERE_SIZE; ++x) {
            double t = 0.5 * ((x + 0.5 - half) / radius + 1.0);
            t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
            for (c = 0; c < 3; ++c)
                alb[x][c] = textured_albedo(t, dims[run]);
        }
        expected_sphere_columns(alb, expect);
        read_exr(out, &p);
        assert_int_equal(p.width, SPHERE_SIZE);
        assert_int_equal(p.height, SPHERE_SIZE);
        inside = compare_sphere(&p, expect, &mean_err, &max_err);
        free(p.data);
        print_message("--vary albedo (dim %.1f): %d pixels, relative error mean %.4f, max %.4f\n",
                      dims[run], inside, mean_err, max_err);
        assert_true(inside > 600);
        assert_true(mean_err < 0.01);
        assert_true(max_err < 0.03);
    }
    path_in_work(out, sizeof out, "vary.png");
    assert_int_equal(run_llplot("--sphere", in, "--vary", "dim", "-o", out, "--size", "48",
                                "--spp", "4", (char *)NULL),
                     0);
    check_png(out, 48, 48);
    (void)state;
}

/* --param alone: the whole sphere at one point of parameter space. */
static void test_sphere_param(void **state)
{
    static float expect[3][SPHERE_SIZE][SPHERE_SIZE];
    static double alb[SPHERE_SIZE][3];
    char in[4096], out[4096], size_text[16];
    exr_picture p;
    double mean_err, max_err;
    int x, c;
    textured_path(in, sizeof in);
    path_in_work(out, sizeof out, "param.exr");
    snprintf(size_text, sizeof size_text, "%d", SPHERE_SIZE);
    /* albedo = 0.25 between the samples, dim clamped from 3 to 1. */
    assert_int_equal(run_llplot("--sphere", in, "--param", "albedo=0.25", "--param", "dim=3",
                                "-o", out, "--size", size_text, "--spp", "256", (char *)NULL),
                     0);
    for (x = 0; x < SPHERE_SIZE; ++x)
        for (c = 0; c < 3; ++c)
            alb[x][c] = textured_albedo(0.25, 1.0);
    expected_sphere_columns(alb, expect);
    read_exr(out, &p);
    compare_sphere(&p, expect, &mean_err, &max_err);
    free(p.data);
    print_message("--param albedo=0.25 dim=3: relative error mean %.4f, max %.4f\n", mean_err,
                  max_err);
    assert_true(mean_err < 0.01);
    assert_true(max_err < 0.03);
    (void)state;
}

/* The sum of channel G over cell (i, j) of a grid mosaic of cells of side n. */
static double cell_sum(const exr_picture *p, int i, int j, int n)
{
    double sum = 0.0;
    int x, y;
    for (y = 0; y < n; ++y)
        for (x = 0; x < n; ++x)
            sum += exr_at(p, "G", i * n + x, j * n + y);
    return sum;
}

/* --grid: one sphere per sample of the first two parameters, each the
 * basis of its cell: the cells of the Lambertian file are the same picture
 * scaled by their albedos (the sampler draws the same directions for every
 * Lambertian basis), so their sums stand in the albedos' ratios. */
static void test_grid(void **state)
{
    char in[4096], out[4096];
    exr_picture p;
    double base;
    int i, j;
    textured_path(in, sizeof in);
    path_in_work(out, sizeof out, "grid.exr");
    assert_int_equal(run_llplot("--grid", in, "-o", out, "--size", "16", "--spp", "8",
                                (char *)NULL),
                     0);
    read_exr(out, &p);
    assert_int_equal(p.width, 2 * 16);
    assert_int_equal(p.height, 2 * 16);
    base = cell_sum(&p, 0, 0, 16);
    assert_true(base > 0.0);
    for (j = 0; j < 2; ++j)
        for (i = 0; i < 2; ++i) {
            double want = textured_albedo(i, j) / textured_albedo(0, 0);
            double got = cell_sum(&p, i, j, 16) / base;
            print_message("--grid cell (%d, %d): %.6f of cell (0, 0), albedo ratio %.6f\n", i, j,
                          got, want);
            assert_true(fabs(got - want) < 1e-4 * want);
        }
    free(p.data);
    path_in_work(out, sizeof out, "grid.png");
    assert_int_equal(run_llplot("--grid", in, "-o", out, "--size", "24", "--spp", "2",
                                (char *)NULL),
                     0);
    {
        /* Two 24-pixel cells and gaps across, two down, labels beside and
         * above: larger than the cells, and dark where no sphere is. */
        cairo_surface_t *s = cairo_image_surface_create_from_png(out);
        assert_int_equal(cairo_surface_status(s), CAIRO_STATUS_SUCCESS);
        assert_true(cairo_image_surface_get_width(s) > 2 * 24 + 60);
        assert_true(cairo_image_surface_get_height(s) > 2 * 24 + 40);
        cairo_surface_destroy(s);
        {
            uint32_t corner = png_pixel(out, 1, 1);
            assert_true(((corner >> 16) & 0xff) < 0x40 && ((corner >> 8) & 0xff) < 0x40 &&
                        (corner & 0xff) < 0x40);
        }
    }
    assert_no_temporaries();
    (void)state;
}

/* --vary, --param and --grid: an unknown name or an untextured file is an
 * error that says so (and lists the file's names); nothing is written. */
static void test_parameter_errors(void **state)
{
    char in[4096], plain[4096], out[4096], msg[4096];
    textured_path(in, sizeof in);
    diffuse_path(plain, sizeof plain);
    path_in_work(out, sizeof out, "never-param.png");

    assert_int_equal(run_llplot("--sphere", in, "--vary", "roughness", "-o", out, (char *)NULL), 1);
    read_stderr(msg, sizeof msg);
    assert_non_null(strstr(msg, "'roughness'"));
    assert_non_null(strstr(msg, "albedo, dim"));
    assert_int_equal(run_llplot("--sphere", in, "--param", "gloss=1", "-o", out, (char *)NULL), 1);
    read_stderr(msg, sizeof msg);
    assert_non_null(strstr(msg, "'gloss'"));
    assert_int_equal(run_llplot("--grid", in, "--param", "gloss=1", "-o", out, (char *)NULL), 1);

    assert_int_equal(run_llplot("--sphere", plain, "--vary", "albedo", "-o", out, (char *)NULL), 1);
    read_stderr(msg, sizeof msg);
    assert_non_null(strstr(msg, "textured"));
    assert_int_equal(run_llplot("--grid", plain, "-o", out, (char *)NULL), 1);
    read_stderr(msg, sizeof msg);
    assert_non_null(strstr(msg, "--grid needs a textured .bsdf file"));
    assert_int_equal(run_llplot("--blocks", plain, "--param", "albedo=1", "-o", out, (char *)NULL),
                     1);

    /* Usage: --vary is for --sphere; --basis does not mix with the rest. */
    assert_int_equal(run_llplot("--blocks", in, "--vary", "albedo", "-o", out, (char *)NULL), 1);
    assert_int_equal(run_llplot("--sphere", in, "--vary", "albedo", "--basis", "1", "-o", out,
                                (char *)NULL),
                     1);
    assert_int_equal(run_llplot("--grid", in, "--basis", "1", "-o", out, (char *)NULL), 1);
    assert_int_equal(run_llplot("--sphere", in, "--param", "albedo", "-o", out, (char *)NULL), 1);
    assert_int_equal(run_llplot("--sphere", in, "--param", "albedo=x", "-o", out, (char *)NULL), 1);
    assert_int_equal(run_llplot("--sphere", in, "--param", "albedo=1", "--param", "albedo=0",
                                "-o", out, (char *)NULL),
                     1);
    assert_int_equal(run_llplot("--grid", in, "--channel", "R", "-o", out, (char *)NULL), 1);
    assert_false(file_exists(out));
    assert_no_temporaries();
    (void)state;
}

/* An existing picture survives a failed run untouched. */
static void test_failure_keeps_existing_output(void **state)
{
    char in[4096], out[4096], bad[4096];
    struct stat before, after;
    diffuse_path(in, sizeof in);
    path_in_work(out, sizeof out, "keep.exr");
    path_in_work(bad, sizeof bad, "corrupt.bsdf");
    assert_int_equal(run_llplot("--polar", in, "-o", out, "--size", "16", (char *)NULL), 0);
    assert_int_equal(stat(out, &before), 0);
    assert_int_not_equal(run_llplot("--polar", bad, "-o", out, (char *)NULL), 0);
    assert_int_equal(stat(out, &after), 0);
    assert_int_equal(before.st_size, after.st_size);
    assert_int_equal(before.st_mtime, after.st_mtime);
    (void)state;
}

int main(int argc, char **argv)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sphere_exr_diffuse),
        cmocka_unit_test(test_blocks_exr_diffuse),
        cmocka_unit_test(test_material_input),
        cmocka_unit_test(test_sphere_transmissive),
        cmocka_unit_test(test_polar_exr_diffuse),
        cmocka_unit_test(test_png_outputs),
        cmocka_unit_test(test_sphere_reproducible),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_failure_keeps_existing_output),
        cmocka_unit_test(test_sphere_vary),
        cmocka_unit_test(test_sphere_param),
        cmocka_unit_test(test_grid),
        cmocka_unit_test(test_parameter_errors),
    };
    if (argc != 3) {
        fprintf(stderr, "usage: %s PATH/TO/llplot WORK_DIR\n", argv[0]);
        return 2;
    }
    llplot_path = argv[1];
    work_dir = argv[2];
    return cmocka_run_group_tests_name("llplot", tests, NULL, NULL);
}
