/*
 * Locale-independent strtod (parse_number.h).
 *
 * strtod reads the decimal separator of the current LC_NUMERIC. POSIX 2008
 * gives each thread its own current locale (uselocale), so the "C" locale
 * is installed for this thread around the call and the previous one put
 * back: no process-wide state is touched, other threads are not affected,
 * and the conversion is glibc's correctly rounded one. newlocale(LC_ALL_MASK,
 * "C") is cheap (glibc hands out its built-in C locale object).
 */
#include "support/parse_number.h"

#include <locale.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

double ll_parse_double(const char *text, char **end)
{
    locale_t c_locale = newlocale(LC_ALL_MASK, "C", (locale_t)0), previous;
    double value;
    if (c_locale == (locale_t)0) {
        /* Nothing parsed; strtod's interface hands back a non-const
         * pointer into the caller's text, which stays the caller's. */
        if (end)
            *end = (char *)(uintptr_t)text;
        return 0.0;
    }
    previous = uselocale(c_locale);
    value = strtod(text, end);
    uselocale(previous);
    freelocale(c_locale);
    return value;
}

int ll_vformat_c(char *buf, size_t size, const char *fmt, va_list ap)
{
    locale_t c_locale = newlocale(LC_ALL_MASK, "C", (locale_t)0), previous;
    int len;
    if (c_locale == (locale_t)0)
        return -1;
    previous = uselocale(c_locale);
    len = vsnprintf(buf, size, fmt, ap);
    uselocale(previous);
    freelocale(c_locale);
    return len;
}

int ll_format_c(char *buf, size_t size, const char *fmt, ...)
{
    va_list ap;
    int len;
    va_start(ap, fmt);
    len = ll_vformat_c(buf, size, fmt, ap);
    va_end(ap);
    return len;
}
