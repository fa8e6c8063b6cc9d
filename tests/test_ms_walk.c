/*
 * The random walk on the Smith microsurface (tests/reference/ms_walk.c),
 * the reference of the energy compensation: its own invariants (F = 1 and
 * a dielectric keep every path; the next-event estimate integrates to the
 * albedo; the first bounce is the height-correlated single-scattering
 * BSDF, its albedo and its value; reciprocity of the multiple part), and
 * a few of its stored results (tests/data/ms_walk.txt, written by
 * `ms_walk table`) computed again with other random numbers, within noise.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#define MS_WALK_NO_MAIN
#include "reference/ms_walk.c"

static void invariants_hold(void **state)
{
    (void)state;
    assert_int_equal(msw_check(), 0);
}

static void stored_results_come_out_again(void **state)
{
    (void)state;
    assert_int_equal(msw_rerun(LL_SOURCE_DIR "/tests/data/ms_walk.txt"), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(invariants_hold),
        cmocka_unit_test(stored_results_come_out_again),
    };
    return cmocka_run_group_tests_name("ms_walk", tests, NULL, NULL);
}
