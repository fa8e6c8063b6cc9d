/*
 * llbuild-mpi's textured builds (tools/llbuild-mpi/textured.c): the bases
 * of a swept material across the ranks.
 */
#ifndef LLBUILD_MPI_TEXTURED_H
#define LLBUILD_MPI_TEXTURED_H

#define LL_EXPERIMENTAL /* ll_material_builder_*, ll_layer_pack */
#include <layerlab.h>
#include <signal.h>

#include "mpi_hook.h"

/* Build every basis of m (swept) and, on rank 0, write out_path through
 * the streaming writer, byte for byte the file ll_material_build writes.
 * shown (rank 0, nullable) is told the fraction of bases written (its
 * return value is not read); cancel is polled on every rank. Returns the
 * agreed outcome (every rank the same); on rank 0 message receives the
 * failure's text. */
ll_status textured_build(mpi_job *job, const ll_material *m, const ll_build_options *o,
                         const char *out_path, const volatile sig_atomic_t *cancel,
                         const ll_monitor *shown, char *message, size_t size);

#endif
