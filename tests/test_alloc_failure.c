/*
 * Out of memory at every allocation of every public call that allocates.
 *
 * For each call, at a small resolution and on one thread (so that the
 * allocations come in one deterministic order, see support/alloc.c), the
 * call is first run with the hook only counting: N allocations. Then for
 * k = 1 .. N it is run again, from the same inputs, with the k-th
 * allocation failing, and:
 *  - it returns LL_ERROR_OUT_OF_MEMORY with a message about memory, every
 *    block it allocated is freed again (the hook's live count is back to 0;
 *    `make test SANITIZE=1` also runs this under LeakSanitizer), and
 *    everything it could change (its output layer's matrices, output
 *    buffers and structs, out pointers, the output directory with its
 *    files) is bit-identical to before the call;
 *  - or, when the failed allocation was one it can do without, it
 *    succeeds with exactly the result of the run without failures.
 * Each call prints its N.
 */
#include "test_util.h"

#include "support/support.h"

#define N_NODES 8
#define N_ORDERS 4

/* ------------------------------------------------------------ snapshots */

/* Everything a call may change, serialised, to compare bit for bit. */
typedef struct blob {
    unsigned char *data;
    size_t size, cap;
} blob;

static void put(blob *b, const void *p, size_t n)
{
    if (b->size + n > b->cap) {
        size_t cap = 2 * (b->size + n) + 64;
        unsigned char *d = realloc(b->data, cap);
        assert_non_null(d);
        b->data = d;
        b->cap = cap;
    }
    memcpy(b->data + b->size, p, n);
    b->size += n;
}

static void put_size(blob *b, size_t v) { put(b, &v, sizeof v); }

static void put_text(blob *b, const char *s)
{
    put_size(b, s ? strlen(s) : (size_t)-1);
    if (s)
        put(b, s, strlen(s));
}

static void put_layer(blob *b, const ll_layer *l)
{
    size_t n = ll_layer_node_count(l), m = ll_layer_order_count(l), k;
    double *buf;
    put_size(b, l ? 1 : 0);
    if (!l)
        return;
    put_size(b, n);
    put_size(b, m);
    put_size(b, ll_layer_stored_count(l));
    buf = malloc(2 * n * n * sizeof *buf + 1);
    assert_non_null(buf);
    assert_int_equal(ll_layer_get_nodes(l, buf, buf + n), LL_OK);
    put(b, buf, 2 * n * sizeof *buf);
    for (k = 0; k < m; ++k) {
        assert_int_equal(ll_layer_matrix(l, k, buf), LL_OK);
        put(b, buf, n * n * sizeof *buf);
    }
    free(buf);
}

static void put_bsdf(blob *b, const ll_bsdf *f)
{
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    double rgb[3], mu;
    float coeffs[2] = { 0.25f, 0.75f };
    put_size(b, f ? 1 : 0);
    if (!f)
        return;
    assert_int_equal(ll_bsdf_get_info(f, &info), LL_OK);
    put_text(b, info.metadata);
    info.metadata = NULL;
    put(b, &info, sizeof info);
    put(b, ll_bsdf_nodes(f), info.n_nodes * sizeof(float));
    for (mu = -0.9; mu < 1.0; mu += 0.3) {
        assert_int_equal(ll_bsdf_eval(f, 0.7, mu, 0.4, info.n_bases > 1 ? coeffs : NULL, rgb),
                         LL_OK);
        put(b, rgb, sizeof rgb);
    }
}

/* Names and contents of the files in dir (sorted by name). */
static int compare_names(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static void put_dir(blob *b, const char *dir)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    char *names[64], path[1024];
    size_t count = 0, i;
    assert_non_null(d);
    while ((e = readdir(d)) != NULL)
        if (strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0) {
            assert_true(count < 64);
            names[count] = malloc(strlen(e->d_name) + 1);
            assert_non_null(names[count]);
            strcpy(names[count++], e->d_name);
        }
    closedir(d);
    qsort(names, count, sizeof *names, compare_names);
    put_size(b, count);
    for (i = 0; i < count; ++i) {
        size_t size;
        unsigned char *data;
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        data = ll_test_read_file(path, &size);
        put_text(b, names[i]);
        put_size(b, size);
        put(b, data, size);
        free(data);
        free(names[i]);
    }
}

/* ---------------------------------------------------------------- world */

