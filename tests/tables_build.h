/*
 * A material built to a .bsdf file and its tables written from it, both
 * in the test program's scratch directory (ll_test_dir) and both opened:
 * what every test that measures a table against its source starts with.
 * Header-only (static inline).
 */
#ifndef LL_TEST_TABLES_BUILD_H
#define LL_TEST_TABLES_BUILD_H

#include "test_util.h"

/* Size of the path buffers ll_test_build_tables fills. */
#define LL_TEST_PATH_SIZE 600

/* Build text (a .layers file named name) to NAME.bsdf, write its tables
 * to NAME.tab with options o (NULL: every size chosen by the default
 * tolerance) and open both into *src and *tab. The two paths go to
 * bsdf_path and tab_path (LL_TEST_PATH_SIZE bytes each). */
static inline void ll_test_build_tables(const char *text, const char *name,
                                        const ll_tables_options *o, char *bsdf_path,
                                        char *tab_path, ll_bsdf **src, ll_bsdf **tab)
{
    ll_material *m = NULL;
    snprintf(bsdf_path, LL_TEST_PATH_SIZE, "%s/%s.bsdf", ll_test_dir(), name);
    snprintf(tab_path, LL_TEST_PATH_SIZE, "%s/%s.tab", ll_test_dir(), name);
    assert_int_equal(ll_material_parse(text, name, &m), LL_OK);
    assert_int_equal(ll_material_build(m, NULL, NULL, bsdf_path), LL_OK);
    ll_material_destroy(m);
    assert_int_equal(ll_bsdf_open(bsdf_path, NULL, src), LL_OK);
    assert_int_equal(ll_tables_write_from_bsdf(*src, tab_path, o, NULL), LL_OK);
    assert_int_equal(ll_bsdf_open(tab_path, NULL, tab), LL_OK);
}

#endif /* LL_TEST_TABLES_BUILD_H */
