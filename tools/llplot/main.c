/*
 * llplot — command line: parse the options, open the material, draw.
 *
 *   llplot --blocks|--sphere|--polar|--grid INPUT -o OUTPUT.png|OUTPUT.exr [options]
 *
 * Exit codes: 0 done, 1 bad input (usage, malformed file or material),
 * 2 a file could not be read or written. The output is written atomically.
 */
#include "figure.h"
#include "llplot.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

static const char usage_text[] =
    "usage: llplot --blocks|--sphere|--polar|--grid INPUT -o OUTPUT.png|OUTPUT.exr [options]\n"
    "\n"
    "Draw a layered material. INPUT is a .bsdf file or a material file (compiled\n"
    "in memory). The output's extension chooses the format: .png is a figure\n"
    "(sRGB, titles, axes), .exr is linear 32-bit float data (OpenEXR).\n"
    "\n"
    "modes:\n"
    "  --blocks   the four scattering blocks T^bt, R^t, R^b, T^tb as images over\n"
    "             (mu_i, mu_o) of f * |mu_i mu_o| at azimuth --phi; each colour\n"
    "             scale is clipped at its block's 99th percentile.\n"
    "             EXR: one 2N x 2N RGB image, N = --size, pixel (x, y) at\n"
    "             mu_i = -1 + (x + 0.5)/N, mu_o = -1 + (y + 0.5)/N.\n"
    "  --sphere   a sphere of the material under a studio sky and a key light,\n"
    "             importance-sampled through the BSDF with a fixed seed.\n"
    "             EXR: linear RGBA, A = coverage (premultiplied).\n"
    "  --polar    f * cos(theta_o) in the plane of incidence for a few incident\n"
    "             angles, as a polar plot. EXR: one row per angle, --size columns\n"
    "             over theta_o = -90..90 degrees (negative: toward the light).\n"
    "  --grid     textured .bsdf: one small sphere per sample of the first two\n"
    "             parameters (first across, second down), labelled with their\n"
    "             values; other parameters at --param or their range's middle.\n"
    "             EXR: the spheres' RGBA side by side, no labels.\n"
    "\n"
    "options:\n"
    "  -o, --output FILE    the picture to write (required)\n"
    "  --size N             blocks: samples per block side (200); sphere: image\n"
    "                       side in pixels (320); polar: PNG width, or EXR\n"
    "                       columns (760); grid: each sphere's side (128)\n"
    "  --phi DEG            blocks: azimuth difference phi_d in degrees (0: the\n"
    "                       plane of the mirror direction)\n"
    "  --quantity fcos|f    blocks: f * |mu_i mu_o| (default) or f alone\n"
    "  --channel Y|R|G|B    blocks/polar PNG: luminance (default) or one channel\n"
    "  --angles A,B,...     polar: incident zenith angles in degrees, at most 8\n"
    "                       (default 0,30,45,60,75)\n"
    "  --spp N              sphere: samples per pixel (32; grid 16)\n"
    "  --seed N             sphere: random seed (0)\n"
    "  --exposure EV        sphere PNG: exposure in stops (0)\n"
    "  --title TEXT         a title instead of the input's file name\n"
    "  --nodes N            material input: zenith nodes (default: the material's\n"
    "                       `set`, at most 120, else 120: a preview, no search)\n"
    "  --orders N           material input: Fourier orders (default: likewise, at\n"
    "                       most 200)\n"
    "  --basis K            textured .bsdf: show basis function K (0)\n"
    "  --vary NAME          sphere, textured .bsdf: parameter NAME runs from its\n"
    "                       smallest sample (left) to its largest (right)\n"
    "  --param NAME=VALUE   textured .bsdf: the value of parameter NAME (default:\n"
    "                       the middle of its samples; clamped to them); repeatable\n"
    "  --threads N          worker threads (0: all processors)\n"
    "  -h, --help           this text\n"
    "  --version            the layerlab version\n"
    "\n"
    "exit codes: 0 done, 1 bad input, 2 a file could not be read or written.\n"
    "example: llplot --sphere coated-gold.bsdf -o coated-gold.png\n";

static int parse_size(const char *name, const char *text, size_t lo, size_t hi, size_t *out)
{
    char *end;
    unsigned long long v;
    errno = 0;
    v = strtoull(text, &end, 10);
    if (errno || end == text || *end != '\0' || text[0] == '-' || v < lo || v > hi)
        return llplot_fail(LLPLOT_EXIT_INPUT, "%s: '%s' is not a whole number in [%zu, %zu]", name,
                           text, lo, hi);
    *out = (size_t)v;
    return LLPLOT_EXIT_OK;
}

