/*
 * Decimal numbers in files (material files, spectra) are written with a
 * '.' whatever the reader's locale: a host program that called
 * setlocale(LC_ALL, "de_DE.UTF-8") must not turn "0.5" into "not a number".
 */
#ifndef LL_PARSE_NUMBER_H
#define LL_PARSE_NUMBER_H

#include "support/support.h"

#include <stdarg.h>

/* strtod in the "C" locale, whatever locale the calling thread or the
 * process has set: the same syntax (decimal or hexadecimal, optional
 * exponent, inf/nan), the same correctly rounded result and the same *end
 * (set to text when nothing was parsed). *end may be NULL. If the "C" locale
 * object cannot be made (out of memory), nothing is parsed: 0 is returned
 * and *end = text. */
LL_INTERNAL double ll_parse_double(const char *text, char **end);

/* vsnprintf / snprintf in the "C" locale, so that numbers written into
 * files (JSON metadata) use '.' whatever the host's locale. Returns what
 * vsnprintf returns (-1 if the "C" locale cannot be made). */
LL_INTERNAL int ll_vformat_c(char *buf, size_t size, const char *fmt, va_list ap)
    LL_PRINTF(3, 0);
LL_INTERNAL int ll_format_c(char *buf, size_t size, const char *fmt, ...) LL_PRINTF(3, 4);

#endif /* LL_PARSE_NUMBER_H */
