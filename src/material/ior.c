/*
 * Named metals: spectra of n and k reduced to one complex index per colour
 * channel (see ior.h), and the list of places where the spectra are looked
 * for.
 */
#define _GNU_SOURCE /* dladdr: where the library itself was loaded from */
#include "material/ior.h"
#include "numerics/spline.h"
#include "support/parse_number.h"
#include "support/regular_file.h"

#include <dirent.h>
#include <dlfcn.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* ------------------------------------------------------------- spectra */

void ll_spectrum_free(ll_spectrum *s)
{
    if (!s)
        return;
    ll_free(s->lambda);
    ll_free(s->value);
    s->lambda = s->value = NULL;
    s->count = 0;
}

/* Append one sample, growing the arrays geometrically. */
static int spectrum_push(ll_spectrum *s, size_t *capacity, double lambda, double value)
{
    if (s->count == *capacity) {
        size_t cap = *capacity ? 2 * *capacity : 64;
        double *l = ll_realloc(s->lambda, cap * sizeof *l);
        double *v;
        if (!l)
            return 0;
        s->lambda = l;
        v = ll_realloc(s->value, cap * sizeof *v);
        if (!v)
            return 0;
        s->value = v;
        *capacity = cap;
    }
    s->lambda[s->count] = lambda;
    s->value[s->count] = value;
    s->count++;
    return 1;
}