/* The inputs and outputs of one call; rebuilt before every run. */
typedef struct world {
    ll_layer *in[3];          /* inputs, not to be changed            */
    ll_layer *out;            /* the layer the call changes or makes  */
    ll_layer *layers[3];      /* ll_material_build_layers             */
    size_t n_channels;
    ll_bsdf *bsdf;
    ll_material *material;    /* input of the material calls          */
    ll_material *parsed;      /* output of parse                      */
    double values[N_NODES * N_NODES];
    size_t sizes[3];
    ll_bsdf_write_options header;
    ll_build_estimate estimate;
} world;

static char scratch_dir[512], out_dir[600], merl_path[600], bsdf_path[600], material_path[600],
    out_path[700], ior_dir[600], rgb_path[600], textured_path[600];
static unsigned char *bsdf_bytes;
static size_t bsdf_size;
static double nodes[N_NODES], weights[N_NODES];

static const char material_text[] = "set nodes=10 orders=4\n"
                                    "dielectric eta=1.5 alpha=0.3\n"
                                    "medium albedo=0.9 g=0.5 tau=0.5\n"
                                    "diffuse albedo=0.5,0.4,0.3\n";
static const char metal_text[] = "set nodes=10 orders=4\n"
                                 "dielectric eta=1.5 alpha=0.3\n"
                                 "conductor eta=Tst alpha=0.2\n";
/* A swept material: 2 x 2 bases, mono, the coat shared by two bases. */
static const char sweep_text[] = "set nodes=10 orders=4\n"
                                 "dielectric name=coat eta=1.5 alpha=[0.2 0.3]\n"
                                 "diffuse albedo=[0.4 0.6]\n";
static const char measured_text[] = "set nodes=10 orders=4\n"
                                    "dielectric eta=1.4 alpha=0.4\n"
                                    "measured file=tiny.binary\n";

static ll_layer *layer(void)
{
    ll_layer *l = NULL;
    assert_int_equal(ll_layer_create(nodes, weights, N_NODES, N_ORDERS, &l), LL_OK);
    return l;
}

/* A slab: Henyey-Greenstein medium of thickness 1. */
static ll_layer *slab(void)
{
    ll_layer *l = layer();
    assert_int_equal(ll_layer_set_henyey_greenstein(l, 0.9, 0.6, NULL), LL_OK);
    assert_int_equal(ll_layer_expand(l, 1.0, NULL), LL_OK);
    return l;
}

static ll_layer *coat(void)
{
    ll_layer *l = layer();
    assert_int_equal(ll_test_set_microfacet(l, 1.5, 0.0, 0.3, 1, 0, NULL), LL_OK);
    return l;
}

static ll_layer *base(double albedo)
{
    ll_layer *l = layer();
    assert_int_equal(ll_layer_set_diffuse(l, albedo, NULL), LL_OK);
    return l;
}

static ll_layer *coated_base(double albedo)
{
    ll_layer *l = base(albedo), *c = coat();
    assert_int_equal(ll_layer_add_to_top(l, c), LL_OK);
    ll_layer_destroy(c);
    return l;
}

static void world_release(world *w)
{
    size_t i;
    for (i = 0; i < 3; ++i) {
        ll_layer_destroy(w->in[i]);
        ll_layer_destroy(w->layers[i]);
    }
    ll_layer_destroy(w->out);
    ll_bsdf_release(w->bsdf);
    ll_material_destroy(w->material);
    ll_material_destroy(w->parsed);
    memset(w, 0, sizeof *w);
}

/* The output folder: empty, or holding an older out.bsdf. */
static void clear_out_dir(void)
{
    ll_test_rmdir(out_dir);
    assert_int_equal(mkdir(out_dir, 0755), 0);
}

static void existing_out_file(void)
{
    static const char old[] = "an older file that a failed write must leave alone\n";
    clear_out_dir();
    ll_test_write_file(out_path, old, sizeof old - 1);
}

static void material_from_text(world *w)
{
    assert_int_equal(ll_material_parse(material_text, "alloc.layers", &w->material), LL_OK);
}

/* What identifies a parsed material: its words, resolution, estimate and
 * the metadata its files get. */
