/*
 * llplot --sphere: the lighting, in one place for the renderer and for the
 * tests that check it.
 *
 * World frame: x right, y up, z toward the (orthographic) camera. The
 * environment is a neutral studio sky that depends on the elevation only:
 * a dark ground, and above it a sky brightest at the horizon and slightly
 * darker toward the zenith,
 *     L(w) = G + (S + Z max(w_y, 0)) s(w_y)        (per channel),
 * where s rises smoothly from 0 to 1 across the horizon band |w_y| < H
 * (a sharp horizon would make the Monte Carlo estimate noisy wherever a
 * glossy lobe straddles it). A warm directional key light of irradiance
 * E_KEY shines from the upper left. A Lambertian sphere of albedo a must
 * shade as
 *     L_o(n) = a / pi * (E_env(n) + E_KEY max(n . l, 0)),
 * where E_env, the irradiance from the sky, is the 1D integral that
 * llplot_env_irradiance evaluates by quadrature (the tests compare against
 * it; the renderer never uses it).
 */
#ifndef LLPLOT_SCENE_H
#define LLPLOT_SCENE_H

#include <math.h>

#define LLPLOT_SCENE_PI 3.14159265358979323846

/* Radiance terms (linear sRGB). */
#define LLPLOT_ENV_GROUND_R 0.075
#define LLPLOT_ENV_GROUND_G 0.067
#define LLPLOT_ENV_GROUND_B 0.058
#define LLPLOT_ENV_SKY_R 0.64
#define LLPLOT_ENV_SKY_G 0.62
#define LLPLOT_ENV_SKY_B 0.58
#define LLPLOT_ENV_ZENITH_R -0.14
#define LLPLOT_ENV_ZENITH_G -0.14
#define LLPLOT_ENV_ZENITH_B -0.12
/* Half-width of the horizon band, in w_y. */
#define LLPLOT_ENV_HORIZON 0.12

/* Key light: irradiance on a surface facing it, and its direction (toward
 * the light, normalised by llplot_key_direction). */
#define LLPLOT_KEY_E_R 2.70
#define LLPLOT_KEY_E_G 2.55
#define LLPLOT_KEY_E_B 2.30
#define LLPLOT_KEY_X -0.50
#define LLPLOT_KEY_Y 0.65
#define LLPLOT_KEY_Z 0.57

/* The sphere's radius as a fraction of half the image side. */
#define LLPLOT_SPHERE_RADIUS 0.9

static inline void llplot_env_terms(double ground[3], double sky[3], double zenith[3])
{
    const double g[3] = { LLPLOT_ENV_GROUND_R, LLPLOT_ENV_GROUND_G, LLPLOT_ENV_GROUND_B };
    const double s[3] = { LLPLOT_ENV_SKY_R, LLPLOT_ENV_SKY_G, LLPLOT_ENV_SKY_B };
    const double z[3] = { LLPLOT_ENV_ZENITH_R, LLPLOT_ENV_ZENITH_G, LLPLOT_ENV_ZENITH_B };
    int c;
    for (c = 0; c < 3; ++c) {
        ground[c] = g[c];
        sky[c] = s[c];
        zenith[c] = z[c];
    }
}

static inline void llplot_key_direction(double l[3])
{
    const double d[3] = { LLPLOT_KEY_X, LLPLOT_KEY_Y, LLPLOT_KEY_Z };
    double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    int c;
    for (c = 0; c < 3; ++c)
        l[c] = d[c] / len;
}

static inline void llplot_key_irradiance(double e[3])
{
    const double k[3] = { LLPLOT_KEY_E_R, LLPLOT_KEY_E_G, LLPLOT_KEY_E_B };
    int c;
    for (c = 0; c < 3; ++c)
        e[c] = k[c];
}

/* The horizon blend: 0 below the band, 1 above, smoothstep in between. */
static inline double llplot_env_sky_weight(double w_y)
{
    double t = (w_y + LLPLOT_ENV_HORIZON) / (2.0 * LLPLOT_ENV_HORIZON);
    if (t <= 0.0)
        return 0.0;
    if (t >= 1.0)
        return 1.0;
    return t * t * (3.0 - 2.0 * t);
}

/* Environment radiance arriving from world direction w (unit). */
static inline void llplot_env_radiance(const double w[3], double rgb[3])
{
    double ground[3], sky[3], zenith[3], s = llplot_env_sky_weight(w[1]);
    int c;
    llplot_env_terms(ground, sky, zenith);
    for (c = 0; c < 3; ++c)
        rgb[c] = ground[c] + s * (sky[c] + zenith[c] * (w[1] > 0.0 ? w[1] : 0.0));
}

/* Irradiance from the environment alone on a surface of unit normal n.
 * The sky is symmetric about the y axis, so with w_y = cos(a) the azimuthal
 * part of the cosine integral has a closed form,
 *     int_0^2pi max(A cos(b) + B, 0) db,  A = sin(a) |n_xz|, B = cos(a) n_y,
 * which is 2 pi B when B >= A, 0 when B <= -A, and otherwise
 * 2 (A sin(b0) + B b0) with cos(b0) = -B / A; the remaining integral over
 * the elevation a is done with the midpoint rule (the integrand is smooth
 * but for kinks, so 20000 steps give about 1e-8 relative accuracy). */
static inline void llplot_env_irradiance(const double n[3], double rgb[3])
{
    enum { STEPS = 20000 };
    double ny = n[1] > 1.0 ? 1.0 : n[1] < -1.0 ? -1.0 : n[1];
    double nxz = sqrt(1.0 - ny * ny), da = LLPLOT_SCENE_PI / STEPS;
    int k, c;
    for (c = 0; c < 3; ++c)
        rgb[c] = 0.0;
    for (k = 0; k < STEPS; ++k) {
        double a = (k + 0.5) * da, A = sin(a) * nxz, B = cos(a) * ny, ring, w[3], L[3];
        if (B >= A)
            ring = 2.0 * LLPLOT_SCENE_PI * B;
        else if (B <= -A)
            ring = 0.0;
        else {
            double b0 = acos(-B / A);
            ring = 2.0 * (A * sin(b0) + B * b0);
        }
        w[0] = sin(a);
        w[1] = cos(a);
        w[2] = 0.0;
        llplot_env_radiance(w, L);
        for (c = 0; c < 3; ++c)
            rgb[c] += L[c] * ring * sin(a) * da;
    }
}

#endif /* LLPLOT_SCENE_H */
