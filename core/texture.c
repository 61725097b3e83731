/* fovea: scene textures: sRGB (or linear data) 8-bit RGBA stored as linear float RGBA with a box-filtered mip
 * chain, sampled trilinearly with REPEAT, CLAMP or MIRROR addressing (glTF samplers). */
#include "scene_impl.h"
#include "texture_tap.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define FV_TEX_MAX_TEXELS ((size_t)1 << 26) /* 8192^2: about 1.4 GB as float RGBA with mips */

/* 2x2 box filter; an odd source side folds its last texel into the last output texel
 * (3 taps), so every source texel contributes and 1-texel sides pass through. */
static void downsample(const float *src, int sw, int sh, float *dst, int dw, int dh)
{
    for (int y = 0; y < dh; y++) {
        int ty[3], nty = 0;
        ty[nty++] = 2 * y;
        if (2 * y + 1 < sh) ty[nty++] = 2 * y + 1;
        if ((sh & 1) && sh > 1 && y == dh - 1) ty[nty++] = 2 * y + 2;
        for (int x = 0; x < dw; x++) {
            int tx[3], ntx = 0;
            tx[ntx++] = 2 * x;
            if (2 * x + 1 < sw) tx[ntx++] = 2 * x + 1;
            if ((sw & 1) && sw > 1 && x == dw - 1) tx[ntx++] = 2 * x + 2;
            float acc[4] = {0, 0, 0, 0};
            for (int j = 0; j < nty; j++)
                for (int i = 0; i < ntx; i++) {
                    const float *p = src + ((size_t)ty[j] * (size_t)sw + (size_t)tx[i]) * 4;
                    for (int c = 0; c < 4; c++) acc[c] += p[c];
                }
            const float inv = 1.0f / (float)(nty * ntx);
            float *d = dst + ((size_t)y * (size_t)dw + (size_t)x) * 4;
            for (int c = 0; c < 4; c++) d[c] = acc[c] * inv;
        }
    }
}

static int add_texture(fv_scene *s, const uint8_t *rgba8, int w, int h, int srgb)
{
    if (!s || !rgba8 || w < 1 || h < 1 || w > FV_TEX_MAX_SIDE || h > FV_TEX_MAX_SIDE ||
        (size_t)w * (size_t)h > FV_TEX_MAX_TEXELS)
        return -1;
    size_t cap = (size_t)s->texture_cap;
    if (fv_scene_grow((void **)&s->textures, &cap, (size_t)s->texture_count + 1, sizeof *s->textures)) return -1;
    s->texture_cap = (int)cap;

    fv_texture t;
    memset(&t, 0, sizeof t);
    size_t total = 0, offs[FV_TEX_MAX_LEVELS];
    for (int lw = w, lh = h;; lw = lw > 1 ? lw / 2 : 1, lh = lh > 1 ? lh / 2 : 1) {
        t.w[t.levels] = lw, t.h[t.levels] = lh;
        offs[t.levels++] = total;
        total += (size_t)lw * (size_t)lh * 4;
        if (lw == 1 && lh == 1) break;
    }
    t.data = malloc(total * sizeof(float));
    if (!t.data) return -1;

    float lut[256]; /* sRGB -> linear */
    for (int i = 0; i < 256; i++) {
        float c = (float)i / 255.0f;
        lut[i] = !srgb ? c : c <= 0.04045f ? c / 12.92f : powf((c + 0.055f) / 1.055f, 2.4f);
    }
    const size_t n = (size_t)w * (size_t)h;
    for (size_t i = 0; i < n; i++) {
        for (int c = 0; c < 3; c++) t.data[i * 4 + (size_t)c] = lut[rgba8[i * 4 + (size_t)c]];
        t.data[i * 4 + 3] = (float)rgba8[i * 4 + 3] / 255.0f;
    }
    for (int l = 0; l < t.levels; l++) t.level[l] = t.data + offs[l];
    for (int l = 1; l < t.levels; l++)
        downsample(t.data + offs[l - 1], t.w[l - 1], t.h[l - 1], t.data + offs[l], t.w[l], t.h[l]);
    s->textures[s->texture_count] = t;
    return s->texture_count++;
}

int fv_scene_add_texture(fv_scene *s, const uint8_t *rgba8, int w, int h) { return add_texture(s, rgba8, w, h, 1); }
int fv_scene_add_texture_linear(fv_scene *s, const uint8_t *rgba8, int w, int h)
{
    return add_texture(s, rgba8, w, h, 0);
}

int fv_scene_set_texture_wrap(fv_scene *s, int tex, fv_wrap wrap_s, fv_wrap wrap_t)
{
    if (!s || tex < 0 || tex >= s->texture_count) return -1;
    s->textures[tex].wrap_s = wrap_s, s->textures[tex].wrap_t = wrap_t;
    return 0;
}

int fv_scene_set_texture_filter(fv_scene *s, int tex, int mag_nearest, int min_nearest, fv_mip mip)
{
    if (!s || tex < 0 || tex >= s->texture_count || mip < FV_MIP_LINEAR || mip > FV_MIP_NONE) return -1;
    fv_texture *t = &s->textures[tex];
    t->mag_nearest = mag_nearest != 0, t->min_nearest = min_nearest != 0, t->mip = (unsigned char)mip;
    return 0;
}

void fv_texture_taps(const fv_texture *t, float u, float v, float lod, fv_tex_taps *tp) { fv_tex_taps_at(t, u, v, lod, tp); }
void fv_texture_taps_prefetch(const fv_tex_taps *tp) { fv_tex_taps_prefetch(tp); }
void fv_texture_blend(const fv_tex_taps *tp, float out[4]) { fv_tex_blend(tp, out); }

/* Trilinear between the two mip levels around lod (lod 0 = full resolution). */
void fv_texture_sample(const fv_texture *t, float u, float v, float lod, float out[4])
{
    fv_tex_taps tp;
    fv_tex_taps_at(t, u, v, lod, &tp);
    fv_tex_blend(&tp, out);
}