static void put_material(blob *b, const ll_material *m)
{
    ll_build_estimate e = LL_BUILD_ESTIMATE_INIT;
    ll_bsdf_write_options header = LL_BSDF_WRITE_OPTIONS_INIT;
    ll_layer *layers[3];
    size_t n, o, c, nch;
    put_size(b, m ? 1 : 0);
    if (!m)
        return;
    put_size(b, ll_material_word_count(m));
    assert_int_equal(ll_material_resolution(m, NULL, NULL, &n, &o, &c), LL_OK);
    put_size(b, n);
    put_size(b, o);
    put_size(b, c);
    assert_int_equal(ll_material_estimate(m, NULL, &e, NULL), LL_OK);
    put(b, &e, sizeof e);
    if (ll_material_axis_count(m) > 0) {
        /* a swept material: its axes, and its first basis */
        ll_material_builder *builder = NULL;
        size_t a;
        for (a = 0; a < ll_material_axis_count(m); ++a) {
            ll_material_axis axis = LL_MATERIAL_AXIS_INIT;
            assert_int_equal(ll_material_get_axis(m, a, &axis), LL_OK);
            put_text(b, axis.name);
            put(b, axis.positions, axis.n_values * sizeof *axis.positions);
        }
        assert_int_equal(ll_material_builder_create(m, NULL, NULL, &builder), LL_OK);
        assert_int_equal(ll_material_builder_build_basis(builder, 0, layers, &nch, &header),
                         LL_OK);
        ll_material_builder_destroy(builder);
    } else {
        assert_int_equal(ll_material_build_layers(m, NULL, NULL, layers, &nch, &header), LL_OK);
    }
    put_text(b, header.metadata);
    header.metadata = NULL;
    put(b, &header, sizeof header);
    for (c = 0; c < nch; ++c) {
        put_layer(b, layers[c]);
        ll_layer_destroy(layers[c]);
    }
}

/* ---------------------------------------------------------------- cases */

typedef struct alloc_case {
    const char *name;
    void (*prepare)(world *w);
    ll_status (*call)(world *w);
    void (*snapshot)(world *w, blob *b);
} alloc_case;

/* Snapshots shared by several cases. */
static void snap_layers(world *w, blob *b)
{
    size_t i;
    for (i = 0; i < 3; ++i)
        put_layer(b, w->in[i]);
    put_layer(b, w->out);
}

static void snap_values(world *w, blob *b)
{
    snap_layers(w, b);
    put(b, w->values, sizeof w->values);
}

static void snap_out_dir(world *w, blob *b)
{
    snap_layers(w, b);
    put_dir(b, out_dir);
}

static void snap_bsdf(world *w, blob *b) { put_bsdf(b, w->bsdf); }

static void snap_parsed(world *w, blob *b) { put_material(b, w->parsed); }

static void snap_build_layers(world *w, blob *b)
{
    size_t c;
    for (c = 0; c < 3; ++c)
        put_layer(b, w->layers[c]);
    put_size(b, w->n_channels);
    put_text(b, w->header.metadata);
    put(b, &w->header.eta, sizeof w->header.eta);
    put(b, w->header.alpha, sizeof w->header.alpha);
    put(b, &w->header.error_goal, sizeof w->header.error_goal);
}

static void snap_estimate(world *w, blob *b)
{
    put(b, &w->estimate, sizeof w->estimate);
    put(b, w->sizes, sizeof w->sizes);
}

/* -- layers */
static void prep_nothing(world *w) { (void)w; }
static void prep_slab_out(world *w) { w->out = slab(); }
static void prep_slab_in(world *w) { w->in[0] = slab(); }
static void prep_phase_out(world *w)
{
    w->out = layer();
    assert_int_equal(ll_layer_set_henyey_greenstein(w->out, 0.95, 0.7, NULL), LL_OK);
}
static void prep_add(world *w)
{
    w->in[0] = coat();
    w->in[1] = base(0.5);
    w->out = slab();
}
static void prep_add_homogeneous(world *w)
{
    w->in[0] = slab();
    w->out = coat();
}
static void prep_add_to_top(world *w)
{
    w->in[0] = coat();
    w->out = base(0.5);
}
static void prep_add_to_bottom(world *w)
{
    w->in[0] = base(0.5);
    w->out = coat();
}
static void prep_coat_out(world *w) { w->out = coat(); }
static void prep_values(world *w)
{
    w->in[0] = coated_base(0.5);
    memset(w->values, 0xA5, sizeof w->values);
}

