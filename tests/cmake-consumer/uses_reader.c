/* Links the reader alone through find_package(layerlab): a program that
 * includes only <layerlab/ll_bsdf.h>, as a renderer's loader does. */
#include <layerlab/ll_bsdf.h>

#include <stdio.h>
#include <string.h>

int main(void)
{
    if (ll_version_number() != LL_VERSION_NUMBER ||
        strcmp(ll_version_string(), LL_VERSION_STRING) != 0) {
        fprintf(stderr, "uses_reader: header %s, library %s\n", LL_VERSION_STRING,
                ll_version_string());
        return 1;
    }
    printf("uses_reader: layerlab reader %s\n", ll_version_string());
    return 0;
}
