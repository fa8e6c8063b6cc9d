/*
 * The vector loops of the profile (words/microfacet_profile.c), written
 * once for every register width: microfacet_profile.c includes this file
 * once per width (no include guard) after defining
 *   PV                     the register type,
 *   PW                     its doubles,
 *   PFN(name)              the name of this width's copy of a function,
 *   PATTR                  the attribute its functions need (a target),
 *   P_SET1(x), P_ZERO()    broadcast, zero,
 *   P_ADD, P_SUB, P_MUL, P_DIV, P_SQRT,
 *   P_AND, P_ANDNOT, P_OR  (bits),
 *   P_GT, P_LT, P_LE       (comparisons to masks, false for a NaN),
 *   P_LOADU, P_STOREU,
 * which it undefines at its end. Each loop keeps the scalar formula's
 * operations in its order, so that every width gives every sample the
 * same double (tests/test_microfacet_profile.c).
 */

/* (x > 0 ? x : 0, x < hi ? x : hi, mask ? a : b, |x|) PW at a time */
#define P_POSITIVE(x) P_AND(P_GT(x, P_ZERO()), x)
#define P_SELECT(mask, a, b) P_OR(P_AND(mask, a), P_ANDNOT(mask, b))
#define P_BELOW(x, hi) P_SELECT(P_LT(x, hi), x, hi)
#define P_ABS(x) P_ANDNOT(P_SET1(-0.0), x)

/* dielectric_fresnel PW at a time: the same operations on each (IEEE's
 * +, -, *, / and sqrt round the same in a vector register; ISO C's mode
 * contracts nothing into fused multiply-adds), with the branch as a
 * selection: a totally reflected sample (cos_t2 <= 0) takes F = 1 instead
 * of the amplitudes, which are computed from sqrt(max(cos_t2, 0)) and
 * dropped. */
PATTR static inline PV PFN(dielectric_fresnel)(PV cos_i, PV eta, PV inv_eta)
{
    PV one = P_SET1(1.0), zero = P_ZERO();
    PV sc = P_SELECT(P_GT(cos_i, zero), inv_eta, eta);
    PV cos_t2 = P_SUB(one, P_MUL(P_SUB(one, P_MUL(cos_i, cos_i)), P_MUL(sc, sc)));
    PV ci = P_ABS(cos_i), ct = P_SQRT(P_POSITIVE(cos_t2));
    PV e_ct = P_MUL(eta, ct), e_ci = P_MUL(eta, ci);
    PV rs = P_DIV(P_SUB(ci, e_ct), P_ADD(ci, e_ct));
    PV rp = P_DIV(P_SUB(e_ci, ct), P_ADD(e_ci, ct));
    PV f = P_MUL(P_SET1(0.5), P_ADD(P_MUL(rs, rs), P_MUL(rp, rp)));
    return P_SELECT(P_LE(cos_t2, zero), one, f);
}

/* ll_fresnel_conductor_kernel PW at a time, the same operations; a2 and
 * b4 its per-pair eta_re^2 - eta_im^2 and 4 eta_im^2 eta_re^2 (fmax(0,
 * x) is 0 for the x < 0 that rounding may give, and x is never -0). */
PATTR static inline PV PFN(conductor_fresnel)(PV cos_i, PV a2, PV b4)
{
    PV one = P_SET1(1.0), half = P_SET1(0.5);
    PV c2 = P_MUL(cos_i, cos_i), s2 = P_SUB(one, c2), s4 = P_MUL(s2, s2);
    PV t1 = P_SUB(a2, s2);
    PV a2pb2 = P_SQRT(P_ADD(P_MUL(t1, t1), b4));
    PV a = P_SQRT(P_POSITIVE(P_MUL(half, P_ADD(a2pb2, t1))));
    PV term1 = P_ADD(a2pb2, c2);
    PV term2 = P_MUL(P_MUL(P_SET1(2.0), a), cos_i);
    PV rs2 = P_DIV(P_SUB(term1, term2), P_ADD(term1, term2));
    PV term3 = P_ADD(P_MUL(a2pb2, c2), s4), term4 = P_MUL(term2, s2);
    PV rp2 = P_DIV(P_MUL(rs2, P_SUB(term3, term4)), P_ADD(term3, term4));
    return P_MUL(half, P_ADD(rp2, rs2));
}

/* The samples of reflect_profile with the Fresnel factor PW at a time;
 * returns the samples done (count rounded down to a multiple of PW). */
