/* fovea eye tracker: accuracy against labelled images (fovea-track --images with labels): per
 * group (all images, and one group per MRL sensor) the count, the share within 1, 2, 3 and 5 px
 * of the label and the median error. A pupil not found counts as an infinite error (a miss). */
#ifndef FOVEA_EYETRACK_LABELSTATS_H
#define FOVEA_EYETRACK_LABELSTATS_H

#define FV_EYE_LABEL_RADII 4
#define FV_EYE_LABEL_GROUPS 8
extern const double fv_eye_label_radii_px[FV_EYE_LABEL_RADII]; /* 1, 2, 3, 5 */

typedef struct fv_eye_label_group {
    char name[16];                      /* "all" or "sensor NAME" */
    long n;                             /* labelled images */
    long within[FV_EYE_LABEL_RADII];    /* errors <= fv_eye_label_radii_px[k] */
    double *err_px;                     /* the n errors (sorted by fv_eye_label_median) */
} fv_eye_label_group;

typedef struct fv_eye_label_stats {
    fv_eye_label_group g[FV_EYE_LABEL_GROUPS]; /* g[0] is "all" */
    int n;                                     /* groups in use */
    long cap;                                  /* images each group can hold */
} fv_eye_label_stats;

/* cap: the most images that will be added. 0, or -1 when out of memory. */
int fv_eye_label_stats_init(fv_eye_label_stats *s, long cap);
void fv_eye_label_stats_free(fv_eye_label_stats *s);
/* One labelled image: its path (an MRL file name also counts towards its sensor's group, up to
 * FV_EYE_LABEL_GROUPS groups in all) and its error in pixels (INFINITY: not found). 0, or -1
 * when out of memory or past cap. */
int fv_eye_label_stats_add(fv_eye_label_stats *s, const char *path, double err_px);
/* The median error of a group (sorts its errors); NAN for an empty group; INFINITY when most
 * were not found. */
double fv_eye_label_median(fv_eye_label_group *g);
/* The sensor field of an MRL file name (subject_image_gender_glasses_eye_refl_light_SENSOR.png,
 * any folder): 1 with it in out, else 0. */
int fv_eye_mrl_sensor(const char *path, char out[16]);

#endif
