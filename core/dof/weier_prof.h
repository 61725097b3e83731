/* TEMPORARY per-pass CPU-time profile (not committed) */
#ifndef FVW_PROF_H
#define FVW_PROF_H
#ifdef FVW_PROF
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
enum { P_COC, P_HPASS, P_LV, P_HBLUR, P_VGAUSS, P_PERI, P_BLURP, P_NEARF, P_LUP, P_COMB, P_OUT, P_N };
__attribute__((unused)) static const char *fvw_pn[P_N] = {"coc", "hpass", "lvpass", "hblur", "vgauss", "peri_row", "blur_periph", "near_full", "near_up", "combine", "output"};
extern double fvw_prof[16][P_N];
extern long fvw_prof_calls;
static inline double fvw_cpu(void) { struct timespec ts; clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts); return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6; }
#define PROF_T(v) const double v = fvw_cpu()
#define PROF_ADD(tid, k, a, b) (fvw_prof[(tid)][(k)] += (b) - (a))
#else
#define PROF_T(v) (void)0
#define PROF_ADD(tid, k, a, b) (void)0
#endif
#endif