PATTR static size_t PFN(reflect)(const pair_plan *p, const reflect_constants *rc,
                                 const double *cos_phi, size_t count, double *g,
                                 double *no_fresnel)
{
    PV neg_sin = P_SET1(-p->sin_prod), mu_prod = P_SET1(p->mu_prod);
    PV s = P_SET1(p->sign_h), scale = P_SET1(p->scale);
    PV one = P_SET1(1.0), half = P_SET1(0.5);
    PV c0 = P_SET1(rc->c0), c1 = P_SET1(rc->c1);
    size_t k;
    for (k = 0; k + PW <= count; k += PW) {
        PV t = P_SUB(P_MUL(neg_sin, P_LOADU(cos_phi + k)), mu_prod);
        PV one_t = P_POSITIVE(P_ADD(one, t));
        PV cos_h = P_MUL(s, P_SQRT(P_BELOW(P_MUL(half, one_t), one)));
        PV value = P_MUL(P_MUL(scale, one_t), one_t);
        PV f = rc->conductor ? PFN(conductor_fresnel)(P_ABS(cos_h), c0, c1)
                             : PFN(dielectric_fresnel)(cos_h, c0, c1);
        P_STOREU(g + k, P_MUL(f, value));
        if (no_fresnel)
            P_STOREU(no_fresnel + k, value);
    }
    return k;
}

/* The samples of refract_profile with the Fresnel factor (eta_re != 1),
 * PW at a time: every sample computed, then those that do not see the
 * front of the facet from both sides set to 0. Returns the samples done. */
PATTR static size_t PFN(refract)(const pair_plan *p, double eta_re, double inv_eta_re,
                                 const double *cos_phi, size_t count, double *g,
                                 double *no_fresnel)
{
    PV neg_sin = P_SET1(-p->sin_prod), mu_prod = P_SET1(p->mu_prod);
    PV s = P_SET1(p->sign_h), scale = P_SET1(p->scale);
    PV eta = P_SET1(p->eta), one_eta2 = P_SET1(1.0 + p->eta * p->eta);
    PV two_eta = P_SET1(2.0 * p->eta), neg_mu_i = P_SET1(-p->mu_i);
    PV mu_o = P_SET1(p->mu_o), one = P_SET1(1.0), zero = P_ZERO();
    PV minus_one = P_SET1(-1.0), tiny = P_SET1(1e-300);
    PV e = P_SET1(eta_re), inv_e = P_SET1(inv_eta_re);
    size_t k;
    for (k = 0; k + PW <= count; k += PW) {
        PV t = P_SUB(P_MUL(neg_sin, P_LOADU(cos_phi + k)), mu_prod);
        PV wi_h = P_ADD(one, P_MUL(eta, t)), wo_h = P_ADD(t, eta);
        PV s_wi = P_MUL(s, wi_h);
        PV front =
            P_AND(P_GT(P_MUL(s_wi, neg_mu_i), zero), P_GT(P_MUL(P_MUL(s, wo_h), mu_o), zero));
        PV value = P_AND(front, P_MUL(scale, P_ABS(P_MUL(wi_h, wo_h))));
        PV len2 = P_ADD(one_eta2, P_MUL(two_eta, t));
        PV cos_h, x, f;
        len2 = P_SELECT(P_GT(len2, tiny), len2, tiny);
        x = P_BELOW(P_DIV(s_wi, P_SQRT(len2)), one);
        cos_h = P_SELECT(P_GT(x, minus_one), x, minus_one);
        f = PFN(dielectric_fresnel)(cos_h, e, inv_e);
        /* (masked again: a sample that is dropped gives 0, never 0 times a NaN) */
        P_STOREU(g + k, P_AND(front, P_MUL(P_SUB(one, f), value)));
        if (no_fresnel)
            P_STOREU(no_fresnel + k, value);
    }
    return k;
}

#undef P_POSITIVE
#undef P_SELECT
#undef P_BELOW
#undef P_ABS
#undef PV
#undef PW
#undef PFN
#undef PATTR
#undef P_SET1
#undef P_ZERO
#undef P_ADD
#undef P_SUB
#undef P_MUL
#undef P_DIV
#undef P_SQRT
#undef P_AND
#undef P_ANDNOT
#undef P_OR
#undef P_GT
#undef P_LT
#undef P_LE
#undef P_LOADU
#undef P_STOREU
