/*
 * Writing one untextured .bsdf file channel by channel (internal; the
 * material builder's streaming write): each channel's finished
 * layer is handed over as soon as it is complete and may be freed at once,
 * so a build never holds every channel's stack and the writer's staging at
 * the same time. The file is byte for byte what ll_bsdf_write writes for
 * the same layers, and as atomic (bsdf_writer.c says how).
 */
#ifndef LL_STORAGE_BSDF_WRITE_CHANNELS_H
#define LL_STORAGE_BSDF_WRITE_CHANNELS_H

#include "layerlab/ll_bsdf_write.h"
#include "support/support.h"

/* (The writer of ll_bsdf_write.h, opened for one basis.) */
typedef struct ll_bsdf_writer ll_channel_writer;

/* A writer of path with n_channels (1, or 3: R, G, B) channels; opts
 * (nullable) read now, as ll_bsdf_write reads them (its metadata copied).
 * Creates the spill file beside path (LL_ERROR_IO if it cannot). */
LL_INTERNAL ll_status ll_channel_writer_open(const char *path, size_t n_channels,
                                             const ll_bsdf_write_options *opts,
                                             ll_channel_writer **out);

/* Channel `channel` (0 = R or mono, 1 = G, 2 = B), each exactly once, in
 * any order; the writer keeps nothing of the layer after it returns.
 * monitor (nullable) is polled per order and column (LL_ERROR_CANCELLED).
 * After any failure only ll_channel_writer_abort is left. */
LL_INTERNAL ll_status ll_channel_writer_add(ll_channel_writer *w, size_t channel,
                                            const ll_layer *layer, const ll_monitor *monitor);

/* Write the file (every channel added) and free the writer, whatever the
 * outcome; monitor as for ll_bsdf_write (stage "writing"; a cancel,
 * also at the last report, leaves no file). */
LL_INTERNAL ll_status ll_channel_writer_commit(ll_channel_writer *w, const ll_monitor *monitor);

/* Give up: no file is left, nor the spill; frees w (NULL is fine). */
LL_INTERNAL void ll_channel_writer_abort(ll_channel_writer *w);

#endif /* LL_STORAGE_BSDF_WRITE_CHANNELS_H */
