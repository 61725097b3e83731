/* SDL2 window display (a PC stand-in for the headset's panel). */
#include "display_sdl.h"

#include <stdlib.h>
#include <string.h>

#include "base/err.h"

#ifdef FV_HAVE_SDL2
#include <SDL.h>

struct fv_window {
    SDL_Window *win;
    SDL_Renderer *ren;
    SDL_Texture *tex;
    int w, h;
    int quit;
};

static int env_set(const char *name)
{
    const char *v = getenv(name);
    return v && *v;
}

int fv_window_open(fv_window **out, int w, int h, char *err, size_t err_len)
{
    *out = NULL;
    /* Without a display SDL falls back to its invisible offscreen driver (and probing Wayland
     * prints to stderr): no window is an error, unless SDL_VIDEODRIVER picks a driver on purpose. */
    const int chosen = env_set("SDL_VIDEODRIVER");
    if (!chosen && !env_set("DISPLAY") && !env_set("WAYLAND_DISPLAY"))
        return fv_err(err, err_len, "window: no display (neither DISPLAY nor WAYLAND_DISPLAY is set)");
    if (!chosen) /* only the drivers of the display named: nothing else probed when it fails */
        SDL_SetHint("SDL_VIDEODRIVER", env_set("WAYLAND_DISPLAY") ? "wayland,x11" : "x11");
    if (SDL_InitSubSystem(SDL_INIT_VIDEO)) {
        if (!chosen)
            return fv_err(err, err_len, "window: no display (SDL: %s; DISPLAY=%s, WAYLAND_DISPLAY=%s)",
                          SDL_GetError(), env_set("DISPLAY") ? getenv("DISPLAY") : "",
                          env_set("WAYLAND_DISPLAY") ? getenv("WAYLAND_DISPLAY") : "");
        return fv_err(err, err_len, "SDL_InitSubSystem(video): %s", SDL_GetError());
    }
    const char *drv = SDL_GetCurrentVideoDriver();
    if (!chosen && drv && (!strcmp(drv, "offscreen") || !strcmp(drv, "dummy"))) {
        SDL_QuitSubSystem(SDL_INIT_VIDEO);
        return fv_err(err, err_len, "window: no display (SDL found only its %s video driver)", drv);
    }
    fv_window *v = calloc(1, sizeof *v);
    if (!v) {
        SDL_QuitSubSystem(SDL_INIT_VIDEO);
        return fv_err(err, err_len, "window: out of memory");
    }
    v->w = w;
    v->h = h;
    /* a stereo pair is wide: show it at half size when it would not fit most screens */
    int ww = w, wh = h;
    while (ww > 1920 || wh > 1080) {
        ww /= 2;
        wh /= 2;
    }
    v->win = SDL_CreateWindow("fovea-headset", SDL_WINDOWPOS_UNDEFINED, SDL_WINDOWPOS_UNDEFINED, ww, wh, 0);
    if (!v->win) {
        fv_err(err, err_len, "SDL_CreateWindow: %s", SDL_GetError());
        goto bad;
    }
    v->ren = SDL_CreateRenderer(v->win, -1, 0); /* no renderer vsync: the frame loop paces itself */
    if (!v->ren) {
        fv_err(err, err_len, "SDL_CreateRenderer: %s", SDL_GetError());
        goto bad;
    }
    v->tex = SDL_CreateTexture(v->ren, SDL_PIXELFORMAT_RGB24, SDL_TEXTUREACCESS_STREAMING, w, h);
    if (!v->tex) {
        fv_err(err, err_len, "SDL_CreateTexture %dx%d: %s", w, h, SDL_GetError());
        goto bad;
    }
    *out = v;
    return 0;
bad:
    fv_window_close(v);
    return -1;
}

static void pump(fv_window *v)
{
    SDL_Event e;
    while (SDL_PollEvent(&e))
        if (e.type == SDL_QUIT || (e.type == SDL_KEYDOWN && e.key.keysym.sym == SDLK_ESCAPE))
            v->quit = 1;
}

int fv_window_present(fv_window *v, const uint8_t *rgb, int w, int h, ptrdiff_t stride, char *err, size_t err_len)
{
    pump(v);
    if (w != v->w || h != v->h)
        return fv_err(err, err_len, "window: image %dx%d, window made for %dx%d", w, h, v->w, v->h);
    if (SDL_UpdateTexture(v->tex, NULL, rgb, (int)stride))
        return fv_err(err, err_len, "SDL_UpdateTexture: %s", SDL_GetError());
    if (SDL_RenderCopy(v->ren, v->tex, NULL, NULL))
        return fv_err(err, err_len, "SDL_RenderCopy: %s", SDL_GetError());
    SDL_RenderPresent(v->ren);
    return 0;
}

int fv_window_mouse_gaze(fv_window *v, float *gx, float *gy)
{
    pump(v);
    if (SDL_GetMouseFocus() != v->win)
        return 0;
    int mx, my, ww, wh;
    SDL_GetMouseState(&mx, &my);
    SDL_GetWindowSize(v->win, &ww, &wh);
    if (ww < 2 || wh < 1)
        return 0;
    /* side by side: the same point in either eye's half */
    const float half = (float)ww / 2.0f;
    float x = (float)mx >= half ? (float)mx - half : (float)mx;
    *gx = x / half;
    *gy = (float)my / (float)wh;
    return 1;
}

int fv_window_quit_requested(fv_window *v)
{
    pump(v);
    return v->quit;
}

void fv_window_close(fv_window *v)
{
    if (!v)
        return;
    if (v->tex)
        SDL_DestroyTexture(v->tex);
    if (v->ren)
        SDL_DestroyRenderer(v->ren);
    if (v->win)
        SDL_DestroyWindow(v->win);
    SDL_QuitSubSystem(SDL_INIT_VIDEO);
    free(v);
}

#else

struct fv_window {
    int unused;
};
int fv_window_open(fv_window **out, int w, int h, char *err, size_t err_len)
{
    (void)w, (void)h;
    *out = NULL;
    return fv_err(err, err_len, "window: fovea was built without SDL2");
}
int fv_window_present(fv_window *v, const uint8_t *rgb, int w, int h, ptrdiff_t stride, char *err, size_t err_len)
{
    (void)v, (void)rgb, (void)w, (void)h, (void)stride;
    return fv_err(err, err_len, "window: fovea was built without SDL2");
}
int fv_window_mouse_gaze(fv_window *v, float *gx, float *gy)
{
    (void)v, (void)gx, (void)gy;
    return 0;
}
int fv_window_quit_requested(fv_window *v)
{
    (void)v;
    return 0;
}
void fv_window_close(fv_window *v) { (void)v; }
#endif
