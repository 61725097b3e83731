/* fovea platform: HMD lens profile files (see lensfile.h). */
#include "lensfile.h"

#include "output.h"

int fv_lens_load(fv_lens *l, const char *path, float r_max, char *err, size_t err_len)
{
    char buf[16384];
    const long n = fv_read_text_file(path, buf, sizeof buf, "a lens profile", err, err_len);
    if (n < 0)
        return -1;
    return fv_lens_parse(l, buf, (size_t)n, path, r_max, err, err_len);
}
