/* Links the whole library through find_package(layerlab): the header and
 * the library it loads agree on the version, and the installed spectra
 * are where the package says (layerlab_IOR_DIR). */
#include <layerlab.h>

#include <stdio.h>
#include <string.h>

int main(void)
{
    char path[4096];
    FILE *f;
    if (ll_version_number() != LL_VERSION_NUMBER ||
        strcmp(ll_version_string(), LL_VERSION_STRING) != 0) {
        fprintf(stderr, "uses_layerlab: header %s, library %s\n", LL_VERSION_STRING,
                ll_version_string());
        return 1;
    }
    snprintf(path, sizeof path, "%s/Au.eta.spd", LL_IOR_DIR);
    f = fopen(path, "r");
    if (!f) {
        fprintf(stderr, "uses_layerlab: %s is missing\n", path);
        return 1;
    }
    fclose(f);
    printf("uses_layerlab: layerlab %s, spectra in %s\n", ll_version_string(), LL_IOR_DIR);
    return 0;
}
