/*
 * An opened table file of the `measured` format (docs/formats.md)
 * behind an ll_bsdf handle: the 2D warps of its fields, and evaluation and
 * sampling as the renderers' `measured` readers do them. Reader side.
 *
 * Directions here are in the format's own convention: wi the direction
 * held fixed (towards the viewer), wo the one evaluated or sampled
 * (towards the light), both unit vectors in the shading frame, z the
 * normal. Values are f cos(theta_o), as Mitsuba's BSDF returns them; the
 * public calls divide by the cosine.
 */
#ifndef LL_TABLES_INTERNAL_H
#define LL_TABLES_INTERNAL_H

#include "reader/bsdf_internal.h"
#include "reader/tables_warp.h"
#include "reader/tensor.h"

typedef struct ll_measured {
    ll_warp2d ndf;        /* D over (u_phi, u_theta) of the normal          */
    ll_warp2d sigma;      /* projected area over the incident direction     */
    ll_warp2d vndf;       /* sampling, parameters (phi_i, theta_i)          */
    ll_warp2d luminance;  /* sampling, parameters (phi_i, theta_i)          */
    ll_warp2d rgb;        /* values, parameters (phi_i, theta_i, channel)   */
    int jacobian;         /* stored values are f cos over D / (4 sigma)     */
    size_t n_wavelengths; /* a spectral file's (its rgb: converted), or 0   */
    /* An extended file (field "layerlab_layout", tables_lobes.c) holds a
     * set of the tables above per lobe, each an ll_measured of its own,
     * indexed by ll_measured_lobe (NULL where the file has none); its own
     * tables above are then empty. All NULL in a plain file. */
    struct ll_measured *lobe[4];
    int extended;
    double eta;           /* extended: index below over index above       */
    /* A lobe's: its luminance albedo at each incident elevation of the
     * file (the weight by which the sampler picks it), and for a
     * transmitted lobe across a net interface the relative index of the
     * far side over the fixed direction's side, which selects the
     * refraction warp (0: reflection, or the warp of the z-flipped
     * direction where the stack has no net interface); for a reflected
     * lobe whose values are stored over the Fresnel reflectance of its
     * half vector (field "fresnel_eta", tables_lobes.c), that relative
     * index, else 0, and its floor k (field "fresnel_floor": the values
     * are over (F + q) / (1 + q), q = k D(0) / D(m) by the set's ndf,
     * tables_refract.h; 0 without the field); for a refracted
     * lobe whose values are stored over its refraction's transmittance
     * (field "transmittance_eta",
     * tables_refract.h), its refract_eta, else 0. */
    double *weight;
    /* A transmitted lobe's relative index of the far side over the fixed
     * direction's side (the file's eta for transmit_top, its inverse for
     * transmit_bottom): how fast a set of the z-flipped warp turns wo with
     * wi between elevations (tables_refract.c). */
    double side_eta;
    double refract_eta;
    double fresnel_eta;
    double fresnel_floor;
    double transmittance_eta;
} ll_measured;

/* The lobes of an extended file, by the side of the fixed direction. */
typedef enum {
    LL_LOBE_REFLECT_TOP = 0,
    LL_LOBE_REFLECT_BOTTOM = 1,
    LL_LOBE_TRANSMIT_TOP = 2,
    LL_LOBE_TRANSMIT_BOTTOM = 3
} ll_measured_lobe;
#define LL_MEASURED_LOBES 4
/* Their field-name prefixes ("reflect_top." ...). */
LL_INTERNAL const char *ll_measured_lobe_prefix(int lobe);

/* The extended file's calls behind ll_measured_eval, _pdf and _sample
 * (tables_lobes.c): wi and wo on any sides. */
LL_INTERNAL void ll_measured_lobes_eval(const ll_measured *m, const double wi[3],
                                        const double wo[3], double value[3]);
LL_INTERNAL double ll_measured_lobes_pdf(const ll_measured *m, const double wi[3],
                                         const double wo[3]);
LL_INTERNAL int ll_measured_lobes_sample(const ll_measured *m, const double wi[3],
                                         const double u[2], double wo[3], double *pdf,
                                         double value[3]);
/* One transmitted lobe (tables_refract.c), in its own frame: wi above, wo
 * below; the refraction warp of relative index m->refract_eta, or where
 * that is 0 the warp of the z-flipped direction. */
LL_INTERNAL void ll_measured_refract_eval(const ll_measured *m, const double wi[3],
                                          const double wo[3], double value[3]);
LL_INTERNAL double ll_measured_refract_pdf(const ll_measured *m, const double wi[3],
                                           const double wo[3]);
LL_INTERNAL int ll_measured_refract_sample(const ll_measured *m, const double wi[3],
                                           const double u[2], double wo[3], double *pdf,
                                           double value[3]);

