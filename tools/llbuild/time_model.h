/*
 * llbuild's time model: the seconds a build takes, from the counts of work
 * that ll_material_estimate reports, at rates measured stage by stage on
 * one machine (x86-64, 2 cores, OpenBLAS) and scaled to the machine of
 * docs/benchmarks.md (time_model.c; docs/material-language.md,
 * "Estimates (`--dry-run`)", says how; docs/benchmarks.md, "Choosing the
 * resolution: cold, remembered and dry runs", has the model's error on
 * the examples). The library reports counts only: rates belong to a
 * machine.
 */
#ifndef LLBUILD_TIME_MODEL_H
#define LLBUILD_TIME_MODEL_H

#ifndef LL_EXPERIMENTAL
#define LL_EXPERIMENTAL /* ll_build_estimate */
#endif
#include <layerlab.h>

/* Wall seconds on e->threads threads and CPU seconds summed over them. */
void llbuild_time(const ll_build_estimate *e, double *wall, double *cpu);

#endif
