/*
 * A caller's monitor seen through one part of the table writer's work:
 * the part reports 0..1 for itself and the caller sees [lo, lo + width]
 * of the whole (a basis of a textured file, a grid of the search).
 */
#include "writer/bsdf_write_tables.h"

static int report_share(void *user, double fraction, const char *stage)
{
    const ll_tables_share *sh = user;
    return sh->whole.progress ? sh->whole.progress(sh->whole.user, sh->lo + fraction * sh->width,
                                                   stage)
                              : 0;
}

ll_monitor ll_tables_share_of(ll_tables_share *sh, double lo, double width)
{
    ll_monitor m = LL_MONITOR_INIT;
    sh->lo = lo;
    sh->width = width;
    m.progress = report_share;
    m.user = sh;
    return m;
}
