/*
 * llplot — OpenEXR output through the OpenEXR C API (OpenEXRCore, 3.1):
 * one scanline part, 32-bit float channels, ZIP compression.
 */
#include "llplot.h"

#include <stdio.h>
#include <string.h>

/* OpenEXR's C headers use anonymous unions, a C11 feature; the tool is
 * C99 with -pedantic -Werror, so silence that one diagnostic for them. */
#if defined(__GNUC__)
#  pragma GCC diagnostic push
#  pragma GCC diagnostic ignored "-Wpedantic"
#endif
#include <openexr.h>
#if defined(__GNUC__)
#  pragma GCC diagnostic pop
#endif

#define EXR_MESSAGE_SIZE 256

/* OpenEXR reports details through a callback on the failing thread; keep
 * the last one for our own message. */
static void remember_exr_error(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    void *user = NULL;
    (void)code;
    if (exr_get_user_data(ctxt, &user) == EXR_ERR_SUCCESS && user)
        snprintf(user, EXR_MESSAGE_SIZE, "%s", msg);
}

static int channel_index(const llplot_image *img, const char *name)
{
    size_t c;
    for (c = 0; c < img->channels; ++c)
        if (img->names[c] && strcmp(img->names[c], name) == 0)
            return (int)c;
    return -1;
}

/* Encode every chunk of scanlines. The library sorts channels by name in
 * the file, so the pipeline's channels are matched to ours by name. */
static exr_result_t write_scanlines(exr_context_t ctxt, int part, const llplot_image *img)
{
    exr_encode_pipeline_t enc;
    exr_result_t rv = EXR_ERR_SUCCESS;
    int32_t lines = 1;
    size_t y;
    int c, initialised = 0;
    memset(&enc, 0, sizeof enc);
    rv = exr_get_scanlines_per_chunk(ctxt, part, &lines);
    for (y = 0; rv == EXR_ERR_SUCCESS && y < img->height; y += (size_t)lines) {
        exr_chunk_info_t cinfo;
        rv = exr_write_scanline_chunk_info(ctxt, part, (int)y, &cinfo);
        if (rv != EXR_ERR_SUCCESS)
            break;
        rv = initialised ? exr_encoding_update(ctxt, part, &cinfo, &enc)
                         : exr_encoding_initialize(ctxt, part, &cinfo, &enc);
        if (rv != EXR_ERR_SUCCESS)
            break;
        for (c = 0; c < enc.channel_count; ++c) {
            exr_coding_channel_info_t *ch = &enc.channels[c];
            int index = channel_index(img, ch->channel_name);
            if (index < 0) {
                rv = EXR_ERR_INVALID_ARGUMENT;
                break;
            }
            ch->user_bytes_per_element = 4;
            ch->user_data_type = EXR_PIXEL_FLOAT;
            ch->user_pixel_stride = 4;
            ch->user_line_stride = (int32_t)(4 * img->width);
            ch->encode_from_ptr =
                (const uint8_t *)(const void *)llplot_pixel(img, (size_t)index, 0, y);
        }
        if (rv != EXR_ERR_SUCCESS)
            break;
        if (!initialised) {
            rv = exr_encoding_choose_default_routines(ctxt, part, &enc);
            initialised = 1;
            if (rv != EXR_ERR_SUCCESS)
                break;
        }
        rv = exr_encoding_run(ctxt, part, &enc);
    }
    if (initialised || enc.channels)
        exr_encoding_destroy(ctxt, &enc);
    return rv;
}

int llplot_write_exr(const char *path, const llplot_image *img, const char *comments)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    exr_context_t ctxt = NULL;
    exr_result_t rv;
    llplot_output out;
    char message[EXR_MESSAGE_SIZE] = "";
    int part = 0, code;
    size_t c;

    if (img->width > INT32_MAX || img->height > INT32_MAX)
        return llplot_fail(LLPLOT_EXIT_INPUT, "%s: %zu x %zu is too large for OpenEXR", path,
                           img->width, img->height);
    code = llplot_output_begin(path, &out);
    if (code != LLPLOT_EXIT_OK)
        return code;
    init.error_handler_fn = remember_exr_error;
    init.user_data = message;
    rv = exr_start_write(&ctxt, out.temp_path, EXR_WRITE_FILE_DIRECTLY, &init);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_add_part(ctxt, "llplot", EXR_STORAGE_SCANLINE, &part);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_initialize_required_attr_simple(ctxt, part, (int32_t)img->width,
                                                 (int32_t)img->height, EXR_COMPRESSION_ZIP);
    for (c = 0; rv == EXR_ERR_SUCCESS && c < img->channels; ++c)
        rv = exr_add_channel(ctxt, part, img->names[c], EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LINEAR,
                             1, 1);
    if (rv == EXR_ERR_SUCCESS && comments)
        rv = exr_attr_set_string(ctxt, part, "comments", comments);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_write_header(ctxt);
    if (rv == EXR_ERR_SUCCESS)
        rv = write_scanlines(ctxt, part, img);
    if (ctxt) {
        /* exr_finish flushes the chunk offset table: it can fail too. */
        exr_result_t fin = exr_finish(&ctxt);
        if (rv == EXR_ERR_SUCCESS)
            rv = fin;
    }
    if (rv != EXR_ERR_SUCCESS) {
        llplot_output_abort(&out);
        return llplot_fail(LLPLOT_EXIT_IO, "%s: cannot write the OpenEXR file: %s", path,
                           message[0] ? message : exr_get_default_error_message(rv));
    }
    return llplot_output_commit(&out);
}