/* Parse one line: blank and `#` lines give 0, a sample 1, garbage -1. */
static int parse_sample_line(const char *line, double *lambda, double *value)
{
    char *end;
    const char *p = line;
    while (*p == ' ' || *p == '\t')
        ++p;
    if (*p == '#' || *p == '\0' || *p == '\n' || *p == '\r')
        return 0;
    *lambda = ll_parse_double(p, &end);
    if (end == p)
        return -1;
    p = end;
    *value = ll_parse_double(p, &end);
    if (end == p)
        return -1;
    p = end;
    while (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n')
        ++p;
    return *p == '\0' ? 1 : -1;
}

ll_status ll_spectrum_read(const char *path, ll_spectrum *out)
{
    FILE *f;
    char *line = NULL;
    size_t line_cap = 0, capacity = 0, line_no = 0;
    long got;
    ll_status status = LL_OK;
    ll_spectrum s = { 0, NULL, NULL };

    out->count = 0;
    out->lambda = out->value = NULL;
    f = ll_fopen_regular(path, "the spectrum");
    if (!f)
        return LL_ERROR_IO;
    while ((got = ll_getline(&line, &line_cap, f)) >= 0) {
        double lambda, value;
        int kind = parse_sample_line(line, &lambda, &value);
        ++line_no;
        if (kind == 0)
            continue;
        if (kind < 0 || !ll_is_finite(lambda) || !ll_is_finite(value) || !(lambda > 0.0)) {
            status = ll_fail(LL_ERROR_FORMAT,
                             "%s:%zu: expected `wavelength value` (two finite numbers, "
                             "wavelength in nm > 0)",
                             path, line_no);
            goto fail;
        }
        if (s.count > 0 && !(lambda > s.lambda[s.count - 1])) {
            status = ll_fail(LL_ERROR_FORMAT,
                             "%s:%zu: wavelength %g nm does not increase (previous %g nm)", path,
                             line_no, lambda, s.lambda[s.count - 1]);
            goto fail;
        }
        if (!spectrum_push(&s, &capacity, lambda, value)) {
            status = ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory reading %s", path);
            goto fail;
        }
    }
    /* getline's -1 for ENOMEM would look like the end of the file and
     * silently truncate the spectrum: ll_getline says -2. */
    if (got == -2) {
        status = ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory reading %s", path);
        goto fail;
    }
    if (ferror(f)) {
        status = ll_fail(LL_ERROR_IO, "error reading the spectrum %s", path);
        goto fail;
    }
    if (s.count < 2) {
        status = ll_fail(LL_ERROR_FORMAT, "%s: a spectrum needs at least 2 samples, found %zu",
                         path, s.count);
        goto fail;
    }
    ll_free(line);
    fclose(f);
    *out = s;
    return LL_OK;
fail:
    ll_free(line);
    fclose(f);
    ll_spectrum_free(&s);
    return status;
}

/* The spectrum at lambda: Catmull-Rom between samples (the recipes use a
 * cubic interpolant too), the end values beyond the measured range. */
static double spectrum_at(const ll_spectrum *s, double lambda)
{
    ptrdiff_t offset;
    double w[4], sum = 0.0;
    int k;
    if (lambda <= s->lambda[0])
        return s->value[0];
    if (lambda >= s->lambda[s->count - 1])
        return s->value[s->count - 1];
    if (!ll_spline_weights(s->lambda, s->count, lambda, &offset, w, 0))
        return s->value[0];
    for (k = 0; k < 4; ++k)
        if (w[k] != 0.0)
            sum += w[k] * s->value[offset + k];
    return sum;
}

void ll_spectrum_to_xyz(const ll_spectrum *s, double xyz[3])
{
    /* Trapezoid rule on the 1 nm grid of the tabulated observer. */
    double sum[3] = { 0.0, 0.0, 0.0 }, y_sum = 0.0;
    size_t j;
    int c;
    for (j = 0; j < LL_CIE1931_COUNT; ++j) {
        double w = (j == 0 || j + 1 == LL_CIE1931_COUNT) ? 0.5 : 1.0;
        double v = spectrum_at(s, LL_CIE1931_FIRST_NM + (double)j);
        for (c = 0; c < 3; ++c)
            sum[c] += w * ll_cie1931_cmf[j][c] * v;
        y_sum += w * ll_cie1931_cmf[j][1];
    }
    for (c = 0; c < 3; ++c)
        xyz[c] = sum[c] / y_sum;
}

/* ---------------------------------------------------------------- metals */

/* dir + "/" + name + suffix, malloc'ed. */
static char *join_path(const char *dir, const char *name, const char *suffix)
{
    size_t a = strlen(dir), b = strlen(name), c = strlen(suffix), total;
    char *p;
    if (!ll_size_add(a, b, &total) || !ll_size_add(total, c + 2, &total))
        return NULL;
    p = ll_malloc(total);
    if (p)
        snprintf(p, total, "%s/%s%s", dir, name, suffix);
    return p;
}

ll_status ll_metal_ior_from_dir(const char *dir, const char *name, ll_metal_ior *out)
{
    char *eta_path = join_path(dir, name, ".eta.spd"), *k_path = join_path(dir, name, ".k.spd");
    ll_spectrum n = { 0, NULL, NULL }, k = { 0, NULL, NULL };
    double xyz_n[3], xyz_k[3];
    size_t j;
    ll_status s;

    if (!eta_path || !k_path) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory looking up the metal %s", name);
        goto done;
    }
    s = ll_spectrum_read(eta_path, &n);
    if (s == LL_OK)
        s = ll_spectrum_read(k_path, &k);
    if (s != LL_OK)
        goto done;
    /* n and k are averaged separately, as the recipes average the real and
     * imaginary parts of the complex index. */
    ll_spectrum_to_xyz(&n, xyz_n);
    ll_spectrum_to_xyz(&k, xyz_k);
    ll_xyz_to_linear_srgb(xyz_n, out->eta);
    ll_xyz_to_linear_srgb(xyz_k, out->k);
    out->eta_y = xyz_n[1];
    out->k_y = xyz_k[1];
    for (j = 0; j < LL_CIE1931_COUNT; ++j) {
        out->eta_nm[j] = spectrum_at(&n, LL_CIE1931_FIRST_NM + (double)j);
        out->k_nm[j] = spectrum_at(&k, LL_CIE1931_FIRST_NM + (double)j);
    }
done:
    ll_spectrum_free(&n);
    ll_spectrum_free(&k);
    ll_free(eta_path);
    ll_free(k_path);
    return s;
}

