/*
 * The binary16 conversions of the tensor container (reader/tensor_half.c),
 * which a textured table file's grids are stored in: every one of the
 * 65536 codes against a decoding of its own (sign, exponent, mantissa by
 * the standard's formula), every code back to itself, and rounding to
 * nearest with ties to even at the midpoint between every two neighbours
 * (and just beside it), the range's end and the subnormals included.
 * And the tensor writer's float16 fields: read back as written (rounded),
 * a value beyond the range refused naming the field, the file untouched.
 */
#include "test_util.h"
#include "reader/tensor.h"
#include "writer/bsdf_write_tensor.h"

/* IEEE 754 binary16 by its definition. */
static double decode(unsigned h)
{
    unsigned e = (h >> 10) & 0x1fu, m = h & 0x3ffu;
    double v = e == 0 ? ldexp((double)m, -24) : ldexp(1.0 + (double)m / 1024.0, (int)e - 15);
    if (e == 31)
        v = m ? NAN : INFINITY;
    return (h & 0x8000u) ? -v : v;
}

static void test_every_code(void **state)
{
    unsigned h;
    (void)state;
    for (h = 0; h < 0x10000u; ++h) {
        double want = decode(h);
        float got = ll_half_to_float((uint16_t)h);
        if (isnan(want)) {
            assert_true(isnan(got));
            assert_true((ll_half_from_float(got) & 0x7c00u) == 0x7c00u &&
                        (ll_half_from_float(got) & 0x3ffu) != 0);
            continue;
        }
        assert_true((double)got == want);
        assert_true(!signbit(got) == !signbit(want));
        assert_int_equal(ll_half_from_float(got), h);
        assert_true(ll_half_round(got) == got);
    }
}

static void test_ties_to_even(void **state)
{
    unsigned h, sign;
    (void)state;
    for (sign = 0; sign <= 0x8000u; sign += 0x8000u)
        for (h = 0; h < 0x7bffu; ++h) {
            /* Two neighbours need 11 significant bits, their midpoint 12:
             * exact in a float. */
            float a = ll_half_to_float((uint16_t)(sign | h)),
                  b = ll_half_to_float((uint16_t)(sign | (h + 1)));
            float mid = (float)(0.5 * ((double)a + (double)b));
            unsigned even = (h & 1u) ? h + 1 : h;
            assert_true((double)mid == 0.5 * ((double)a + (double)b));
            assert_int_equal(ll_half_from_float(mid), sign | even);
            assert_int_equal(ll_half_from_float(nextafterf(mid, 0.0f)), sign | h);
            assert_int_equal(ll_half_from_float(nextafterf(mid, sign ? -INFINITY : INFINITY)),
                             sign | (h + 1));
        }
}

static void test_range(void **state)
{
    (void)state;
    assert_true(ll_half_to_float(0x7bffu) == LL_HALF_MAX);
    assert_int_equal(ll_half_from_float(65504.0f), 0x7bffu);
    assert_int_equal(ll_half_from_float(nextafterf(65520.0f, 0.0f)), 0x7bffu);
    /* 65520 is the midpoint to the next step, 65536: to even, infinity. */
    assert_int_equal(ll_half_from_float(65520.0f), 0x7c00u);
    assert_int_equal(ll_half_from_float(-65520.0f), 0xfc00u);
    assert_int_equal(ll_half_from_float(1e30f), 0x7c00u);
    assert_int_equal(ll_half_from_float(INFINITY), 0x7c00u);
    assert_int_equal(ll_half_from_float(-INFINITY), 0xfc00u);
    /* Half the smallest subnormal rounds to 0, anything above to it. */
    assert_int_equal(ll_half_from_float(0x1p-25f), 0x0000u);
    assert_int_equal(ll_half_from_float(nextafterf(0x1p-25f, 1.0f)), 0x0001u);
    assert_int_equal(ll_half_from_float(-0x1p-26f), 0x8000u);
    assert_int_equal(ll_half_from_float(1e-30f), 0x0000u);
    assert_int_equal(ll_half_from_float(1.0f), 0x3c00u);
    /* The relative rounding error of a normal value: at most 2^-11. */
    assert_true(fabs((double)ll_half_round(0.1f) / 0.1f - 1.0) <= 0x1p-11);
}

static void test_written_fields(void **state)
{
    float v[2][3] = { { 0.1f, 1.0f, 65504.0f }, { 0.0f, 3.0f, 0x1p-24f } };
    ll_tensor_out_field f = { "basis0.vndf", LL_TENSOR_F16, 2, { 2, 3 }, v, NULL, NULL };
    char path[600];
    unsigned char *bytes;
    size_t size = 0, i;
    ll_tensor_file tf;
    (void)state;
    snprintf(path, sizeof path, "%s/half.tab", ll_test_dir());
    assert_int_equal(ll_tensor_write(path, "test", &f, 1), LL_OK);
    bytes = ll_test_read_file(path, &size);
    assert_non_null(bytes);
    assert_int_equal(ll_tensor_parse(bytes, size, path, &tf), LL_OK);
    assert_int_equal(tf.fields[0].dtype, LL_TENSOR_F16);
    assert_int_equal(tf.fields[0].bytes, 12);
    for (i = 0; i < 6; ++i)
        assert_true(ll_tensor_value(&tf.fields[0], i) == ll_half_round(v[i / 3][i % 3]));
    ll_tensor_file_free(&tf);
    free(bytes);
    /* 65520 rounds to infinity; a NaN: refused, naming field and element. */
    v[1][1] = 65520.0f;
    assert_int_equal(ll_tensor_write(path, "test", &f, 1), LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "\"basis0.vndf\": element 4 = 65520"));
    v[1][1] = NAN;
    assert_int_equal(ll_tensor_write(path, "test", &f, 1), LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "\"basis0.vndf\": element 4"));
    /* The file as the first write left it. */
    bytes = ll_test_read_file(path, &size);
    assert_non_null(bytes);
    assert_int_equal(ll_tensor_parse(bytes, size, path, &tf), LL_OK);
    assert_true(ll_tensor_value(&tf.fields[0], 4) == 3.0f);
    ll_tensor_file_free(&tf);
    free(bytes);
    unlink(path);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_code),
        cmocka_unit_test(test_ties_to_even),
        cmocka_unit_test(test_range),
        cmocka_unit_test(test_written_fields),
    };
    return cmocka_run_group_tests(tests, ll_test_dir_setup, ll_test_dir_teardown);
}
