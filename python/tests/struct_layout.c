/*
 * The layout of every public size-tagged struct as the C compiler sees it,
 * for test_struct_layout.py to compare with the ctypes Structures of
 * layerlab/_native.py. Prints, per struct:
 *     struct NAME SIZEOF INIT_BYTES_IN_HEX
 *     field NAME FIELD OFFSET SIZE
 */
#include <stddef.h>
#include <stdio.h>

#define LL_EXPERIMENTAL /* the experimental structs too */
#include <layerlab.h>

static void print_struct(const char *name, size_t size, const void *init)
{
    const unsigned char *bytes = init;
    size_t i;
    printf("struct %s %zu ", name, size);
    for (i = 0; i < size; ++i)
        printf("%02x", bytes[i]);
    printf("\n");
}

#define STRUCT(type, init)                          \
    do {                                            \
        static const type value = init;             \
        print_struct(#type, sizeof(type), &value);  \
    } while (0)
#define FIELD(type, field)                                                        \
    printf("field %s %s %zu %zu\n", #type, #field, offsetof(type, field),        \
           sizeof(((type *)0)->field))

int main(void)
{
    STRUCT(ll_bsdf_write_options, LL_BSDF_WRITE_OPTIONS_INIT);
    FIELD(ll_bsdf_write_options, struct_size);
    FIELD(ll_bsdf_write_options, eta);
    FIELD(ll_bsdf_write_options, alpha);
    FIELD(ll_bsdf_write_options, metadata);
    FIELD(ll_bsdf_write_options, error_goal);

    STRUCT(ll_bsdf_info, LL_BSDF_INFO_INIT);
    FIELD(ll_bsdf_info, struct_size);
    FIELD(ll_bsdf_info, n_nodes);
    FIELD(ll_bsdf_info, max_order);
    FIELD(ll_bsdf_info, n_channels);
    FIELD(ll_bsdf_info, n_bases);
    FIELD(ll_bsdf_info, n_parameters);
    FIELD(ll_bsdf_info, n_coeffs);
    FIELD(ll_bsdf_info, eta);
    FIELD(ll_bsdf_info, alpha);
    FIELD(ll_bsdf_info, metadata);
    FIELD(ll_bsdf_info, metadata_size);
    FIELD(ll_bsdf_info, file_size);
    FIELD(ll_bsdf_info, flags);
    FIELD(ll_bsdf_info, format);
    FIELD(ll_bsdf_info, n_wavelengths);

    STRUCT(ll_bsdf_tables, LL_BSDF_TABLES_INIT);
    FIELD(ll_bsdf_tables, struct_size);
    FIELD(ll_bsdf_tables, n_nodes);
    FIELD(ll_bsdf_tables, n_channels);
    FIELD(ll_bsdf_tables, n_bases);
    FIELD(ll_bsdf_tables, max_order);
    FIELD(ll_bsdf_tables, n_coeffs);
    FIELD(ll_bsdf_tables, n_parameters);
    FIELD(ll_bsdf_tables, n_parameter_values);
    FIELD(ll_bsdf_tables, eta);
    FIELD(ll_bsdf_tables, nodes);
    FIELD(ll_bsdf_tables, pairs);
    FIELD(ll_bsdf_tables, coeffs);
    FIELD(ll_bsdf_tables, cdf);
    FIELD(ll_bsdf_tables, a0);
    FIELD(ll_bsdf_tables, parameter_counts);
    FIELD(ll_bsdf_tables, parameter_positions);

    STRUCT(ll_tables_options, LL_TABLES_OPTIONS_INIT);
    FIELD(ll_tables_options, struct_size);
    FIELD(ll_tables_options, n_theta_i);
    FIELD(ll_tables_options, vndf_size);
    FIELD(ll_tables_options, sample_size);
    FIELD(ll_tables_options, format);
    FIELD(ll_tables_options, description);
    FIELD(ll_tables_options, wavelengths);
    FIELD(ll_tables_options, n_wavelengths);
    FIELD(ll_tables_options, spectrum);
    FIELD(ll_tables_options, spectrum_user);
    FIELD(ll_tables_options, tolerance);

    STRUCT(ll_build_options, LL_BUILD_OPTIONS_INIT);
    FIELD(ll_build_options, struct_size);
    FIELD(ll_build_options, n_nodes);
    FIELD(ll_build_options, n_orders);
    FIELD(ll_build_options, n_channels);
    FIELD(ll_build_options, threads);
    FIELD(ll_build_options, tolerance);
    FIELD(ll_build_options, mu_min);
    FIELD(ll_build_options, error_goal);
    FIELD(ll_build_options, max_memory_bytes);
    FIELD(ll_build_options, channel_done);
    FIELD(ll_build_options, channel_done_user);
    FIELD(ll_build_options, cache_dir);

    STRUCT(ll_build_estimate, LL_BUILD_ESTIMATE_INIT);
    FIELD(ll_build_estimate, struct_size);
    FIELD(ll_build_estimate, n_nodes);
    FIELD(ll_build_estimate, n_orders);
    FIELD(ll_build_estimate, n_channels);
    FIELD(ll_build_estimate, n_bases);
    FIELD(ll_build_estimate, threads);
    FIELD(ll_build_estimate, resolution_error);
    FIELD(ll_build_estimate, peak_bytes);
    FIELD(ll_build_estimate, file_bytes);
    FIELD(ll_build_estimate, max_memory_bytes);
    FIELD(ll_build_estimate, over_budget);
    FIELD(ll_build_estimate, layers_built);
    FIELD(ll_build_estimate, additions);
    FIELD(ll_build_estimate, doublings);
    FIELD(ll_build_estimate, dielectric_pairs);
    FIELD(ll_build_estimate, conductor_pairs);
    FIELD(ll_build_estimate, pair_orders);
    FIELD(ll_build_estimate, measured_lookups);
    FIELD(ll_build_estimate, measured_files);
    FIELD(ll_build_estimate, phase_entries);
    FIELD(ll_build_estimate, diffuse_entries);
    FIELD(ll_build_estimate, add_entries);
    FIELD(ll_build_estimate, add_empty_entries);
    FIELD(ll_build_estimate, stored_values);

    STRUCT(ll_microfacet, LL_MICROFACET_INIT);
    FIELD(ll_microfacet, struct_size);
    FIELD(ll_microfacet, eta_re);
    FIELD(ll_microfacet, eta_im);
    FIELD(ll_microfacet, alpha);
    FIELD(ll_microfacet, distribution);
    FIELD(ll_microfacet, compensate);
    FIELD(ll_microfacet, n_orders_internal);

    STRUCT(ll_monitor, LL_MONITOR_INIT);
    FIELD(ll_monitor, struct_size);
    FIELD(ll_monitor, progress);
    FIELD(ll_monitor, user);
    return 0;
}
