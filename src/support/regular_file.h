/*
 * Opening an input file that must be a regular file (.bsdf, MERL, material,
 * spectrum) without ever blocking: open(2) of a FIFO with no writer, or of
 * some devices, waits forever, so the file is opened with O_NONBLOCK, its
 * type checked with fstat, and O_NONBLOCK cleared only for a regular file.
 */
#ifndef LL_REGULAR_FILE_H
#define LL_REGULAR_FILE_H

#include "support/support.h"

#include <stdio.h>
#include <sys/stat.h>

/* Open path for reading. On success *fd is a blocking descriptor of a
 * regular file and *st its fstat. Otherwise LL_ERROR_IO with the message
 * "<what> \"<path>\": cannot open: <strerror>" or "<what> \"<path>\" is a
 * FIFO (named pipe) | directory | character device | block device | socket,
 * not a regular file", and *fd = -1. */
LL_INTERNAL ll_status ll_open_regular(const char *path, const char *what, int *fd,
                                      struct stat *st);

/* The same as a stdio stream ("rb"); NULL with the message set (status
 * LL_ERROR_IO, or LL_ERROR_OUT_OF_MEMORY when fdopen fails for want of
 * memory) on failure. */
LL_INTERNAL FILE *ll_fopen_regular(const char *path, const char *what);

/* The kind of a file mode, for messages ("FIFO (named pipe)", ...). */
LL_INTERNAL const char *ll_file_kind(mode_t mode);

#endif /* LL_REGULAR_FILE_H */