void ll_metal_ior_at(const ll_metal_ior *m, double nm, double *eta, double *k)
{
    double x = nm - LL_CIE1931_FIRST_NM, t;
    size_t j;
    if (!(x > 0.0))
        x = 0.0;
    if (x > (double)(LL_CIE1931_COUNT - 1))
        x = (double)(LL_CIE1931_COUNT - 1);
    j = (size_t)x;
    if (j >= LL_CIE1931_COUNT - 1)
        j = LL_CIE1931_COUNT - 2;
    t = x - (double)j;
    *eta = (1.0 - t) * m->eta_nm[j] + t * m->eta_nm[j + 1];
    *k = (1.0 - t) * m->k_nm[j] + t * m->k_nm[j + 1];
}

/* ----------------------------------------------------------- the search */

/* A growing '\n'-separated list of directories. */
typedef struct dir_list {
    char *text;
    size_t len, cap;
    int failed;
} dir_list;

static void list_add(dir_list *l, const char *a, const char *b)
{
    size_t add = strlen(a) + (b ? strlen(b) : 0) + 2;
    if (l->failed)
        return;
    if (l->len + add > l->cap) {
        size_t cap = 2 * (l->len + add) + 256;
        char *t = ll_realloc(l->text, cap);
        if (!t) {
            l->failed = 1;
            return;
        }
        l->text = t;
        l->cap = cap;
    }
    l->len += (size_t)snprintf(l->text + l->len, l->cap - l->len, "%s%s\n", a, b ? b : "");
}

/* Where the running library lives: the directory of the object that holds
 * this function's code (dladdr on a function, not on data, so that the
 * answer is the file the code was loaded from: liblayerlab.so for the
 * tools and the Python package, the program itself when it links
 * liblayerlab.a, as the tests do). The name is made absolute and free of
 * symlinks (realpath), so a library loaded by a relative path or through
 * its soname link gives its real folder; /proc/self/exe is the fallback
 * when dladdr knows no file. Written to buf; 0 if unknown. */
static int library_dir(char *buf, size_t size)
{
    ll_status (*self)(const char *, char **) = ll_ior_search_dirs;
    void *address;
    Dl_info info;
    char *real = NULL, *slash;
    ssize_t n = -1;

    /* A function pointer travels to dladdr's void * by its bytes (POSIX
     * requires the two to have the same representation; ISO C has no cast). */
    memcpy(&address, &self, sizeof address < sizeof self ? sizeof address : sizeof self);
    if (dladdr(address, &info) && info.dli_fname && info.dli_fname[0])
        real = ll_realpath(info.dli_fname);
    if (real && strlen(real) < size) {
        strcpy(buf, real);
        n = (ssize_t)strlen(buf);
    } else {
        n = readlink("/proc/self/exe", buf, size - 1);
        if (n > 0)
            buf[n] = '\0';
    }
    ll_free(real);
    if (n <= 0)
        return 0;
    slash = strrchr(buf, '/');
    if (!slash)
        return 0;
    if (slash == buf)
        slash[1] = '\0';
    else
        *slash = '\0';
    return 1;
}

ll_status ll_ior_search_dirs(const char *material_dir, char **out)
{
    dir_list l = { NULL, 0, 0, 0 };
    const char *env = getenv("LAYERLAB_IOR_DIR");
    char lib[4096];
    int have_lib = library_dir(lib, sizeof lib);

    *out = NULL;
    /* 1. The user's explicit choice: a colon-separated list. */
    if (env && *env) {
        const char *p = env;
        while (*p) {
            size_t len = strcspn(p, ":");
            if (len > 0 && len < 4096) {
                char dir[4096];
                memcpy(dir, p, len);
                dir[len] = '\0';
                list_add(&l, dir, NULL);
            }
            p += len;
            if (*p == ':')
                ++p;
        }
    }
    /* 2. Spectra kept next to the material. */
    if (material_dir)
        list_add(&l, material_dir, "/ior");
    /* 3. The spectra that come with the library, found from the library's
     *    own folder by one rule: PREFIX/lib -> PREFIX/share/layerlab/ior
     *    after `make install`, and build/lib (or build/tests, build/bin for
     *    programs linked statically) -> build/share/layerlab/ior in a build
     *    tree, where make copies the project's data/ior. Nothing depends on
     *    the working directory or on folders beside the checkout. */
    if (have_lib)
        list_add(&l, lib, "/../share/layerlab/ior");
    if (l.failed) {
        ll_free(l.text);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory listing the ior directories");
    }
    if (!l.text)
        list_add(&l, ".", NULL);
    *out = l.text;
    return l.failed ? ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory") : LL_OK;
}

