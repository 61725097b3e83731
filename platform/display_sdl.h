/* fovea platform: the SDL2 window back end of platform/display.h (-lSDL2). */
#ifndef FOVEA_DISPLAY_SDL_H
#define FOVEA_DISPLAY_SDL_H

#include <stddef.h>
#include <stdint.h>

typedef struct fv_window fv_window;
int fv_window_open(fv_window **v, int w, int h, char *err, size_t err_len);
int fv_window_present(fv_window *v, const uint8_t *rgb, int w, int h, ptrdiff_t stride, char *err, size_t err_len);
int fv_window_mouse_gaze(fv_window *v, float *gx, float *gy);
int fv_window_quit_requested(fv_window *v);
void fv_window_close(fv_window *v);

#endif