static int parse_double(const char *name, const char *text, double lo, double hi, double *out)
{
    char *end;
    double v;
    errno = 0;
    v = strtod(text, &end);
    if (errno || end == text || *end != '\0' || !(v >= lo && v <= hi))
        return llplot_fail(LLPLOT_EXIT_INPUT, "%s: '%s' is not a number in [%g, %g]", name, text,
                           lo, hi);
    *out = v;
    return LLPLOT_EXIT_OK;
}

static int parse_angles(const char *text, llplot_options *o)
{
    const char *p = text;
    o->n_angles = 0;
    while (*p) {
        char item[64], *end;
        size_t len = strcspn(p, ",");
        double v;
        if (len == 0 || len >= sizeof item || o->n_angles == LLPLOT_MAX_ANGLES)
            return llplot_fail(LLPLOT_EXIT_INPUT,
                               "--angles: '%s' is not a list of at most %d angles", text,
                               LLPLOT_MAX_ANGLES);
        memcpy(item, p, len);
        item[len] = '\0';
        v = strtod(item, &end);
        /* 90 degrees is grazing: no light arrives, so the curve is empty. */
        if (end == item || *end != '\0' || !(v >= 0.0 && v < 90.0))
            return llplot_fail(LLPLOT_EXIT_INPUT, "--angles: '%s' is not an angle in [0, 90)",
                               item);
        o->angles_deg[o->n_angles++] = v;
        p += len;
        if (*p == ',')
            ++p;
    }
    if (o->n_angles == 0)
        return llplot_fail(LLPLOT_EXIT_INPUT, "--angles: the list is empty");
    return LLPLOT_EXIT_OK;
}

/* --param NAME=VALUE (a finite VALUE; out of range is clamped later). */
static int parse_param(const char *text, llplot_options *o)
{
    const char *eq = strchr(text, '=');
    llplot_param *p;
    size_t k;
    if (!eq || eq == text)
        return llplot_fail(LLPLOT_EXIT_INPUT, "--param: '%s' is not NAME=VALUE", text);
    if (o->n_params == LLPLOT_MAX_PARAMS)
        return llplot_fail(LLPLOT_EXIT_INPUT, "--param: at most %d of them", LLPLOT_MAX_PARAMS);
    for (k = 0; k < o->n_params; ++k)
        if (o->params[k].name_len == (size_t)(eq - text) &&
            memcmp(o->params[k].name, text, o->params[k].name_len) == 0)
            return llplot_fail(LLPLOT_EXIT_INPUT, "--param: %.*s is given twice",
                               (int)(eq - text), text);
    p = &o->params[o->n_params];
    p->name = text;
    p->name_len = (size_t)(eq - text);
    if (parse_double("--param", eq + 1, -1e30, 1e30, &p->value) != LLPLOT_EXIT_OK)
        return LLPLOT_EXIT_INPUT;
    ++o->n_params;
    return LLPLOT_EXIT_OK;
}

static int has_extension(const char *path, const char *ext)
{
    size_t n = strlen(path), e = strlen(ext);
    return n > e && strcasecmp(path + n - e, ext) == 0;
}

/* Options given that the mode does not use are mistakes worth reporting. */
typedef struct given_flags {
    int phi, quantity, channel, angles, spp, seed, exposure, vary, param;
} given_flags;

static const char *mode_name(llplot_mode mode)
{
    switch (mode) {
    case LLPLOT_BLOCKS: return "blocks";
    case LLPLOT_SPHERE: return "sphere";
    case LLPLOT_GRID: return "grid";
    default: return "polar";
    }
}

static int check_mode_options(const llplot_options *o, const given_flags *g)
{
    const char *wrong = NULL;
    int spheres = o->mode == LLPLOT_SPHERE || o->mode == LLPLOT_GRID;
    if (o->mode != LLPLOT_BLOCKS && (g->phi || g->quantity))
        wrong = g->phi ? "--phi" : "--quantity";
    else if (o->mode != LLPLOT_POLAR && g->angles)
        wrong = "--angles";
    else if (!spheres && (g->spp || g->seed || g->exposure))
        wrong = g->spp ? "--spp" : g->seed ? "--seed" : "--exposure";
    else if (spheres && g->channel)
        wrong = "--channel";
    else if (o->mode != LLPLOT_SPHERE && g->vary)
        wrong = "--vary";
    if (wrong)
        return llplot_fail(LLPLOT_EXIT_INPUT, "%s does not apply to --%s (see llplot --help)",
                           wrong, mode_name(o->mode));
    if (o->basis_given && (g->vary || g->param || o->mode == LLPLOT_GRID))
        return llplot_fail(LLPLOT_EXIT_INPUT,
                           "--basis picks one basis function; it does not combine with %s",
                           o->mode == LLPLOT_GRID ? "--grid" : g->vary ? "--vary" : "--param");
    if (o->format == LLPLOT_EXR && (g->channel || g->exposure))
        return llplot_fail(LLPLOT_EXIT_INPUT,
                           "%s applies to PNG figures only (EXR files hold linear RGB)",
                           g->channel ? "--channel" : "--exposure");
    return LLPLOT_EXIT_OK;
}

