/* fovea HIL: the KMS display as the KMS check drives it (tests/hil/hil_display.c). */
#ifndef FOVEA_HIL_DISPLAY_H
#define FOVEA_HIL_DISPLAY_H

#include <stddef.h>
#include <stdint.h>

typedef struct fv_hil_display fv_hil_display;

/* First connected connector, its preferred mode, two XRGB8888 buffers. NULL with err. */
fv_hil_display *fv_hil_display_open(const char *card, char *err, size_t err_len);
int fv_hil_display_width(const fv_hil_display *d);
int fv_hil_display_height(const fv_hil_display *d);
/* The buffer to draw the next frame into (0x00RRGGBB, pitch in bytes). 0, or -1 with err. */
int fv_hil_display_back(fv_hil_display *d, uint32_t **px, size_t *pitch, char *err, size_t err_len);
/* Shows the back buffer: the first call sets the mode, later ones page-flip and wait for the
 * flip's event. 0, or -1 with err. */
int fv_hil_display_present(fv_hil_display *d, char *err, size_t err_len);
void fv_hil_display_close(fv_hil_display *d);

#endif
