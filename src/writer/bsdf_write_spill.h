/*
 * A spill file for the writer (bsdf_writer.c), which sees a file's parts
 * out of the order the file stores them (layer after layer, where the file
 * interleaves them pair by pair): a file beside the output (same file system), created
 * with mkstemp (O_EXCL, mode 0600) and unlinked at once, so no path names it
 * while the writer works and its space returns however the process ends.
 * Writes are buffered; reads are positioned (pread) and may come in any
 * order once the bytes are flushed. A spill in memory (the small writes
 * that are handed every layer at once) keeps the bytes in its growing
 * buffer instead and creates no file.
 */
#ifndef LL_STORAGE_BSDF_WRITE_SPILL_H
#define LL_STORAGE_BSDF_WRITE_SPILL_H

#include "support/support.h"

typedef struct ll_spill {
    const char *path;           /* the output the spill sits beside      */
    int fd;                     /* -1 before open and after close        */
    unsigned long long flushed; /* bytes written to the file             */
    unsigned char *buffer;      /* LL_SPILL_BUFFER bytes, or all of them */
    size_t buffered;
    size_t capacity;            /* in memory: the buffer's size, else 0  */
} ll_spill;

/* A closed spill (fd -1, nothing allocated): ll_spill_close is safe on it. */
void ll_spill_init(ll_spill *sp);
/* Creates the file beside path (which must outlive the spill) and its
 * buffer; fn names the caller in messages. */
ll_status ll_spill_open(ll_spill *sp, const char *path, const char *fn);
/* A spill in memory: no file; path names the output in messages. */
void ll_spill_open_memory(ll_spill *sp, const char *path);
/* The offset the next ll_spill_put's first byte will have. */
unsigned long long ll_spill_tell(const ll_spill *sp);
ll_status ll_spill_put(ll_spill *sp, const void *data, size_t size, const char *fn);
/* Writes out what is buffered: call before reading it back. */
ll_status ll_spill_flush(ll_spill *sp, const char *fn);
ll_status ll_spill_read(const ll_spill *sp, unsigned long long at, void *data, size_t size,
                        const char *fn);
void ll_spill_close(ll_spill *sp);

#endif