static void set_defaults(llplot_options *o)
{
    static const double default_angles[] = { 0.0, 30.0, 45.0, 60.0, 75.0 };
    size_t k;
    memset(o, 0, sizeof *o);
    o->channel = 'Y';
    o->quantity = LLPLOT_QUANTITY_FCOS;
    o->n_angles = sizeof default_angles / sizeof default_angles[0];
    for (k = 0; k < o->n_angles; ++k)
        o->angles_deg[k] = default_angles[k];
}

/* Parse argv into o. Returns an exit code, or -1 when --help/--version
 * was answered. */
static int parse_args(int argc, char **argv, llplot_options *o)
{
    given_flags given;
    int i, have_mode = 0, code = LLPLOT_EXIT_OK;
    memset(&given, 0, sizeof given);
    set_defaults(o);
    for (i = 1; i < argc && code == LLPLOT_EXIT_OK; ++i) {
        const char *arg = argv[i], *value = NULL, *eq;
        char name[32];
        int mode = -1;
        if (strcmp(arg, "-h") == 0 || strcmp(arg, "--help") == 0) {
            fputs(usage_text, stdout);
            return -1;
        }
        if (strcmp(arg, "--version") == 0) {
            printf("llplot (layerlab) %s\n", ll_version_string());
            return -1;
        }
        if (arg[0] != '-' || strcmp(arg, "-") == 0) {
            if (o->input)
                return llplot_fail(LLPLOT_EXIT_INPUT, "more than one input: '%s' and '%s'",
                                   o->input, arg);
            o->input = arg;
            continue;
        }
        if (strcmp(arg, "--blocks") == 0)
            mode = LLPLOT_BLOCKS;
        else if (strcmp(arg, "--sphere") == 0)
            mode = LLPLOT_SPHERE;
        else if (strcmp(arg, "--polar") == 0)
            mode = LLPLOT_POLAR;
        else if (strcmp(arg, "--grid") == 0)
            mode = LLPLOT_GRID;
        if (mode >= 0) {
            if (have_mode && o->mode != (llplot_mode)mode)
                return llplot_fail(LLPLOT_EXIT_INPUT,
                                   "choose one of --blocks, --sphere, --polar, --grid");
            o->mode = (llplot_mode)mode;
            have_mode = 1;
            continue;
        }
        /* "--name value" or "--name=value". */
        eq = strchr(arg, '=');
        if (eq && (size_t)(eq - arg) < sizeof name) {
            memcpy(name, arg, (size_t)(eq - arg));
            name[eq - arg] = '\0';
            value = eq + 1;
        } else {
            snprintf(name, sizeof name, "%s", arg);
            if (i + 1 < argc)
                value = argv[++i];
        }
        if (!value)
            return llplot_fail(LLPLOT_EXIT_INPUT, "%s needs a value (see llplot --help)", arg);
        if (strcmp(name, "-o") == 0 || strcmp(name, "--output") == 0)
            o->output = value;
        else if (strcmp(name, "--size") == 0)
            code = parse_size(name, value, 2, 16384, &o->size);
        else if (strcmp(name, "--phi") == 0) {
            code = parse_double(name, value, -3600.0, 3600.0, &o->phi_deg);
            given.phi = 1;
        } else if (strcmp(name, "--quantity") == 0) {
            given.quantity = 1;
            if (strcmp(value, "fcos") == 0)
                o->quantity = LLPLOT_QUANTITY_FCOS;
            else if (strcmp(value, "f") == 0)
                o->quantity = LLPLOT_QUANTITY_F;
            else
                code = llplot_fail(LLPLOT_EXIT_INPUT, "--quantity: '%s' is not fcos or f", value);
        } else if (strcmp(name, "--channel") == 0) {
            given.channel = 1;
            if (strlen(value) == 1 && strchr("YRGB", value[0]))
                o->channel = value[0];
            else
                code = llplot_fail(LLPLOT_EXIT_INPUT, "--channel: '%s' is not Y, R, G or B", value);
        } else if (strcmp(name, "--angles") == 0) {
            code = parse_angles(value, o);
            given.angles = 1;
        } else if (strcmp(name, "--spp") == 0) {
            code = parse_size(name, value, 1, 1u << 20, &o->spp);
            given.spp = 1;
        } else if (strcmp(name, "--seed") == 0) {
            size_t seed = 0;
            code = parse_size(name, value, 0, (size_t)-1, &seed);
            o->seed = seed;
            given.seed = 1;
        } else if (strcmp(name, "--exposure") == 0) {
            code = parse_double(name, value, -20.0, 20.0, &o->exposure);
            given.exposure = 1;
        } else if (strcmp(name, "--title") == 0)
            o->title = value;
        else if (strcmp(name, "--nodes") == 0)
            code = parse_size(name, value, 2, 1u << 16, &o->nodes);
        else if (strcmp(name, "--orders") == 0)
            code = parse_size(name, value, 1, 1u << 16, &o->orders);
        else if (strcmp(name, "--basis") == 0) {
            code = parse_size(name, value, 0, (size_t)-1, &o->basis);
            o->basis_given = 1;
        } else if (strcmp(name, "--vary") == 0) {
            o->vary = value;
            given.vary = 1;
        } else if (strcmp(name, "--param") == 0) {
            code = parse_param(value, o);
            given.param = 1;
        }
        else if (strcmp(name, "--threads") == 0)
            code = parse_size(name, value, 0, 1024, &o->threads);
        else
            code = llplot_fail(LLPLOT_EXIT_INPUT, "unknown option '%s' (see llplot --help)", name);
    }
    if (code != LLPLOT_EXIT_OK)
        return code;
    if (!have_mode)
        return llplot_fail(LLPLOT_EXIT_INPUT, "choose a picture: --blocks, --sphere, --polar or "
                                              "--grid (see llplot --help)");
    if (!o->input)
        return llplot_fail(LLPLOT_EXIT_INPUT, "no input file (a .bsdf or material file)");
    if (!o->output)
        return llplot_fail(LLPLOT_EXIT_INPUT, "no output file: add -o OUTPUT.png or -o OUTPUT.exr");
    if (has_extension(o->output, ".png"))
        o->format = LLPLOT_PNG;
    else if (has_extension(o->output, ".exr"))
        o->format = LLPLOT_EXR;
    else
        return llplot_fail(LLPLOT_EXIT_INPUT, "%s: the output must end in .png or .exr",
                           o->output);
    if (o->mode == LLPLOT_POLAR && o->format == LLPLOT_PNG && o->size && o->size < 320)
        return llplot_fail(LLPLOT_EXIT_INPUT, "--size: a polar figure needs at least 320 pixels");
    if ((o->mode == LLPLOT_SPHERE || o->mode == LLPLOT_GRID) && o->size && o->size < 8)
        return llplot_fail(LLPLOT_EXIT_INPUT, "--size: a sphere needs at least 8 pixels");
    return check_mode_options(o, &given);
}

