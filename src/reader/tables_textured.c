/*
 * Extended table files: the `measured` container holding more than the
 * one opaque material the format describes. The field "layerlab_layout"
 * names what is present; such a file has no plain table fields, so a
 * renderer that knows only `measured` refuses it instead of rendering
 * part of it.
 *
 * A textured file ("textured" in the layout) holds one full set of table
 * fields per basis of the textured .bsdf it came from, named
 * "basis<k>." + the format's names (k from 0, the .bsdf's basis index,
 * parameter 0 fastest), and the parameters as the .bsdf's parameter block
 * holds them: "layerlab_parameter_counts" (float32 [P], whole numbers,
 * their product the number of bases) and "layerlab_parameter_positions"
 * (float32 [sum of counts], each parameter's positions strictly
 * ascending). "layerlab_metadata" is the .bsdf's own metadata text, so
 * the parameter names and ll_bsdf_basis_coefficients read as on the
 * .bsdf. Every field is checked before anything it sizes is allocated.
 *
 * Evaluation blends the bases with the caller's weights as the Fourier
 * path does (a weight of 0 is not visited). Sampling picks basis k with
 * probability |w_k| / sum |w_j| and samples its tables; the density is
 * that mixture of the bases' densities, exact for the sampler whatever
 * the weights. The hat weights of ll_bsdf_basis_coefficients are
 * non-negative and sum to 1, where this is sampling by the blend's own
 * weights; a caller's negative weights are sampled by their magnitude.
 */
#include "reader/tables_internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* Parameters and bases a textured table file may have: the material
 * language makes at most 4 axes; each basis takes about ten fields of the
 * container (LL_TENSOR_MAX_FIELDS). */
#define LL_MEASURED_MAX_PARAMETERS 16
#define LL_MEASURED_MAX_BASES 1024

#define FAIL(status, ...) do { s = ll_fail(status, __VA_ARGS__); goto done; } while (0)

/* The parameter block, checked as the .bsdf reader checks its own, into
 * b (n_parameters, n_parameter_values, n_bases and their arrays). */
static ll_status read_parameters(const ll_tensor_file *t, const char *file, ll_bsdf *b)
{
    const ll_tensor_field *counts = ll_tensor_find(t, "layerlab_parameter_counts");
    const ll_tensor_field *pos = ll_tensor_find(t, "layerlab_parameter_positions");
    size_t p, k, total = 0, bases = 1;
    if (!counts || !pos)
        return ll_fail(LL_ERROR_FORMAT, "ll_bsdf_open: %s: field \"%s\" is missing", file,
                       counts ? "layerlab_parameter_positions" : "layerlab_parameter_counts");
    if (counts->dtype != LL_TENSOR_F32 || counts->rank != 1 || counts->count == 0 ||
        counts->count > LL_MEASURED_MAX_PARAMETERS)
        return ll_fail(LL_ERROR_FORMAT,
                       "ll_bsdf_open: %s: field \"layerlab_parameter_counts\" must be float32 "
                       "of rank 1 with 1..%d elements",
                       file, LL_MEASURED_MAX_PARAMETERS);
    for (p = 0; p < counts->count; ++p) {
        float c = ll_tensor_f32(counts, p);
        if (!(c >= 1.0f && c <= (float)LL_MEASURED_MAX_BASES) || c != floorf(c))
            return ll_fail(LL_ERROR_FORMAT,
                           "ll_bsdf_open: %s: field \"layerlab_parameter_counts\": element %zu "
                           "= %g is not a whole number in 1..%d",
                           file, p, (double)c, LL_MEASURED_MAX_BASES);
        total += (size_t)c;
        bases *= (size_t)c; /* each factor <= 1024, checked below at once */
        if (bases > LL_MEASURED_MAX_BASES)
            return ll_fail(LL_ERROR_FORMAT,
                           "ll_bsdf_open: %s: field \"layerlab_parameter_counts\": more than "
                           "%d bases",
                           file, LL_MEASURED_MAX_BASES);
    }
    if (pos->dtype != LL_TENSOR_F32 || pos->rank != 1 || pos->count != total)
        return ll_fail(LL_ERROR_FORMAT,
                       "ll_bsdf_open: %s: field \"layerlab_parameter_positions\" must be "
                       "float32 of rank 1 with %zu elements (the sum of the counts)",
                       file, total);
    b->n_parameters = counts->count;
    b->n_parameter_values = total;
    b->n_bases = bases;
    b->param_counts = ll_alloc_array(b->n_parameters, sizeof *b->param_counts);
    b->param_first = ll_alloc_array(b->n_parameters, sizeof *b->param_first);
    b->param_positions = ll_alloc_array(total, sizeof *b->param_positions);
    if (!b->param_counts || !b->param_first || !b->param_positions)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_bsdf_open: %s: out of memory", file);
    for (p = 0, total = 0; p < b->n_parameters; ++p) {
        b->param_counts[p] = (uint32_t)ll_tensor_f32(counts, p);
        b->param_first[p] = total;
        for (k = 0; k < b->param_counts[p]; ++k, ++total) {
            float x = ll_tensor_f32(pos, total);
            if (!isfinite(x) || (k > 0 && !(x > b->param_positions[total - 1])))
                return ll_fail(LL_ERROR_FORMAT,
                               "ll_bsdf_open: %s: field \"layerlab_parameter_positions\": "
                               "parameter %zu: position %zu = %g is not finite or not above "
                               "the one before",
                               file, p, k, (double)x);
            b->param_positions[total] = x;
        }
    }
    return LL_OK;
}