/* Open a table file held in data[0 .. size) (validated completely; the
 * bytes are not kept). file names it in messages. */
LL_INTERNAL ll_status ll_measured_open(const unsigned char *data, size_t size, const char *file,
                                       ll_bsdf **out);
LL_INTERNAL void ll_measured_free(ll_measured *m);

/* One material of a parsed file: its fields named prefix +
 * the format's names ("" the plain file, "basis3." a textured file's
 * basis 3), every one checked as ll_measured_open checks them (errors
 * name the field in full). A basis' grids (vndf, luminance, rgb or
 * spectra) may be float16, the plain file's are float32. */
LL_INTERNAL ll_status ll_measured_read_set(const ll_tensor_file *t, const char *prefix,
                                           const char *file, ll_measured **out);
/* b->metadata from the field "layerlab_metadata" (else "description"). */
LL_INTERNAL ll_status ll_measured_copy_metadata(ll_bsdf *b, const ll_tensor_file *t,
                                                const char *file);
/* An extended file's "layerlab_layout" field f: the lobe sets it names
 * (present[k]) or "textured" (*textured), each at most once, nothing else
 * (tables_read.c). */
LL_INTERNAL ll_status ll_measured_read_layout(const ll_tensor_field *f, const char *file,
                                              int present[LL_MEASURED_LOBES], int *textured);
/* A textured table file (its layout "textured", tables_textured.c): the
 * parameters and a set per basis. file_size: the file's bytes. */
LL_INTERNAL ll_status ll_measured_open_textured(const ll_tensor_file *t, size_t file_size,
                                                const char *file, ll_bsdf **out);

/* Set k of a table handle: basis k of a textured table file, the only
 * set of an untextured one (k = 0). */
static inline const ll_measured *ll_measured_basis(const ll_bsdf *b, size_t k)
{
    return b->measured_bases ? b->measured_bases[k] : b->measured;
}

/* The blend of a table handle's bases with the weights basis[0 ..
 * n_bases) (tables_textured.c; bases of weight 0 are not visited), in
 * the format's convention as the single-set calls above:
 * eval: sum_k w_k f_k cos;
 * pdf: the density of sample, sum_k |w_k| pdf_k / sum_k |w_k|;
 * sample: a basis picked with probability |w_k| / sum |w_k| by u[0]
 *   (rescaled to [0, 1) and passed on), wo sampled from it; the pdf and
 *   value of the blend there. 0 if no direction (or every weight 0). */
LL_INTERNAL void ll_measured_blend_eval(const ll_bsdf *b, const double wi[3], const double wo[3],
                                        const float *basis, double value[3]);
LL_INTERNAL double ll_measured_blend_pdf(const ll_bsdf *b, const double wi[3],
                                         const double wo[3], const float *basis);
LL_INTERNAL int ll_measured_blend_sample(const ll_bsdf *b, const double wi[3], const double u[2],
                                         const float *basis, double wo[3], double *pdf,
                                         double value[3]);

/* The fixed direction wi as every look-up of a call needs it: its
 * elevation, the slices of its parameters, and its azimuth phi_i in the
 * forms that are used. The half vector's azimuth is only ever read
 * relative to phi_i (the files are isotropic), and that difference is one
 * atan2 of the half vector in wi's own azimuthal frame; phi_i itself is
 * taken only where a table depends on it (a file with two incident
 * azimuths, or a sigma that varies along the azimuth), and wi's unit
 * azimuth vector only where the sampler turns a normal by it. */
typedef struct ll_measured_incident {
    double theta, u_theta, u_phi;
    double ax, ay;            /* wi's azimuth vector (unit if asked for)   */
    int has_azimuth;          /* wi is not (next to) the normal            */
    double phi;               /* phi_i where it is read, else 0            */
    ll_warp_slices sl;
} ll_measured_incident;

/* One look-up of a plain (not extended) set, split where it waits on
 * memory, so that the batch calls (tables_batch.c) can run the steps of
 * several look-ups interleaved while each one's tables are fetched; the
 * scalar calls below run the same steps in a row, so both give the same
 * bits. What a look-up carries from one step to the next: */
typedef struct ll_measured_look {
    ll_measured_incident in;
    double wi[3];             /* the fixed direction                       */
    double m[3], um[2];       /* the normal and its square's coordinates
                                 (eval and pdf: m is wi + wo, the normal
                                 times a positive length)                */
    double theta_m;
    ll_warp_draw dr;          /* draw: the current warp's sampling        */
    double s[2];              /* the sample square's point                 */
    double p_v, p_l;          /* the vndf's and the luminance's densities  */
} ll_measured_look;

