/*
 * Size-tagged public structs (ll_bsdf_write_options, ll_bsdf_info,
 * ll_build_options, ll_build_estimate, and any later one) are read and
 * written here and nowhere else. Each begins with `size_t struct_size`, set
 * by the caller to the sizeof of the struct in the headers it was built
 * with; fields are only ever appended. So a caller's struct is a prefix of
 * the library's: the library reads and writes exactly the bytes that
 * struct_size covers, and nothing beyond (the caller's memory may end
 * there). A program built against newer headers (struct_size larger than
 * the library knows) gets the fields this library knows; the rest keep
 * what the caller put there.
 *
 * The smallest accepted struct_size is the struct_size field itself: such
 * a struct reads as all defaults and receives nothing. One rule for every
 * struct, so that none of them can ever be too new for a library.
 *
 * A later field must not be appended into the tail padding of the current
 * struct (e.g. a uint32_t after ll_bsdf_info.flags): an older caller's
 * sizeof covers that padding, so the field would be read from it.
 */
#include "support/support.h"

#include <ctype.h>
#include <string.h>

static ll_status caller_size(const void *caller, const char *fn, const char *type, size_t *size)
{
    char init[64];
    size_t k;
    if (!caller)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: the %s pointer is NULL", fn, type);
    memcpy(size, caller, sizeof *size);
    if (*size >= sizeof(size_t))
        return LL_OK;
    /* Every public struct ll_x has its initialiser LL_X_INIT: name it, as
     * that is what the caller forgot. */
    for (k = 0; type[k] && k + 6 < sizeof init; ++k)
        init[k] = (char)toupper((unsigned char)type[k]);
    memcpy(init + k, "_INIT", 6);
    return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                   "%s: %s.struct_size = %zu is smaller than the struct_size field itself "
                   "(%zu); set it to sizeof(%s) (initialise the struct with %s)",
                   fn, type, *size, sizeof(size_t), type, init);
}

ll_status ll_struct_read(void *dst, size_t dst_size, const void *src, const char *fn,
                         const char *type)
{
    size_t size = 0;
    ll_status s = caller_size(src, fn, type, &size);
    if (s != LL_OK)
        return s;
    memcpy(dst, src, size < dst_size ? size : dst_size);
    memcpy(dst, &dst_size, sizeof dst_size);
    return LL_OK;
}

ll_status ll_struct_write(void *dst, const void *src, size_t src_size, const char *fn,
                          const char *type)
{
    size_t size = 0;
    ll_status s = caller_size(dst, fn, type, &size);
    if (s != LL_OK)
        return s;
    if (size > src_size)
        size = src_size;
    /* The caller's struct_size stays as the caller set it. */
    memcpy((char *)dst + sizeof(size_t), (const char *)src + sizeof(size_t),
           size - sizeof(size_t));
    return LL_OK;
}

ll_status ll_struct_check(const void *caller, const char *fn, const char *type)
{
    size_t size = 0;
    return caller_size(caller, fn, type, &size);
}