ll_status ll_measured_open_textured(const ll_tensor_file *t, size_t file_size,
                                    const char *file, ll_bsdf **out)
{
    ll_bsdf *b = NULL;
    size_t k;
    ll_status s = LL_OK;
    b = ll_calloc(1, sizeof *b);
    if (!b)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_bsdf_open: %s: out of memory", file);
    b->refcount = 1;
    b->n_channels = 3;
    b->eta = 1.0;
    b->file_size = file_size;
    if ((s = read_parameters(t, file, b)) != LL_OK)
        goto done;
    /* Every basis' fields exist before any set is built. */
    for (k = 0; k < b->n_bases; ++k) {
        char name[LL_TENSOR_MAX_NAME + 1];
        snprintf(name, sizeof name, "basis%zu.theta_i", k);
        if (!ll_tensor_find(t, name))
            FAIL(LL_ERROR_FORMAT, "ll_bsdf_open: %s: field \"%s\" is missing (%zu bases)", file,
                 name, b->n_bases);
    }
    b->measured_bases = ll_calloc_array(b->n_bases, sizeof *b->measured_bases);
    if (!b->measured_bases)
        FAIL(LL_ERROR_OUT_OF_MEMORY, "ll_bsdf_open: %s: out of memory", file);
    for (k = 0; k < b->n_bases; ++k) {
        char prefix[32];
        snprintf(prefix, sizeof prefix, "basis%zu.", k);
        if ((s = ll_measured_read_set(t, prefix, file, &b->measured_bases[k])) != LL_OK)
            goto done;
        if (b->measured_bases[k]->n_wavelengths != b->measured_bases[0]->n_wavelengths)
            FAIL(LL_ERROR_FORMAT,
                 "ll_bsdf_open: %s: field \"%swavelengths\": basis %zu has %zu wavelengths, "
                 "basis 0 %zu (the bases are one material)",
                 file, prefix, k, b->measured_bases[k]->n_wavelengths,
                 b->measured_bases[0]->n_wavelengths);
    }
    b->measured = b->measured_bases[0];
    if ((s = ll_measured_copy_metadata(b, t, file)) != LL_OK)
        goto done;
    if (!ll_bsdf_read_parameter_names(b))
        FAIL(LL_ERROR_OUT_OF_MEMORY, "ll_bsdf_open: %s: out of memory", file);
done:
    if (s != LL_OK) {
        ll_bsdf_free(b);
        return s;
    }
    *out = b;
    return LL_OK;
}

