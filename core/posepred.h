/* fovea: head pose prediction to the photon time. Pose samples (a trace read as a 1 kHz pose
 * source, or any later tracker) go into a small ring; the prediction extrapolates the newest
 * sample with the linear and angular velocity measured between it and the newest sample at
 * least vel_span_ns older (constant velocity, the rotation about a fixed world axis), up to
 * max_horizon_ns ahead. OS-free, not thread safe (the caller locks). */
#ifndef FOVEA_POSEPRED_H
#define FOVEA_POSEPRED_H

#include <stdint.h>

#include "camera.h"

#define FV_POSEPRED_RING 64
typedef struct fv_posepred {
    int64_t t_ns[FV_POSEPRED_RING];
    fv_pose pose[FV_POSEPRED_RING];
    long n;                 /* samples pushed */
    int64_t vel_span_ns;    /* 8 ms: long enough to average a tracker's noise, short for the lag */
    int64_t max_horizon_ns; /* 50 ms: never extrapolate further */
} fv_posepred;

void fv_posepred_init(fv_posepred *p, int64_t vel_span_ns, int64_t max_horizon_ns);
/* Samples in time order (an older or equal time than the newest is ignored). */
void fv_posepred_push(fv_posepred *p, int64_t t_ns, const fv_pose *pose);
/* The pose predicted for t_ns into *out: 1, or 0 with no sample yet. *sample_t_ns (may be NULL)
 * gets the newest sample's time (the start of motion-to-photon). */
int fv_posepred_predict(const fv_posepred *p, int64_t t_ns, fv_pose *out, int64_t *sample_t_ns);

/* The angle between two orientations in degrees (0..180) and the distance between positions in
 * metres: the prediction's error against a true pose. */
double fv_pose_angle_deg(const fv_pose *a, const fv_pose *b);
double fv_pose_dist_m(const fv_pose *a, const fv_pose *b);

#endif