static ll_status call_create(world *w)
{
    return ll_layer_create(nodes, weights, N_NODES, N_ORDERS, &w->out);
}
static ll_status call_clone(world *w) { return ll_layer_clone(w->in[0], &w->out); }
static ll_status call_diffuse(world *w) { return ll_layer_set_diffuse(w->out, 0.3, NULL); }
static ll_status call_isotropic(world *w) { return ll_layer_set_isotropic(w->out, 0.8, NULL); }
static ll_status call_hg(world *w) { return ll_layer_set_henyey_greenstein(w->out, 0.7, -0.3, NULL); }
static ll_status call_vmf(world *w) { return ll_layer_set_von_mises_fisher(w->out, 0.8, 5.0, NULL); }
static ll_status call_dielectric(world *w)
{
    return ll_test_set_microfacet(w->out, 1.33, 0.0, 0.2, 1, 0, NULL);
}
static ll_status call_conductor(world *w)
{
    return ll_test_set_microfacet(w->out, 0.2, 3.9, 0.25, 1, 2 * N_ORDERS, NULL);
}
static ll_status call_matusik(world *w) { return ll_layer_set_matusik(w->out, merl_path, 1, 0, NULL); }
static ll_status call_add(world *w) { return ll_layer_add(w->in[0], w->in[1], w->out, 0, NULL); }
static ll_status call_add_homogeneous(world *w)
{
    return ll_layer_add(w->in[0], w->in[0], w->out, 1, NULL);
}
static ll_status call_add_to_top(world *w) { return ll_layer_add_to_top(w->out, w->in[0]); }
static ll_status call_add_to_bottom(world *w) { return ll_layer_add_to_bottom(w->out, w->in[0]); }
static ll_status call_expand(world *w) { return ll_layer_expand(w->out, 3.0, NULL); }
static ll_status call_reverse(world *w) { return ll_layer_reverse(w->out); }
static ll_status call_clear(world *w) { return ll_layer_clear(w->out); }
static ll_status call_matrix(world *w) { return ll_layer_matrix(w->in[0], 1, w->values); }
static ll_status call_albedo(world *w)
{
    return ll_layer_albedo(w->in[0], 0.6, &w->values[0], &w->values[1]);
}
static ll_status call_eval_many(world *w)
{
    double mu_o[4] = { -0.9, -0.5, 0.3, 0.8 }, mu_i[4] = { 0.2, 0.5, 0.7, 1.0 };
    return ll_layer_eval_many(w->in[0], 4, mu_i, mu_o, NULL, w->values);
}

/* -- files */
static void prep_write_one(world *w)
{
    w->in[0] = coated_base(0.5);
    clear_out_dir();
}
static void prep_write_over(world *w)
{
    w->in[0] = coated_base(0.5);
    existing_out_file();
}
static void prep_write_rgb(world *w)
{
    w->in[0] = coated_base(0.7);
    w->in[1] = coated_base(0.5);
    w->in[2] = coated_base(0.2);
    existing_out_file();
}
static void prep_write_textured(world *w)
{
    w->in[0] = coated_base(0.8);
    w->in[1] = coated_base(0.1);
    existing_out_file();
}
static ll_status call_write_one(world *w)
{
    const ll_layer *const l[1] = { w->in[0] };
    return ll_bsdf_write(out_path, l, 1, NULL, NULL);
}
static ll_status call_write_rgb(world *w)
{
    const ll_layer *const l[3] = { w->in[0], w->in[1], w->in[2] };
    ll_bsdf_write_options o = LL_BSDF_WRITE_OPTIONS_INIT;
    o.metadata = "three channels";
    return ll_bsdf_write(out_path, l, 3, &o, NULL);
}
static ll_status call_write_textured(world *w)
{
    const ll_layer *const l[2] = { w->in[0], w->in[1] };
    const size_t counts[1] = { 2 };
    const double positions[2] = { 0.0, 1.0 };
    return ll_bsdf_write_textured(out_path, l, 1, 1, counts, positions, NULL, NULL);
}
static ll_status call_open(world *w) { return ll_bsdf_open(bsdf_path, NULL, &w->bsdf); }
static ll_status call_open_rgb(world *w) { return ll_bsdf_open(rgb_path, NULL, &w->bsdf); }
static ll_status call_open_textured(world *w)
{
    return ll_bsdf_open(textured_path, NULL, &w->bsdf);
}
static ll_status call_open_memory(world *w)
{
    return ll_bsdf_open_memory(bsdf_bytes, bsdf_size, NULL, &w->bsdf);
}

