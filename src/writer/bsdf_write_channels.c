/*
 * The channel-by-channel writer (bsdf_write_channels.h): the writer of
 * bsdf_writer.c with one basis, its spill a file beside the output, fed
 * each channel as the material builder finishes it, under the build's
 * names and monitor.
 */
#include "writer/bsdf_write_channels.h"
#include "writer/bsdf_write_job.h"
#include "layer/layer.h"

static const char *const fn_names[3] = { "ll_material_build (opening the file)",
                                         "ll_material_build (a finished channel)",
                                         "ll_material_build (writing)" };

ll_status ll_channel_writer_open(const char *path, size_t n_channels,
                                 const ll_bsdf_write_options *opts, ll_channel_writer **out)
{
    return ll_writer_open_as(fn_names, path, n_channels, 0, NULL, NULL, opts, 0, out);
}

ll_status ll_channel_writer_add(ll_channel_writer *w, size_t channel, const ll_layer *layer,
                                const ll_monitor *monitor)
{
    ll_watch watch;
    ll_status s = ll_watch_begin(&watch, monitor, fn_names[1]);
    if (s != LL_OK) {
        ll_writer_fail(w);
        return s;
    }
    /* A unit of the stage is an order of the layer's series lengths. */
    ll_watch_stage(&watch, "writing", 0.0, 1.0, layer ? layer->m : 0);
    return ll_writer_add_unit(w, 0, channel, layer, &watch);
}

ll_status ll_channel_writer_commit(ll_channel_writer *w, const ll_monitor *monitor)
{
    return ll_bsdf_writer_commit(w, monitor);
}

void ll_channel_writer_abort(ll_channel_writer *w)
{
    ll_bsdf_writer_abort(w);
}