/* Does dir hold both spectra of name? 1 yes, 0 no, -1 out of memory (not
 * "no": the search would go on and end in "unknown metal"). */
static int has_metal(const char *dir, const char *name)
{
    char *a = join_path(dir, name, ".eta.spd"), *b = join_path(dir, name, ".k.spd");
    int ok = !a || !b ? -1 : access(a, R_OK) == 0 && access(b, R_OK) == 0;
    ll_free(a);
    ll_free(b);
    return ok;
}

static int compare_names(const void *a, const void *b)
{
    return strcmp(*(const char *const *)a, *(const char *const *)b);
}

/* Append to msg (capacity cap) the metal names that dir offers, sorted. */
static void append_names(char *msg, size_t cap, const char *dir)
{
    static const char suffix[] = ".eta.spd";
    DIR *d = opendir(dir);
    struct dirent *e;
    char *names[64];
    size_t count = 0, len = strlen(msg), i, sl = sizeof suffix - 1;
    if (!d)
        return;
    while ((e = readdir(d)) != NULL && count < sizeof names / sizeof names[0]) {
        size_t n = strlen(e->d_name);
        if (n > sl && strcmp(e->d_name + n - sl, suffix) == 0) {
            names[count] = ll_malloc(n - sl + 1);
            if (!names[count])
                break;
            memcpy(names[count], e->d_name, n - sl);
            names[count++][n - sl] = '\0';
        }
    }
    closedir(d);
    qsort(names, count, sizeof names[0], compare_names);
    for (i = 0; i < count; ++i) {
        if (len + strlen(names[i]) + 3 < cap)
            len += (size_t)snprintf(msg + len, cap - len, "%s%s", len ? ", " : "", names[i]);
        ll_free(names[i]);
    }
}

ll_status ll_metal_ior_lookup(const char *name, const char *material_dir, ll_metal_ior *out)
{
    char *dirs = NULL, *p, names[400] = "";
    const char *first_existing = NULL;
    ll_status s;
    size_t k;
    int found;

    for (k = 0; name[k]; ++k) {
        char c = name[k];
        if (!((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
              c == '_' || c == '-'))
            return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                           "'%s' is not a metal name (letters, digits, '_' and '-' only)", name);
    }
    if (k == 0)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "the metal name is empty");
    s = ll_ior_search_dirs(material_dir, &dirs);
    if (s != LL_OK)
        return s;
    for (p = dirs; *p;) {
        char *nl = strchr(p, '\n');
        *nl = '\0';
        found = has_metal(p, name);
        if (found != 0) {
            s = found > 0 ? ll_metal_ior_from_dir(p, name, out)
                          : ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory looking up the metal %s",
                                    name);
            ll_free(dirs);
            return s;
        }
        if (!first_existing && access(p, X_OK) == 0)
            first_existing = p;
        p = nl + 1;
    }
    if (first_existing)
        append_names(names, sizeof names, first_existing);
    s = ll_fail(LL_ERROR_INVALID_ARGUMENT,
                "unknown metal '%s': no %s.eta.spd and %s.k.spd in $LAYERLAB_IOR_DIR, the "
                "material's ior/ folder or the library's ../share/layerlab/ior "
                "(%s%s%s%s)",
                name, name, name, first_existing ? "known in " : "no ior folder found",
                first_existing ? first_existing : "", first_existing ? ": " : "", names);
    ll_free(dirs);
    return s;
}
