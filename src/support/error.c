/*
 * Status codes, versions and the error message of the calling thread.
 *
 * The library's mutable state is per thread -- the last error message
 * (here) and the worker-thread count requested by the calling thread
 * (threads.c) -- but for the process-wide allocator that the caller sets
 * before anything is allocated (alloc.c).
 */
#include "support/support.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

static __thread char tls_message[LL_MESSAGE_CAPACITY];

int ll_version_number(void) { return LL_VERSION_NUMBER; }

const char *ll_version_string(void) { return LL_VERSION_STRING; }

const char *ll_status_string(ll_status status)
{
    switch (status) {
    case LL_OK: return "success";
    case LL_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case LL_ERROR_OUT_OF_MEMORY: return "out of memory";
    case LL_ERROR_IO: return "input/output error";
    case LL_ERROR_FORMAT: return "malformed file";
    case LL_ERROR_NUMERICAL: return "numerical failure";
    case LL_ERROR_UNSUPPORTED: return "unsupported";
    case LL_ERROR_PARSE: return "parse error";
    case LL_ERROR_CANCELLED: return "cancelled";
    default: return "unknown status";
    }
}

const char *ll_last_error_message(void) { return tls_message; }

ll_status ll_fail(ll_status status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(tls_message, sizeof tls_message, fmt, ap);
    va_end(ap);
    return status;
}

void ll_message_copy(char *dst, size_t capacity)
{
    if (capacity == 0)
        return;
    strncpy(dst, tls_message, capacity - 1);
    dst[capacity - 1] = '\0';
}

int ll_is_finite(double x) { return isfinite(x) != 0; }

