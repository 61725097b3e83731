/* fovea platform: gaze / head trace files (see tracefile.h). */
#include "tracefile.h"

#include <stdlib.h>
#include <string.h>

#include "output.h"

int fv_trace_load(fv_trace *tr, const char *path, char *err, size_t err_len)
{
    memset(tr, 0, sizeof *tr);
    size_t len;
    char *buf = fv_read_file_alloc(path, FV_TRACE_MAX_FILE_BYTES, &len, err, err_len);
    if (!buf)
        return -1;
    int rc = fv_trace_parse(tr, buf, len, path, err, err_len);
    free(buf);
    return rc;
}