/* -- the material language */
static ll_status call_parse(world *w)
{
    return ll_material_parse(material_text, "alloc.layers", &w->parsed);
}
static ll_status call_parse_metal(world *w)
{
    return ll_material_parse(metal_text, "metal.layers", &w->parsed);
}
static ll_status call_parse_file(world *w) { return ll_material_parse_file(material_path, &w->parsed); }
static void prep_material(world *w)
{
    material_from_text(w);
    w->header.struct_size = sizeof w->header;
    w->header.eta = -1.0;
    w->header.metadata = "untouched";
    memset(&w->estimate, 0xA5, sizeof w->estimate);
    w->estimate.struct_size = sizeof w->estimate;
    w->sizes[0] = w->sizes[1] = w->sizes[2] = 77;
}
static void prep_measured(world *w)
{
    prep_material(w);
    ll_material_destroy(w->material);
    w->material = NULL;
    assert_int_equal(ll_material_parse_file(material_path, &w->material), LL_OK);
}
static void prep_material_out(world *w)
{
    prep_material(w);
    existing_out_file();
}
static void prep_material_write(world *w)
{
    size_t c;
    prep_material_out(w);
    assert_int_equal(ll_material_build_layers(w->material, NULL, NULL, w->layers, &w->n_channels, NULL),
                     LL_OK);
    for (c = 0; c < 3; ++c) {
        w->in[c] = w->layers[c];
        w->layers[c] = NULL;
    }
}
static ll_status call_resolution(world *w)
{
    return ll_material_resolution(w->material, NULL, NULL, &w->sizes[0], &w->sizes[1], &w->sizes[2]);
}
static ll_status call_estimate(world *w) { return ll_material_estimate(w->material, NULL, &w->estimate, NULL); }
static ll_status call_build_layers(world *w)
{
    return ll_material_build_layers(w->material, NULL, NULL, w->layers, &w->n_channels, &w->header);
}
static ll_status call_build(world *w) { return ll_material_build(w->material, NULL, NULL, out_path); }
static ll_status call_material_write(world *w)
{
    return ll_material_write(w->material, NULL, w->in, 3, out_path, NULL);
}
static ll_status call_parse_sweep(world *w)
{
    return ll_material_parse(sweep_text, "sweep.layers", &w->parsed);
}
static void prep_sweep_out(world *w)
{
    prep_material_out(w);
    ll_material_destroy(w->material);
    w->material = NULL;
    assert_int_equal(ll_material_parse(sweep_text, "sweep.layers", &w->material), LL_OK);
}
static ll_status call_sweep_estimate(world *w)
{
    return ll_material_estimate(w->material, NULL, &w->estimate, NULL);
}
/* The streaming writer: open, two bases, commit. */
static ll_status call_writer(world *w)
{
    const size_t counts[1] = { 2 };
    const double positions[2] = { 0.0, 1.0 };
    ll_bsdf_writer *writer = NULL;
    ll_status s = ll_bsdf_writer_open(out_path, 1, 1, counts, positions, NULL, &writer);
    if (s == LL_OK)
        s = ll_bsdf_writer_add_basis(writer, (const ll_layer *const *)&w->in[0]);
    if (s == LL_OK)
        s = ll_bsdf_writer_add_basis(writer, (const ll_layer *const *)&w->in[1]);
    if (s == LL_OK)
        return ll_bsdf_writer_commit(writer, NULL);
    ll_bsdf_writer_abort(writer);
    return s;
}

