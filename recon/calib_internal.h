/* calib_internal.h — what calib_refine.c and calib_sweep.c share: moving
 * the views cleared of the gauge, and the grid of the lenslets' centres;
 * and calib_sweep_pattern.c's several objects swept together.
 * Not part of the public API (elfm_calib.h is). */
#ifndef ELFM_CALIB_INTERNAL_H
#define ELFM_CALIB_INTERNAL_H

#include "elfm_calib.h"

#include <stddef.h>
#include <stdint.h>

/* Views needed to set others on their grid (cx, cy affine in (i, j)) */
#define ELFM_CALIB_GRID_MIN_VIEWS 6

/* Move c's views with use[v] by (su[v], sw[v]) cleared of the two moves no
 * recording can see (elfm_calib_gauge_clear; su, sw are cleared in place);
 * the moves into shift_px (2 per view, may be NULL). */
void elfm_calib_move_gauge_free(elfm_calib *c, const int *use, double *su, double *sw, double *shift_px);

/* Set the views with to[v] where the grid of the views with from[v] puts
 * them (least squares), adding each move to shift_px (2 per view: the
 * moves so far, from the calibration before them), then clear those moves
 * of the gauge over all the views of from and to, together. 0, and nothing
 * moved, when those views do not span the grid. */
int elfm_calib_place_on_grid(elfm_calib *c, const int *from, const int *to, double *shift_px);

/* The 3 x 3 system m[.][0..2] x = m[.][3], solved in place (Gauss-Jordan
 * with partial pivoting): 0 when it is singular (calib_refine.c) */
int elfm_calib_solve3(double m[3][4], double x[3]);

/* The median of a[0 .. n) (n > 0), reordering a (calib_sweep.c) */
double elfm_calib_median(double *a, size_t n);

/* The largest distance, px, of a view with use[v] from the lenslets' grid
 * (cx, cy affine in (i, j)) fitted to those views, and that view into
 * *worst; -1 when they do not span the grid. */
double elfm_calib_off_grid(const elfm_calib *c, const int *use, int *worst);

/* Several objects swept through z together (calib_sweep_pattern.c): each
 * view's spots in each frame (n_spots [nf][nv], spots [nf][nv][MAX][2],
 * the brightest's strength [nf][nv]) matched to one pattern of objects,
 * its first object's place into pu, pw ([nf][nv], NaN where not placed).
 * Returns the pattern's objects (0: no pattern of two or more, pu and pw
 * all NaN); in *share the median over the views with tells[v] of the
 * share of their frames with two spots or more that were placed (0 for a
 * view with none), and in *depth_um how far apart in depth its objects
 * lie (the deepest's depth less the shallowest's; NaN with no pattern). */
int elfm_calib_sweep_pattern(const elfm_calib *c, size_t nf, const int *tells, const uint8_t *n_spots,
                             const float *strength, const float *spots, float *pu, float *pw, double *share,
                             double *depth_um);

/* The translation of spots S[0 .. ns) onto objects P[0 .. np) (at most
 * ELFM_CALIB_SWEEP_MAX_SPOTS each) that elfm_calib_sweep_pattern takes for
 * a view's frame, into t: the objects that agree on it, 0 for none (fewer
 * than 2, or than half of the spots or objects, or two translations as
 * good). with_votes 0: without the differences' votes that spare it most
 * of the pairs (the same result, slower). For tests. */
int elfm_calib_pattern_translate(const float (*S)[2], int ns, const double (*P)[2], int np, int with_votes,
                                 double t[2]);

#endif
