/* llbuild's time model (see time_model.h). */
#include "time_model.h"

#include <math.h>

/* A rough interface: the node pairs (mu_o, mu_i) dominate (the Chebyshev
 * samples, Filon's rule where a kink is), a dielectric's growing with its
 * roughness (the estimate weights its pairs by alpha / 0.1) and, measured
 * at n = 40 to 300, like n^(1/3); plus a little per order and pair (less
 * per pair at more nodes: 1.5e-9 (200 / n) s). About half of the time does
 * not gain from more threads (coated-gold, mostly interfaces: 0.66 s on
 * one thread, 0.50 s on two). */
#define COST_PAIR_DIELECTRIC 2.9e-6 /* s per pair at alpha = 0.1, n = 200 */
#define COST_PAIR_CONDUCTOR 9e-7
#define COST_PAIR_ORDER 1.5e-9
/* A measured table: DCT multiply-adds (the orders of each lookup) and the
 * lookups themselves, in parallel; reading and converting a file. */
#define RATE_MERL 7e8
#define COST_MERL_SAMPLE 1.8e-7
#define COST_MERL_LOAD 0.04
/* Phase matrices, per entry of an order that holds one (in parallel over
 * the orders); a diffuse word, per entry (serial). */
#define COST_PHASE 7e-9
#define COST_DIFFUSE 1e-8
/* Adding and doubling steps, per n x n entry of an order holding values in
 * both operands, or empty in one (in parallel over the orders). */
#define COST_ADD_ORDER 4.5e-9
#define COST_ADD_EMPTY 3e-10
/* Writing: per stored value (spline fits, float conversion). */
#define COST_WRITE 3e-8
/* The rates above were measured stage by stage on one 2-core x86-64 VM;
 * the machine the project's figures are taken on (docs/benchmarks.md,
 * "Choosing the resolution: cold, remembered and dry runs") builds the
 * examples in about half the CPU time, so the model's work is scaled to
 * it. Rates belong to a machine: on another the estimate is off by that
 * machine's speed against this one. */
#define MACHINE_SCALE 0.5
/* A process: start, parse, the OpenBLAS set-up (CPU seconds; the wall
 * time adds loading and thread start-up). */
#define PROCESS_SECONDS 0.01
#define PROCESS_WALL_SECONDS 0.03

void llbuild_time(const ll_build_estimate *e, double *wall, double *cpu)
{
    double n = e->n_nodes > 0 ? (double)e->n_nodes : 1.0, m = (double)e->n_orders;
    double t = e->threads > 0 ? (double)e->threads : 1.0;
    double interface = e->dielectric_pairs * COST_PAIR_DIELECTRIC * pow(n / 200.0, 0.33) +
                       e->conductor_pairs * COST_PAIR_CONDUCTOR +
                       e->pair_orders * COST_PAIR_ORDER * (200.0 / n);
    double parallel = e->measured_lookups * (m / RATE_MERL + COST_MERL_SAMPLE) +
                      e->phase_entries * COST_PHASE + e->add_entries * COST_ADD_ORDER +
                      e->add_empty_entries * COST_ADD_EMPTY;
    double serial = e->measured_files * COST_MERL_LOAD + e->diffuse_entries * COST_DIFFUSE +
                    e->stored_values * COST_WRITE;
    *cpu = MACHINE_SCALE * (2.0 * interface + parallel + serial) + PROCESS_SECONDS;
    *wall = MACHINE_SCALE * (interface / t + interface + parallel / t + serial) +
            PROCESS_WALL_SECONDS;
}