static alloc_case cases[] = {
    { "ll_layer_create", prep_nothing, call_create, snap_layers },
    { "ll_layer_clone", prep_slab_in, call_clone, snap_layers },
    { "ll_layer_set_diffuse", prep_slab_out, call_diffuse, snap_layers },
    { "ll_layer_set_isotropic", prep_slab_out, call_isotropic, snap_layers },
    { "ll_layer_set_henyey_greenstein", prep_slab_out, call_hg, snap_layers },
    { "ll_layer_set_von_mises_fisher", prep_slab_out, call_vmf, snap_layers },
    { "ll_layer_set_microfacet (dielectric)", prep_slab_out, call_dielectric, snap_layers },
    { "ll_layer_set_microfacet (conductor)", prep_slab_out, call_conductor, snap_layers },
    { "ll_layer_set_matusik", prep_slab_out, call_matusik, snap_layers },
    { "ll_layer_add", prep_add, call_add, snap_layers },
    { "ll_layer_add (homogeneous)", prep_add_homogeneous, call_add_homogeneous, snap_layers },
    { "ll_layer_add_to_top", prep_add_to_top, call_add_to_top, snap_layers },
    { "ll_layer_add_to_bottom", prep_add_to_bottom, call_add_to_bottom, snap_layers },
    { "ll_layer_expand", prep_phase_out, call_expand, snap_layers },
    { "ll_layer_reverse", prep_coat_out, call_reverse, snap_layers },
    { "ll_layer_clear", prep_slab_out, call_clear, snap_layers },
    { "ll_layer_matrix", prep_values, call_matrix, snap_values },
    { "ll_layer_albedo", prep_values, call_albedo, snap_values },
    { "ll_layer_eval_many", prep_values, call_eval_many, snap_values },
    { "ll_bsdf_write (new file)", prep_write_one, call_write_one, snap_out_dir },
    { "ll_bsdf_write (over a file)", prep_write_over, call_write_one, snap_out_dir },
    { "ll_bsdf_write (rgb)", prep_write_rgb, call_write_rgb, snap_out_dir },
    { "ll_bsdf_write_textured", prep_write_textured, call_write_textured, snap_out_dir },
    { "ll_bsdf_open", prep_nothing, call_open, snap_bsdf },
    { "ll_bsdf_open_memory", prep_nothing, call_open_memory, snap_bsdf },
    { "ll_bsdf_open (rgb)", prep_nothing, call_open_rgb, snap_bsdf },
    { "ll_bsdf_open (textured)", prep_nothing, call_open_textured, snap_bsdf },
    { "ll_material_parse", prep_nothing, call_parse, snap_parsed },
    { "ll_material_parse_file (measured)", prep_nothing, call_parse_file, snap_parsed },
    { "ll_material_parse (named metal)", prep_nothing, call_parse_metal, snap_parsed },
    { "ll_material_resolution", prep_material, call_resolution, snap_estimate },
    { "ll_material_estimate", prep_material, call_estimate, snap_estimate },
    { "ll_material_build_layers", prep_material, call_build_layers, snap_build_layers },
    { "ll_material_build_layers (measured)", prep_measured, call_build_layers, snap_build_layers },
    { "ll_material_build", prep_material_out, call_build, snap_out_dir },
    { "ll_material_write", prep_material_write, call_material_write, snap_out_dir },
    { "ll_material_parse (sweep)", prep_nothing, call_parse_sweep, snap_parsed },
    { "ll_material_estimate (sweep)", prep_sweep_out, call_sweep_estimate, snap_estimate },
    { "ll_material_build (textured)", prep_sweep_out, call_build, snap_out_dir },
    { "ll_bsdf_writer_*", prep_write_textured, call_writer, snap_out_dir },
};

/* --------------------------------------------------------------- runner */

static void snapshot(const alloc_case *c, world *w, blob *b)
{
    b->size = 0;
    c->snapshot(w, b);
}

static int same(const blob *a, const blob *b)
{
    return a->size == b->size && memcmp(a->data, b->data, a->size) == 0;
}

/* Run c failing each of its allocations in turn, the calls made with
 * `threads` worker threads (the allocations are counted with one). */
static void run_failures(const alloc_case *c, size_t threads)
{
    world w;
    blob before = { NULL, 0, 0 }, expected = { NULL, 0, 0 }, now = { NULL, 0, 0 };
    size_t n_alloc, k, failed = 0;
    ll_status s;

    assert_int_equal(ll_set_thread_count(1), LL_OK);
    memset(&w, 0, sizeof w);
    c->prepare(&w);
    snapshot(c, &w, &before);
    ll_alloc_fail_after(0);
    s = c->call(&w);
    n_alloc = ll_alloc_count();
    ll_alloc_hook_off();
    assert_int_equal(s, LL_OK);
    snapshot(c, &w, &expected);
    world_release(&w);

    for (k = 1; k <= n_alloc; ++k) {
        long long live;
        memset(&w, 0, sizeof w);
        c->prepare(&w);
        snapshot(c, &w, &now);
        assert_true(same(&now, &before));
        assert_int_equal(ll_set_thread_count(threads), LL_OK);
        ll_alloc_fail_after(k);
        s = c->call(&w);
        live = ll_alloc_live();
        ll_alloc_hook_off();
        assert_int_equal(ll_set_thread_count(1), LL_OK);
        snapshot(c, &w, &now);
        if (s == LL_OK) {
            if (!same(&now, &expected))
                fail_msg("%s: succeeded with allocation %zu of %zu failing, but with another "
                         "result", c->name, k, n_alloc);
        } else {
            ++failed;
            if (s != LL_ERROR_OUT_OF_MEMORY)
                fail_msg("%s: allocation %zu of %zu failing gave status %d (%s): %s", c->name,
                         k, n_alloc, (int)s, ll_status_string(s), ll_last_error_message());
            if (!strstr(ll_last_error_message(), "memory"))
                fail_msg("%s: allocation %zu of %zu failing: the message \"%s\" does not say "
                         "out of memory", c->name, k, n_alloc, ll_last_error_message());
            if (live != 0)
                fail_msg("%s: allocation %zu of %zu failing left %+lld block(s) allocated "
                         "(leaked, or freed what it should keep)", c->name, k, n_alloc, live);
            if (!same(&now, &before))
                fail_msg("%s: allocation %zu of %zu failing left the output changed", c->name,
                         k, n_alloc);
        }
        world_release(&w);
    }
    if (threads == 1)
        printf("    %-40s N = %4zu allocations, %zu of them fatal\n", c->name, n_alloc, failed);
    free(before.data);
    free(expected.data);
    free(now.data);
}

