/*
 * llplot — pictures of a layered material: the four scattering blocks of a
 * layer (--blocks), a shaded sphere (--sphere) and the reflectance in the
 * plane of incidence (--polar), written as OpenEXR (linear float data) or
 * PNG (sRGB figures drawn with cairo).
 *
 * Declarations shared by the files of the tool. Everything here is private
 * to the program; it uses only the public layerlab API.
 */
#ifndef LLPLOT_H
#define LLPLOT_H

#include <stddef.h>
#include <stdint.h>

#include <layerlab.h>

#if defined(__GNUC__)
#  define LLPLOT_PRINTF(a, b) __attribute__((format(printf, a, b)))
#else
#  define LLPLOT_PRINTF(a, b)
#endif

#define LLPLOT_PI 3.14159265358979323846

/* Exit codes: 0 success, 1 bad input (usage, malformed file, invalid
 * material), 2 input/output failure (a file could not be read or written). */
#define LLPLOT_EXIT_OK 0
#define LLPLOT_EXIT_INPUT 1
#define LLPLOT_EXIT_IO 2

/* Print "llplot: <message>" on stderr and return code, so that call sites
 * read `return llplot_fail(LLPLOT_EXIT_IO, "...", ...)`. */
int llplot_fail(int code, const char *fmt, ...) LLPLOT_PRINTF(2, 3);

/* Report a failed layerlab call about `what` (usually the input path): the
 * library's message, prefixed by what unless it names it already. Returns
 * the exit code: 2 for I/O errors, 1 for everything else (format, parse,
 * invalid argument). */
int llplot_fail_ll(ll_status status, const char *what);

/* ----------------------------------------------------------- options */

typedef enum { LLPLOT_BLOCKS, LLPLOT_SPHERE, LLPLOT_POLAR, LLPLOT_GRID } llplot_mode;
typedef enum { LLPLOT_PNG, LLPLOT_EXR } llplot_format;

/* What a blocks panel shows: the BSDF times |mu_i mu_o| (the default, as
 * the seed's notebook), or the BSDF alone. */
typedef enum { LLPLOT_QUANTITY_FCOS, LLPLOT_QUANTITY_F } llplot_quantity;

#define LLPLOT_MAX_ANGLES 8
/* --param NAME=VALUE options (one per textured parameter at most). */
#define LLPLOT_MAX_PARAMS 16

typedef struct llplot_param {
    const char *name;         /* points into argv: "NAME=VALUE" up to '=' */
    size_t name_len;
    double value;
} llplot_param;

typedef struct llplot_options {
    llplot_mode mode;
    llplot_format format;
    const char *input;
    const char *output;
    const char *title;        /* NULL: derived from the input name          */
    double phi_deg;           /* --blocks: azimuth difference, degrees      */
    size_t size;              /* pixels or samples, see --help; 0: default  */
    size_t spp;               /* --sphere: samples per pixel                */
    uint64_t seed;            /* --sphere: random seed                      */
    double exposure;          /* --sphere PNG: exposure in stops            */
    size_t nodes, orders;     /* material input: resolution, 0 = default    */
    size_t threads;           /* worker threads, 0 = all processors         */
    size_t basis;             /* textured .bsdf: the basis function shown   */
    char channel;             /* 'Y' (luminance), 'R', 'G' or 'B'           */
    llplot_quantity quantity;
    double angles_deg[LLPLOT_MAX_ANGLES]; /* --polar: incident zenith angles */
    size_t n_angles;
    const char *vary;         /* --sphere: the parameter varied left to right */
    llplot_param params[LLPLOT_MAX_PARAMS]; /* --param: fixed values        */
    size_t n_params;
    int basis_given;          /* --basis was given                          */
} llplot_options;

/* ------------------------------------------------------------ source */

/* The material being drawn: an opened .bsdf file, or a material file
 * compiled in memory (then layers are set as well, and bsdf only when the
 * caller asked for sampling). */
typedef struct llplot_source {
    char label[256];          /* the input's file name, for titles          */
    ll_layer *layers[3];      /* material input: one per channel            */
    size_t n_layers;
    ll_bsdf *bsdf;            /* .bsdf input, or a material's compiled file */
    float *basis_coeffs;      /* one-hot weights of a textured file, or NULL */
    size_t n_channels;        /* 1 or 3                                      */
} llplot_source;

/* Open o->input: a .bsdf file (recognised by its "SCATFUN" magic bytes,
 * whatever its name) or a material file. need_sampling: the caller will
 * use llplot_source_sample_dir (a material is then also written to a
 * temporary .bsdf file and opened, which is how sampling is reached
 * through the public API). Returns an exit code. */
int llplot_source_open(const llplot_options *o, int need_sampling, llplot_source *s);
void llplot_source_close(llplot_source *s);

/* The BSDF f (no cosine factor) in the layer convention of ll_layer_eval:
 * mu_i > 0 is light arriving from above; reflection leaves with mu_o < 0;
 * phi_d = 0 is the specular plane. RGB (three equal values for one
 * channel). */
void llplot_source_eval(const llplot_source *s, double mu_i, double mu_o, double phi_d,
                        double rgb[3]);

/* ---------------------------------------------------- parameter space */

