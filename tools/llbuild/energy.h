/*
 * llbuild's check of the file it wrote: a material reflects and transmits
 * at most the light it receives, and a .bsdf that does more says that its
 * resolution does not resolve the material (a lobe narrower than the given
 * nodes can hold: the spline over mu overshoots its peak), so llbuild
 * warns, naming the worst angle and basis.
 */
#ifndef LLBUILD_ENERGY_H
#define LLBUILD_ENERGY_H

#include <stdio.h>

/* R + T of the .bsdf at path, per channel, at incident elevations 0, 30,
 * 60 and 80 degrees from above (and from below where it transmits), for
 * each basis of a textured file. Where the largest exceeds 1 by more than
 * the file's quadrature can (LLBUILD_ENERGY_SLACK), one warning to out;
 * a file that cannot be read back is left to the summary's own message.
 * resolution_given: the nodes and orders were given, not chosen by the
 * tolerance (the warning says which way to more nodes).
 * Returns 1 if it warned, else 0. */
int llbuild_warn_energy(FILE *out, const char *path, int resolution_given);

/* How far above 1 R + T may come by the file's quadrature and rounding
 * alone (a lossless interface with its energy compensation has R + T = 1
 * up to them; tests/llbuild.sh builds one and sees no warning). */
#define LLBUILD_ENERGY_SLACK 0.01

#endif
