/* fovea: circle-of-confusion (CoC) models as pure functions (issue 4, formulas only; no
 * filtering yet). Distances in the scene are view depths in metres; lengths inside the eye are
 * in millimetres. Every model returns a SIGNED value: negative for points nearer than the
 * focus (near field), positive for farther ones (far field), 0 in focus; its magnitude is the
 * paper's formula. Derivations, units and the presets are in docs/dof.md. */
#ifndef FOVEA_DOF_COC_H
#define FOVEA_DOF_COC_H

/* Depths below this are clamped: every lens formula needs the object outside the focal length
 * (about 22 mm), and nothing nearer than 5 cm is seen sharply or rendered meaningfully. */
#define FV_COC_MIN_DEPTH_M 0.05f

/* Eye optics defaults (DESIGN.md): image distance d_i 22.4 mm (Weier), focal length 22.3 mm and
 * pupil 4.49 mm (Liu), tracking depth tolerance t 0.2 m (Weier). */
#define FV_EYE_IMAGE_DIST_MM 22.4f
#define FV_EYE_FOCAL_MM 22.3f
#define FV_EYE_PUPIL_MM 4.49f
#define FV_EYE_DEPTH_TOL_M 0.2f

/* E: pixels of the eye image per millimetre on the retina. A retinal length x mm subtends
 * x / d_i radians at the lens; the pinhole eye image has focal_px pixels per unit tan, i.e. per
 * radian at the optical axis (focal_px = pixels per degree * 180 / pi). So E = focal_px / d_i.
 * With the planar focus plane of core/reference.c the conversion is exact at every pixel. */
static inline float fv_retina_px_per_mm(float focal_px, float image_dist_mm) { return focal_px / image_dist_mm; }

/* Weier et al. 2018 eq. (3): the tracking-aware thin lens. The retina sits at d_i; the eye is
 * assumed focused anywhere in [d_n, d_f] = [d_o - t, d_o + t], so points in that range get 0 and
 * others are blurred relative to the nearer bound: focal lengths 1/f = 1/d + 1/d_i for d_n and
 * d_f, image distances V_d(F, g) = F g / (g - F), V_f(F, d) = F d / (d - F) (= d_i), and the
 * blur diameter on the retina by similar triangles k |V_d - V_f| / V_d (mm), times E. */
typedef struct fv_coc_weier {
    float image_dist_mm;    /* d_i */
    float pupil_mm;         /* k */
    float tolerance_m;      /* t */
    float retina_px_per_mm; /* E (fv_retina_px_per_mm); scaled by the presets */
} fv_coc_weier;
/* d_i 22.4 mm, k 4.49 mm, t 0.2 m, E = focal_px / d_i. */
void fv_coc_weier_default(fv_coc_weier *p, float focal_px);
/* Signed CoC diameter on the retina in mm (no E); exactly 0 for d_o - t <= depth <= d_o + t. */
float fv_coc_weier_mm(const fv_coc_weier *p, float focus_m, float depth_m);
/* The same in pixels of the eye image: fv_coc_weier_mm * E. */
float fv_coc_weier_px(const fv_coc_weier *p, float focus_m, float depth_m);

/* Intensity presets (--dof none|weak|medium|strong). Weier et al. give no numbers, only that
 * k and E control the effect: the pupil is Liu's 4.49 mm throughout and E is scaled. weak is
 * the physiological blur (scale 1), medium and strong double it each step (blur is judged on a
 * roughly logarithmic scale), none switches the blur off. */
typedef enum { FV_DOF_NONE, FV_DOF_WEAK, FV_DOF_MEDIUM, FV_DOF_STRONG, FV_DOF_PRESET_COUNT } fv_dof_preset;
typedef struct fv_dof_preset_desc {
    const char *name;
    float pupil_mm; /* k */
    float e_scale;  /* multiplies E */
} fv_dof_preset_desc;
extern const fv_dof_preset_desc fv_dof_presets[FV_DOF_PRESET_COUNT];
/* 0 and *out set for "none", "weak", "medium", "strong"; -1 otherwise. */
int fv_dof_preset_parse(const char *name, fv_dof_preset *out);
/* Sets p's pupil and scales its E (call on a default-initialised p). */
void fv_coc_weier_apply_preset(fv_coc_weier *p, fv_dof_preset preset);

/* Liu et al. eq. (12): C_e = |v - f_e| * tau_e / v with v = f_e F D / (F D + f_e D - f_e F), the
 * image distance of a point at D when the eye (retina at f_e) is focused at F. Result in mm on
 * the retina. It is eq. (3) with t = 0 and d_i = f_e. */
typedef struct fv_coc_liu {
    float focal_mm; /* f_e, 22.3 */
    float pupil_mm; /* tau_e, 4.49 */
} fv_coc_liu;
void fv_coc_liu_default(fv_coc_liu *p);
float fv_coc_liu_mm(const fv_coc_liu *p, float focus_m, float depth_m);

/* Mantiuk et al. 2011 eq. (1), a camera's thin lens (fixed focal length, moving sensor):
 * CoC = a |f / (d0 - f)| |1 - d0 / dp|. The result has the unit of the aperture a. */
typedef struct fv_coc_mantiuk {
    float aperture;  /* a: 4.49 (mm, the pupil) by default; Mantiuk's study used 2, 7, 19 */
    float focal_mm;  /* f: 22.3 */
} fv_coc_mantiuk;
void fv_coc_mantiuk_default(fv_coc_mantiuk *p);
float fv_coc_mantiuk_size(const fv_coc_mantiuk *p, float focus_m, float depth_m);

/* Hussain et al.: Gaussian sigma = K |1/d0 - 1/d1| (pixels), K in pixels x metres folding the
 * aperture, the posterior nodal distance and the CoC-to-sigma constant. */
typedef struct fv_coc_hussain {
    float k_px_m; /* K */
} fv_coc_hussain;
/* K matching the thin lens: a disc of diameter c = pupil_m |dD| focal_px has a per-axis
 * standard deviation of c / 4, so K = pupil_m * focal_px / 4. */
void fv_coc_hussain_default(fv_coc_hussain *p, float pupil_mm, float focal_px);
float fv_coc_hussain_sigma_px(const fv_coc_hussain *p, float focus_m, float depth_m);

#endif