int main(int argc, char **argv)
{
    llplot_options o;
    llplot_source source;
    int code = parse_args(argc, argv, &o);
    if (code < 0)
        return LLPLOT_EXIT_OK;
    if (code != LLPLOT_EXIT_OK)
        return code;
    /* The library's own parallel regions (compiling a material) follow
     * --threads as well. */
    if (o.threads)
        ll_set_thread_count(o.threads);
    code = llplot_source_open(&o, o.mode == LLPLOT_SPHERE || o.mode == LLPLOT_GRID, &source);
    if (code != LLPLOT_EXIT_OK)
        return code;
    /* --param alone fixes the point of every picture; --vary and --grid
     * read it themselves. */
    if (o.n_params > 0 && !o.vary && o.mode != LLPLOT_GRID)
        code = llplot_source_set_point(&o, &source);
    if (code == LLPLOT_EXIT_OK) {
        switch (o.mode) {
        case LLPLOT_BLOCKS: code = llplot_blocks(&o, &source); break;
        case LLPLOT_SPHERE: code = llplot_sphere(&o, &source); break;
        case LLPLOT_GRID: code = llplot_grid(&o, &source); break;
        default: code = llplot_polar(&o, &source); break;
        }
    }
    llplot_source_close(&source);
    llplot_figure_release_caches();
    return code;
}