/* The textured parameters of a .bsdf source (params.c): names from the
 * file (ll_bsdf_get_parameter_name), sampled ranges, and the point every
 * sphere is drawn at unless a mode varies a parameter: --param NAME=VALUE
 * where given, else the middle of the parameter's range. */
typedef struct llplot_axes {
    size_t n;                 /* parameters (>= 1)                          */
    size_t n_bases;
    const char **names;       /* [n], owned by the source's bsdf            */
    const float **positions;  /* [n] sample positions, owned likewise       */
    size_t *counts;           /* [n]                                        */
    double *point;            /* [n] the fixed point                        */
} llplot_axes;

/* Set up a for a textured source, checking every --param name (an unknown
 * one is an error listing the file's names). what: the option that needs a
 * textured file ("--vary", "--grid", "--param"), for the message when s is
 * not one. Returns an exit code. */
int llplot_axes_open(const llplot_options *o, const llplot_source *s, const char *what,
                     llplot_axes *a);
void llplot_axes_close(llplot_axes *a);
/* The index of parameter name, or an error (exit code in *code) listing the
 * file's names; what names the option. */
int llplot_axes_find(const llplot_axes *a, const char *name, size_t len, const char *what,
                     const char *input, size_t *index);
/* The basis weights (a->n_bases floats) of point (a->n values). */
int llplot_axes_weights(const llplot_source *s, const double *point, float *coeffs);
/* "%g" of a parameter value, as labels show it. */
void llplot_format_value(double v, char *buf, size_t size);

/* --param without --vary or --grid: the source's weights become those of
 * the fixed point (instead of --basis's one-hot weights). */
int llplot_source_set_point(const llplot_options *o, llplot_source *s);

/* Luminance of linear sRGB (the weights the .bsdf format uses for Y). */
double llplot_luminance(const double rgb[3]);

/* ------------------------------------------------------------ images */

/* A float image with planar channels: channel c of pixel (x, y) is
 * data[(c * height + y) * width + x]. Row 0 is the top row. */
typedef struct llplot_image {
    size_t width, height, channels;
    const char *names[4];     /* EXR channel names, e.g. "R", "G", "B", "A" */
    float *data;
} llplot_image;

/* Allocate a zeroed image (checked size arithmetic). Returns an exit code. */
int llplot_image_alloc(llplot_image *img, size_t width, size_t height, size_t channels);
void llplot_image_free(llplot_image *img);

static inline float *llplot_pixel(const llplot_image *img, size_t c, size_t x, size_t y)
{
    return img->data + (c * img->height + y) * img->width + x;
}

/* Write img as a scanline OpenEXR file of 32-bit float channels (ZIP
 * compression) with a "comments" attribute; atomic (temporary file in the
 * same directory, renamed on success). Returns an exit code. */
int llplot_write_exr(const char *path, const llplot_image *img, const char *comments);

/* ------------------------------------------------------- atomic files */

/* A temporary file next to the final path; commit renames it over the
 * final path, abort removes it. The final path is never partially written. */
typedef struct llplot_output {
    char *final_path;
    char *temp_path;
} llplot_output;

int llplot_output_begin(const char *path, llplot_output *out);
int llplot_output_commit(llplot_output *out);
void llplot_output_abort(llplot_output *out);

/* ------------------------------------------------------------ threads */

/* Run body(row, ctx) for every row in [0, n_rows) on up to `threads`
 * threads (0: all processors). Rows are handed out one at a time; the
 * body must make its result independent of the thread that runs it (the
 * sphere seeds its random numbers per pixel), so pictures are identical
 * for any thread count. */
typedef void (*llplot_row_fn)(size_t row, void *ctx);
void llplot_parallel_rows(size_t n_rows, size_t threads, llplot_row_fn body, void *ctx);

/* --------------------------------------------------------------- modes */

int llplot_blocks(const llplot_options *o, const llplot_source *s);
int llplot_sphere(const llplot_options *o, const llplot_source *s);
int llplot_polar(const llplot_options *o, const llplot_source *s);
int llplot_grid(const llplot_options *o, const llplot_source *s);

/* The sphere of --sphere as a linear RGBA image of size x size pixels
 * (premultiplied, filtered), with the basis weights of the source or, if
 * column_coeffs is not NULL, those of column x at column_coeffs + x *
 * n_bases (--vary; n_bases 0: the same weights for every column, --grid).
 * img is allocated here. Returns an exit code. */
int llplot_sphere_image(const llplot_options *o, const llplot_source *s, size_t size, size_t spp,
                        const float *column_coeffs, size_t n_bases, llplot_image *img);
/* Tone-map the sphere image (as --sphere's PNG: exposure, filmic curve,
 * sRGB, over the backdrop gradient) into a cairo RGB24 surface's pixels at
 * (x0, y0). */
void llplot_sphere_paint(const llplot_options *o, const llplot_image *img, unsigned char *data,
                         int stride, size_t x0, size_t y0);

/* Default sizes (see --help). */
#define LLPLOT_DEFAULT_BLOCK_SIZE 200
#define LLPLOT_DEFAULT_SPHERE_SIZE 320
#define LLPLOT_DEFAULT_POLAR_SIZE 760
#define LLPLOT_DEFAULT_SPP 32
#define LLPLOT_DEFAULT_GRID_CELL 128
#define LLPLOT_DEFAULT_GRID_SPP 16

#endif /* LLPLOT_H */
