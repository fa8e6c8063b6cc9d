/*
 * Writing a file atomically, as a little-endian byte stream: the bytes go
 * to a hidden temporary file (".NAME.XXXXXX.tmp") created in the target's
 * directory (or, for a symbolic link, in the directory of the file it leads
 * to), which is flushed, fsync'ed and renamed over the target only when
 * everything has been written; the file keeps the mode of the target it
 * replaces, or gets 0666 minus the umask. Stale temporaries of the same
 * target are removed (bsdf_file_out.c says when one is stale). On any failure the temporary file is removed and the target
 * is untouched. Write errors are sticky: the put calls never fail, commit
 * reports the first error.
 */
#ifndef LL_BSDF_FILE_OUT_H
#define LL_BSDF_FILE_OUT_H

#include "support/support.h"

typedef struct ll_bsdf_out ll_bsdf_out;

/* Create the temporary file for path; fn names the calling function in
 * messages. LL_ERROR_IO if it cannot be created. */
LL_INTERNAL ll_status ll_bsdf_out_begin(const char *path, const char *fn, ll_bsdf_out **out);

LL_INTERNAL void ll_bsdf_out_u32(ll_bsdf_out *o, uint32_t v);
LL_INTERNAL void ll_bsdf_out_f32(ll_bsdf_out *o, float v);
LL_INTERNAL void ll_bsdf_out_bytes(ll_bsdf_out *o, const void *data, size_t size);

/* Flush, fsync, close and rename over the target; frees o. On failure the
 * temporary file is removed (LL_ERROR_IO naming the path and the system
 * error). */
LL_INTERNAL ll_status ll_bsdf_out_commit(ll_bsdf_out *o);

/* Give up: close and remove the temporary file; frees o. NULL is fine. */
LL_INTERNAL void ll_bsdf_out_abort(ll_bsdf_out *o);

#endif /* LL_BSDF_FILE_OUT_H */