static void run_case(void **state)
{
    run_failures(*state, 1);
}

/* With two threads the failing allocation may be in either worker (which
 * one is not deterministic), but every failure must still be clean. */
static void run_case_two_threads(void **state)
{
    run_failures(*state, 2);
}

/* ---------------------------------------------------------------- setup */

/* A small MERL table (little-endian, as the database's): glossy near the
 * specular direction, different per channel. */
static void write_merl(const char *file)
{
    enum { TH = 6, TD = 5, PD = 8 };
    const uint32_t dims[3] = { TH, TD, PD };
    FILE *f = fopen(file, "wb");
    unsigned char b[8];
    size_t ih, id, ip, k;
    int c;
    assert_non_null(f);
    for (k = 0; k < 3; ++k) {
        for (c = 0; c < 4; ++c)
            b[c] = (unsigned char)(dims[k] >> (8 * c) & 0xff);
        assert_int_equal(fwrite(b, 1, 4, f), 4);
    }
    for (c = 0; c < 3; ++c)
        for (ih = 0; ih < TH; ++ih)
            for (id = 0; id < TD; ++id)
                for (ip = 0; ip < PD; ++ip) {
                    double v = 1500.0 * (c + 1) * (0.1 + 1.0 / (1.0 + (double)(ih * ih)));
                    uint64_t bits;
                    memcpy(&bits, &v, 8);
                    for (k = 0; k < 8; ++k)
                        b[k] = (unsigned char)(bits >> (8 * k) & 0xff);
                    assert_int_equal(fwrite(b, 1, 8, f), 8);
                }
    assert_int_equal(fclose(f), 0);
}

/* Spectra of a made-up metal "Tst", with a comment line longer than the
 * first line buffer. */
static void write_spectrum(const char *suffix, double value)
{
    char path[700];
    FILE *f;
    int nm, i;
    snprintf(path, sizeof path, "%s/Tst%s", ior_dir, suffix);
    f = fopen(path, "w");
    assert_non_null(f);
    fputs("# a test spectrum:", f);
    for (i = 0; i < 40; ++i)
        fputs(" padding", f);
    fputs("\n", f);
    for (nm = 350; nm <= 850; nm += 25)
        fprintf(f, "%d %g\n", nm, value + 0.001 * nm);
    assert_int_equal(fclose(f), 0);
}

static void write_input_files(void)
{
    ll_layer *l[3];
    const size_t counts[1] = { 2 };
    const double positions[2] = { 0.0, 0.5 };
    size_t i;
    for (i = 0; i < 3; ++i)
        l[i] = coated_base(0.2 + 0.3 * (double)i);
    assert_int_equal(ll_bsdf_write(bsdf_path, (const ll_layer *const *)l, 1, NULL, NULL), LL_OK);
    assert_int_equal(ll_bsdf_write(rgb_path, (const ll_layer *const *)l, 3, NULL, NULL), LL_OK);
    assert_int_equal(ll_bsdf_write_textured(textured_path, (const ll_layer *const *)l, 1, 1,
                                            counts, positions, NULL, NULL),
                     LL_OK);
    for (i = 0; i < 3; ++i)
        ll_layer_destroy(l[i]);
    bsdf_bytes = ll_test_read_file(bsdf_path, &bsdf_size);
}