/* eval and pdf at (wi, wo): _begin takes the half vector and its
 * coordinates (0: wi and wo are not both above the surface; the value and
 * pdf are 0); _invert reads the vndf warp there (its nodes: asked for by
 * _prefetch_vndf); _value and _pdf read the values or the luminance at the
 * point found (asked for by _prefetch_values, pdf nonzero for the
 * luminance). */
LL_INTERNAL int ll_measured_look_begin(const ll_measured *t, const double wi[3],
                                       const double wo[3], ll_measured_look *lk);
LL_INTERNAL void ll_measured_look_prefetch_vndf(const ll_measured *t, const ll_measured_look *lk);
LL_INTERNAL void ll_measured_look_invert(const ll_measured *t, ll_measured_look *lk);
LL_INTERNAL void ll_measured_look_prefetch_values(const ll_measured *t,
                                                  const ll_measured_look *lk, int pdf);
LL_INTERNAL void ll_measured_look_value(const ll_measured *t, const ll_measured_look *lk,
                                        double value[3]);
LL_INTERNAL double ll_measured_look_pdf(const ll_measured *t, const ll_measured_look *lk);
/* sample from u given wi: _begin (0: wi is not above the surface; no
 * direction) starts the luminance warp's sampling (ll_warp2d_draw_begin)
 * and asks for the stretch of its rows that it reads; _middle reads it,
 * then starts the vndf warp's sampling and asks for its stretch and for
 * the values at the luminance's point; _end reads those and gives what
 * ll_measured_sample gives. */
LL_INTERNAL int ll_measured_draw_begin(const ll_measured *t, const double wi[3],
                                       const double u[2], ll_measured_look *lk);
LL_INTERNAL void ll_measured_draw_middle(const ll_measured *t, ll_measured_look *lk);
LL_INTERNAL int ll_measured_draw_end(const ll_measured *t, ll_measured_look *lk, double wo[3],
                                     double *pdf, double value[3]);

/* f cos(theta_o) of the channels R, G, B at (wi, wo); 0 below the surface. */
LL_INTERNAL void ll_measured_eval(const ll_measured *m, const double wi[3], const double wo[3],
                                  double value[3]);
/* Density (per solid angle of wo) of ll_measured_sample. */
LL_INTERNAL double ll_measured_pdf(const ll_measured *m, const double wi[3], const double wo[3]);
/* Sample wo given wi from u in [0, 1]^2 (u[1] drives the elevation-like
 * coordinate, as Mitsuba's swapped sample): wo, its pdf and f cos there.
 * 0 if no direction (below the horizon). */
LL_INTERNAL int ll_measured_sample(const ll_measured *m, const double wi[3], const double u[2],
                                   double wo[3], double *pdf, double value[3]);

/* The layer-convention cores of ll_bsdf_internal.h for a table handle. */
LL_INTERNAL void ll_measured_eval_cos(const ll_bsdf *b, double mu_i, double mu_o, double cos_phi,
                                      const float *basis, double extra_scale, double rgb[3]);
LL_INTERNAL double ll_measured_pdf_cos(const ll_bsdf *b, double mu_i, double mu_o,
                                       double cos_phi, const float *basis);
LL_INTERNAL int ll_measured_sample_core(const ll_bsdf *b, double mu_i, const double u[2],
                                        const float *basis, double *mu_o, double *phi_d,
                                        double *pdf, double sums[3]);

/* What the reflected (tables_eval.c) and refracted (tables_refract.c)
 * lobes share. ll_measured_values_at: the channels of t at s times scale,
 * negatives cut to 0; channel c hits node c of the 3 exactly (as the
 * renderers evaluate an RGB file at 0, 1, 2). ll_measured_normal_area:
 * the area of the normal's square per steradian of normals, 2 pi^2
 * u_theta sin theta_m, kept from 0 (the pole) so that a pdf stays finite. */
static inline void ll_measured_values_at(const ll_measured *t, const ll_warp_slices *sl,
                                         const double s[2], double scale, double value[3])
{
    size_t c;
    ll_warp2d_eval_nodes(&t->rgb, sl, 3, s, value);
    for (c = 0; c < 3; ++c) {
        double v = value[c] * scale;
        value[c] = v > 0.0 ? v : 0.0;
    }
}

static inline double ll_measured_normal_area_sin(double u_theta_m, double sin_theta_m)
{
    double area = 2.0 * LL_PI * LL_PI * u_theta_m * sin_theta_m;
    return area < 1e-6 ? 1e-6 : area;
}

static inline double ll_measured_normal_area(double u_theta_m, double theta_m)
{
    return ll_measured_normal_area_sin(u_theta_m, sin(theta_m));
}

#endif /* LL_TABLES_INTERNAL_H */
