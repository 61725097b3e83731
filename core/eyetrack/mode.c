/* The tracker's modes: what each does (the settings), the AUTO size rule, names. */
#include <string.h>

#include "base/util.h"
#include "eyetrack/eyetrack.h"

const fv_eye_mode_settings fv_eye_headset_settings = {
    .mode = FV_EYE_MODE_HEADSET,
    .search_sides = 1,
    .sides_frac = 0.5f,
    .sides_min_grey = 10.0f,
    .lost_contrast = 3.0f,
    .refine_on_search_image = 0,
    .refine_max_side = 320, /* the edge points keep sub-pixel precision, noise halves, work quarters */
    .window_side_div = 4,   /* the search box can be only the darkest part of a big pupil */
    .reflect_grow_px = 3,
    .centroid_iters = 6,
    .box_grow_max = 4,
    .smooth_rays = 1,
    .edge_search_px = 3.0f,
    .beyond_frac = 0.35f,
    .lid_line = 1,
    .ransac_iters = 64,
    .ransac_grad_mincos = 0.85, /* 32 deg */
    .min_aspect = 0.6,          /* gaze up to ~50 deg off the camera axis; flatter is lid consensus */
    .report_box_centre = 0,
};

/* Tuned on the MRL infrared crops (docs/eyetrack.md; the weights on the even-numbered images):
 * with ~10 px pupils inside an often equally dark iris, the search box's centre beat every
 * refinement tried, which here only gives the levels, size, fit quality and glints. */
const fv_eye_mode_settings fv_eye_crop_settings = {
    .mode = FV_EYE_MODE_CROP,
    /* spectacles (docs/eyetrack.md, "Spectacles"): the brow above a frame's bright rim is a
     * dark box with a bright ring; clipped, the rim counts no more than skin, and the sides
     * test with a lower bar (a tinted lens leaves 6-15 grey levels of contrast, and the lid or
     * rim often takes one side) refuses the brow, a band as dark as the box along itself */
    .search_sides = 1,
    .sides_frac = 0.3f,
    .sides_min_grey = 3.0f,
    .search_clip_grey = 20,
    /* a corneal reflection beside a box nearly as good as the best marks the eye: the best can
     * be the iris's shadowed side or a dark patch of a tinted lens (docs/eyetrack.md) */
    .spot_margin_grey = 5.0f,
    .lost_contrast = 2.0f, /* 3 behind a lens passing ~70 % */
    .refine_on_search_image = 1,
    .centroid_iters = 2,
    .min_aspect = 0.3,
    .report_box_centre = 1,
    .centre_weight = 0.05f,
    .glint_weight = 0.3f,
    .spot_min_grey = 20,
};

fv_eye_mode fv_eye_resolve_mode(fv_eye_mode mode, int w, int h)
{
    if (mode == FV_EYE_MODE_HEADSET || mode == FV_EYE_MODE_CROP)
        return mode;
    /* frames the search does not halve: crops around an eye, in practice */
    return fv_mini(w, h) <= FV_EYE_AUTO_CROP_MAX_SIDE ? FV_EYE_MODE_CROP : FV_EYE_MODE_HEADSET;
}

const fv_eye_mode_settings *fv_eye_mode_get_settings(fv_eye_mode mode)
{
    return mode == FV_EYE_MODE_HEADSET ? &fv_eye_headset_settings
           : mode == FV_EYE_MODE_CROP  ? &fv_eye_crop_settings
                                       : NULL;
}

static const char *const names[] = { [FV_EYE_MODE_AUTO] = "auto", [FV_EYE_MODE_HEADSET] = "headset",
                                     [FV_EYE_MODE_CROP] = "crop" };

const char *fv_eye_mode_name(fv_eye_mode mode)
{
    return (unsigned)mode < sizeof names / sizeof names[0] ? names[mode] : NULL;
}

int fv_eye_mode_parse(const char *name, fv_eye_mode *mode)
{
    for (unsigned i = 0; name && i < sizeof names / sizeof names[0]; i++)
        if (!strcmp(name, names[i])) {
            *mode = (fv_eye_mode)i;
            return 0;
        }
    return -1;
}