/* ------------------------------------------------------------ blending */

void ll_measured_blend_eval(const ll_bsdf *b, const double wi[3], const double wo[3],
                            const float *basis, double value[3])
{
    size_t k;
    value[0] = value[1] = value[2] = 0.0;
    for (k = 0; k < b->n_bases; ++k) {
        double v[3], w = (double)basis[k];
        if (w == 0.0)
            continue;
        ll_measured_eval(ll_measured_basis(b, k), wi, wo, v);
        value[0] += w * v[0];
        value[1] += w * v[1];
        value[2] += w * v[2];
    }
}

double ll_measured_blend_pdf(const ll_bsdf *b, const double wi[3], const double wo[3],
                             const float *basis)
{
    double sum = 0.0, total = 0.0;
    size_t k;
    /* One set: its own density, whatever its weight (as before textures). */
    if (b->n_bases == 1)
        return ll_measured_pdf(b->measured, wi, wo);
    for (k = 0; k < b->n_bases; ++k) {
        double w = fabs((double)basis[k]);
        if (w == 0.0)
            continue;
        total += w;
        sum += w * ll_measured_pdf(ll_measured_basis(b, k), wi, wo);
    }
    return total > 0.0 ? sum / total : 0.0;
}

int ll_measured_blend_sample(const ll_bsdf *b, const double wi[3], const double u[2],
                             const float *basis, double wo[3], double *pdf, double value[3])
{
    double total = 0.0, before = 0.0, target, v[3], w_pick, pdf_pick, uu[2];
    size_t k, pick = 0, last = 0;
    int any = 0;
    if (b->n_bases == 1) {
        double w = (double)basis[0];
        if (!ll_measured_sample(b->measured, wi, u, wo, pdf, value))
            return 0;
        value[0] *= w;
        value[1] *= w;
        value[2] *= w;
        return 1;
    }
    for (k = 0; k < b->n_bases; ++k)
        total += fabs((double)basis[k]);
    wo[0] = wo[1] = 0.0;
    wo[2] = 1.0;
    *pdf = 0.0;
    value[0] = value[1] = value[2] = 0.0;
    if (!(total > 0.0) || !ll_is_finite(total))
        return 0;
    /* The basis whose share of [0, total) holds u[0] total; the last of
     * non-zero weight takes what rounding leaves over. */
    target = u[0] * total;
    for (k = 0; k < b->n_bases; ++k) {
        double w = fabs((double)basis[k]);
        if (w == 0.0)
            continue;
        last = k;
        if (!any && target < before + w) {
            pick = k;
            any = 1;
            break;
        }
        before += w;
    }
    if (!any) {
        pick = last;
        before = total - fabs((double)basis[last]);
    }
    w_pick = fabs((double)basis[pick]);
    uu[0] = (target - before) / w_pick;
    uu[0] = uu[0] < 0.0 ? 0.0 : uu[0] < 1.0 ? uu[0] : 1.0 - 0x1p-53;
    uu[1] = u[1];
    if (!ll_measured_sample(ll_measured_basis(b, pick), wi, uu, wo, &pdf_pick, v))
        return 0;
    /* The blend at wo: the picked basis' own values, the others' evaluated. */
    *pdf = w_pick * pdf_pick;
    for (k = 0; k < 3; ++k)
        value[k] = (double)basis[pick] * v[k];
    for (k = 0; k < b->n_bases; ++k) {
        double w = (double)basis[k], vk[3];
        if (w == 0.0 || k == pick)
            continue;
        *pdf += fabs(w) * ll_measured_pdf(ll_measured_basis(b, k), wi, wo);
        ll_measured_eval(ll_measured_basis(b, k), wi, wo, vk);
        value[0] += w * vk[0];
        value[1] += w * vk[1];
        value[2] += w * vk[2];
    }
    *pdf /= total;
    return *pdf > 0.0;
}