static int group_setup(void **state)
{
    (void)state;
    /* One thread: the allocations come in one order, so the k-th is one
     * deterministic allocation (see support/alloc.c). */
    assert_int_equal(ll_set_thread_count(1), LL_OK);
    assert_int_equal(ll_quad_gauss_lobatto(N_NODES, nodes, weights, NULL), LL_OK);
    ll_test_mkdtemp(scratch_dir, sizeof scratch_dir);
    snprintf(out_dir, sizeof out_dir, "%s/out", scratch_dir);
    snprintf(out_path, sizeof out_path, "%s/out.bsdf", out_dir);
    snprintf(merl_path, sizeof merl_path, "%s/tiny.binary", scratch_dir);
    snprintf(bsdf_path, sizeof bsdf_path, "%s/in.bsdf", scratch_dir);
    snprintf(material_path, sizeof material_path, "%s/measured.layers", scratch_dir);
    snprintf(rgb_path, sizeof rgb_path, "%s/rgb.bsdf", scratch_dir);
    snprintf(textured_path, sizeof textured_path, "%s/textured.bsdf", scratch_dir);
    snprintf(ior_dir, sizeof ior_dir, "%s/ior", scratch_dir);
    write_merl(merl_path);
    ll_test_write_file(material_path, measured_text, sizeof measured_text - 1);
    write_input_files();
    assert_int_equal(mkdir(out_dir, 0755), 0);
    assert_int_equal(mkdir(ior_dir, 0755), 0);
    write_spectrum(".eta.spd", 0.3);
    write_spectrum(".k.spd", 3.0);
    assert_int_equal(setenv("LAYERLAB_IOR_DIR", ior_dir, 1), 0);
    return 0;
}

static int group_teardown(void **state)
{
    (void)state;
    free(bsdf_bytes);
    ll_test_rmdir(scratch_dir);
    return 0;
}

/* The hook itself: counts, fails exactly the k-th allocation, and tracks
 * live blocks. */
static void hook_fails_the_kth_allocation(void **state)
{
    void *a, *b, *c;
    (void)state;
    ll_alloc_fail_after(2);
    a = ll_malloc(8);
    b = ll_calloc(2, 8);
    c = ll_realloc(NULL, 8);
    assert_non_null(a);
    assert_null(b);
    assert_non_null(c);
    assert_int_equal(ll_alloc_count(), 3);
    assert_int_equal(ll_alloc_live(), 2);
    ll_free(a);
    ll_free(c);
    assert_int_equal(ll_alloc_live(), 0);
    ll_alloc_hook_off();
    a = ll_malloc(8);
    assert_non_null(a);
    assert_int_equal(ll_alloc_count(), 3);
    ll_free(a);
}

/* Calls that run parallel loops, run again with two threads. */
static const char *const parallel[] = { "ll_layer_set_microfacet (dielectric)",
                                        "ll_layer_set_matusik", "ll_layer_add",
                                        "ll_layer_expand", "ll_bsdf_write (rgb)",
                                        "ll_material_build_layers" };

int main(void)
{
    enum { N_CASES = sizeof cases / sizeof cases[0], N_PARALLEL = sizeof parallel / sizeof parallel[0] };
    struct CMUnitTest tests[1 + N_CASES + N_PARALLEL];
    char names[N_PARALLEL][96];
    size_t i, j, count = 0;
    memset(tests, 0, sizeof tests);
    tests[count].name = "hook_fails_the_kth_allocation";
    tests[count++].test_func = hook_fails_the_kth_allocation;
    for (i = 0; i < N_CASES; ++i) {
        tests[count].name = cases[i].name;
        tests[count].test_func = run_case;
        tests[count++].initial_state = &cases[i];
    }
    for (j = 0; j < N_PARALLEL; ++j)
        for (i = 0; i < N_CASES; ++i)
            if (strcmp(cases[i].name, parallel[j]) == 0) {
                snprintf(names[j], sizeof names[j], "%s, two threads", cases[i].name);
                tests[count].name = names[j];
                tests[count].test_func = run_case_two_threads;
                tests[count++].initial_state = &cases[i];
            }
    if (count != 1 + N_CASES + N_PARALLEL) {
        fprintf(stderr, "test_alloc_failure: a name in parallel[] is not a case\n");
        return 1;
    }
    return _cmocka_run_group_tests("alloc_failure", tests, count, group_setup, group_teardown);
}
