/* peaks.c — 3D local maxima, threshold, separation, sub-voxel refinement
 * (see elfm_peaks.h). */
#include "elfm_peaks.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The MAD of n samples of Gaussian noise has a relative standard error of
 * ~1.17 / sqrt(n) (asymptotic variance of the sample median of |x|): 0.9 %
 * at 16,384, 0.5 % at 65,536, i.e. a 6-sigma threshold moves by < 1 % either
 * way. 16,384 costs a quarter of the two selections (65,536 took ~0.3 ms of
 * the detector's 2.1 ms per flow volume in bench_peaks); on the simulated
 * time surfaces the absolute rule sets the threshold anyway. */
#define PEAKS_NOISE_SAMPLES 16384

typedef struct peak_cand {
  float value;
  int32_t x, y, z;
  int32_t weak;   /* above the low (hysteresis) threshold only */
  int32_t deep;   /* above the depth-scaled threshold only (elfm_detection.deep_only) */
} peak_cand;

struct elfm_peaks {
  elfm_peaks_options opt;
  int w, h, nz;
  size_t cand_cap;
  peak_cand *cand;   /* candidates of the current volume */
  float *sample;     /* noise sample */
  uint32_t *keys;    /* its selection's scratch (select_kth) */
  double *thr_plane; /* threshold per z plane of the current volume */
  double *thr_low;   /* hysteresis (low) threshold per plane; = thr_plane when off */
  uint8_t *views;    /* views sampling each voxel (NULL: rule off) */
  int n_views;
  double view_scale[256]; /* threshold factor (N / n)^exponent by view count n */
  int32_t *row_max;  /* per (y, z) row: its maximum voxel's bits as int32 (float order for >= 0) */
  uint8_t *above;    /* one row's voxels above the threshold (mark_above), w rounded up to 8 */
  double last_threshold;
};

void elfm_peaks_options_default(elfm_peaks_options *o)
{
  memset(o, 0, sizeof *o);
  o->absolute = 0.0;
  o->relative = 0.0;
  o->k_sigma = 6.0;        /* 6 sigma: ~1e-9 false-positive rate per voxel for Gaussian noise */
  o->radius_xy_um = 3.0;
  o->radius_z_um = 15.0;
  o->min_separation_um = 4.0;
  o->kz = 4.0;
  o->refine = ELFM_REFINE_GAUSSIAN;
  o->fit_half_xy = 1;
  o->fit_half_z = 3;       /* +-6 um at 2 um planes: a third of the 21 um axial FWHM */
}

elfm_peaks *elfm_peaks_create(const elfm_peaks_options *o, int w, int h, int nz, elfm_error *err)
{
  if (!o || w <= 0 || h <= 0 || nz <= 0) {
    elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "peaks: bad volume size %d x %d x %d", w, h, nz);
    return NULL;
  }
  /* the first option out of range, named with its value and what it takes */
  const struct { int ok; const char *name; double value; const char *what; } need[] = {
    {o->radius_xy_um > 0, "radius_xy_um", o->radius_xy_um, "> 0"},
    {o->radius_z_um > 0, "radius_z_um", o->radius_z_um, "> 0"},
    {o->kz > 0, "kz", o->kz, "> 0"},
    {o->min_separation_um >= 0, "min_separation_um", o->min_separation_um, ">= 0"},
    {isfinite(o->absolute), "absolute", o->absolute, "finite"},
    {isfinite(o->relative) && o->relative <= 1, "relative", o->relative, "<= 1"},
    {isfinite(o->k_sigma), "k_sigma", o->k_sigma, "finite"},
    {o->depth_range_um >= 0 && isfinite(o->depth_range_um), "depth_range_um", o->depth_range_um, ">= 0"},
    {isfinite(o->absolute_min), "absolute_min", o->absolute_min, "finite"},
    {o->hysteresis_low >= 0 && isfinite(o->hysteresis_low), "hysteresis_low", o->hysteresis_low, ">= 0"},
    {o->fit_half_xy >= 0 && o->fit_half_xy <= 8, "fit_half_xy", o->fit_half_xy, "0..8"},
    {o->fit_half_z >= 0 && o->fit_half_z <= 16, "fit_half_z", o->fit_half_z, "0..16"},
    {o->refine >= ELFM_REFINE_GAUSSIAN && o->refine <= ELFM_REFINE_NONE, "refine", (double)o->refine,
     "an elfm_refine"},
  };
  for (size_t k = 0; k < sizeof need / sizeof need[0]; k++)
    if (!need[k].ok) {
      elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "peaks: option %s = %g is out of range (%s)",
                     need[k].name, need[k].value, need[k].what);
      return NULL;
    }
  if ((double)w * h * nz >= 4294967295.0) {  /* the voxel counts are 32-bit */
    elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "peaks: volume of %d x %d x %d is too large", w, h, nz);
    return NULL;
  }
  elfm_peaks *p = calloc(1, sizeof *p);
  if (!p) goto nomem;
  p->opt = *o;
  p->w = w;
  p->h = h;
  p->nz = nz;
  /* With the index tie-break, no two 26-neighbours are both maxima, so at
   * most one voxel in each 2x2x2 block is a candidate. */
  size_t nvox = (size_t)w * h * nz;
  p->cand_cap = nvox / 8 + 64;
  p->cand = malloc(p->cand_cap * sizeof *p->cand);
  p->sample = malloc(PEAKS_NOISE_SAMPLES * sizeof *p->sample);
  p->keys = malloc(PEAKS_NOISE_SAMPLES * sizeof *p->keys);
  p->row_max = malloc((size_t)h * nz * sizeof *p->row_max);
  p->thr_plane = malloc((size_t)nz * sizeof *p->thr_plane);
  p->thr_low = malloc((size_t)nz * sizeof *p->thr_low);
  p->above = calloc((size_t)w + 8, 1); /* the tail past w stays 0: read 8 at a time */
  if (!p->cand || !p->sample || !p->keys || !p->row_max || !p->thr_plane || !p->thr_low ||
      !p->above)
    goto nomem;
  return p;
nomem:
  elfm_peaks_free(p);
  elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "peaks: out of memory");
  return NULL;
}

void elfm_peaks_free(elfm_peaks *p)
{
  if (!p) return;
  free(p->cand);
  free(p->sample);
  free(p->keys);
  free(p->row_max);
  free(p->thr_plane);
  free(p->thr_low);
  free(p->above);
  free(p->views);
  free(p);
}

elfm_status elfm_peaks_set_view_counts(elfm_peaks *p, const uint8_t *count, int n_views,
                                       double exponent, elfm_error *err)
{
  if (!p) return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "peaks: NULL detector");
  free(p->views);
  p->views = NULL;
  p->n_views = 0;
  if (!count) return ELFM_OK;
  if (n_views < 1 || n_views > 255)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "peaks: %d views (1..255)", n_views);
  if (!(exponent >= 0 && exponent <= 4))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "peaks: view exponent %g (0..4)", exponent);
  size_t nvox = (size_t)p->w * p->h * p->nz;
  p->views = malloc(nvox);
  if (!p->views) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "peaks: out of memory");
  memcpy(p->views, count, nvox);
  p->n_views = n_views;
  p->view_scale[0] = INFINITY;  /* no view: never a peak */
  for (int k = 1; k < 256; k++) p->view_scale[k] = pow((double)n_views / k, exponent);
  return ELFM_OK;
}

double elfm_peaks_last_threshold(const elfm_peaks *p) { return p ? p->last_threshold : NAN; }

/* A float's bits as an unsigned key in the floats' order (not NaN): a
 * negative float's bits flipped, a positive one's sign bit set. -0 sorts
 * just below +0, which compare equal: either is the same value below. */
static inline uint32_t float_key(float f)
{
  uint32_t b;
  memcpy(&b, &f, sizeof b);
  return (b & 0x80000000u) ? ~b : b | 0x80000000u;
}

static inline float key_float(uint32_t k)
{
  const uint32_t b = (k & 0x80000000u) ? k & 0x7fffffffu : ~k;
  float f;
  memcpy(&f, &b, sizeof f);
  return f;
}

/* The k-th smallest (from 0) of a[0 .. n-1], k < n, no NaN: a radix
 * selection on float_key, 11 + 11 + 10 bits, each pass counting the keys
 * that share the bits found so far and keeping those of the digit that
 * holds rank k (keys: n of scratch). The same value as any exact
 * selection; Hoare's quickselect, which this replaced, was 2 % of `track`
 * under perf (its partitions branch on every sample: two selections of
 * 16,384 samples per volume). */
static float select_kth(const float *a, size_t n, size_t k, uint32_t *keys)
{
  static const int shift[3] = {21, 10, 0};
  static const uint32_t digits[3] = {2048, 2048, 1024};
  for (size_t i = 0; i < n; i++) keys[i] = float_key(a[i]);
  size_t m = n;
  for (int pass = 0; pass < 3; pass++) {
    uint32_t hist[2048] = {0};
    const uint32_t dm = digits[pass] - 1;
    for (size_t i = 0; i < m; i++) hist[(keys[i] >> shift[pass]) & dm]++;
    uint32_t dg = 0;
    while (k >= hist[dg]) k -= hist[dg++];
    /* keep the keys of digit dg, in place (the write index trails) */
    size_t j = 0;
    for (size_t i = 0; i < m; i++)
      if (((keys[i] >> shift[pass]) & dm) == dg) keys[j++] = keys[i];
    m = j;
  }
  return key_float(keys[0]); /* m keys left, all the same */
}

/* median and 1.4826 * MAD of s[0..n-1] (overwrites s; keys: n of scratch). */
static void robust_stats(float *s, size_t n, uint32_t *keys, double *median, double *sigma)
{
  if (n == 0) { *median = 0; *sigma = 0; return; }
  float med = select_kth(s, n, n / 2, keys);
  for (size_t i = 0; i < n; i++) s[i] = fabsf(s[i] - med);
  float mad = select_kth(s, n, n / 2, keys);
  *median = med;
  *sigma = 1.4826 * mad;  /* MAD -> sigma for Gaussian noise */
}

static int cand_cmp(const void *a, const void *b)
{
  const peak_cand *x = a, *y = b;
  if (x->value != y->value) return x->value < y->value ? 1 : -1;
  /* equal values: voxel order, so results do not depend on qsort */
  if (x->z != y->z) return x->z < y->z ? -1 : 1;
  if (x->y != y->y) return x->y < y->y ? -1 : 1;
  return (x->x > y->x) - (x->x < y->x);
}

/* Is voxel (x,y,z) the maximum of the box of half-sizes (rx,ry,rz)? Ties go
 * to the lower linear index. */
static int is_box_max(const float *d, int w, int h, int nz, int x, int y, int z, int rx, int rz)
{
  float c = d[((size_t)z * h + y) * w + x];
  size_t ic = ((size_t)z * h + y) * w + x;
  int z0 = z - rz < 0 ? 0 : z - rz, z1 = z + rz >= nz ? nz - 1 : z + rz;
  int y0 = y - rx < 0 ? 0 : y - rx, y1 = y + rx >= h ? h - 1 : y + rx;
  int x0 = x - rx < 0 ? 0 : x - rx, x1 = x + rx >= w ? w - 1 : x + rx;
  for (int k = z0; k <= z1; k++)
    for (int j = y0; j <= y1; j++) {
      const float *row = d + ((size_t)k * h + j) * w;
      size_t ibase = ((size_t)k * h + j) * w;
      for (int i = x0; i <= x1; i++) {
        float q = row[i];
        if (q > c || (q == c && ibase + i < ic)) return 0;
      }
    }
  return 1;
}

/* Weighted least-squares parabola y = a + b t + c t^2 over t = -m..m; the
 * vertex offset (clamped to +-1 voxel), the value there and the curvature
 * c. Returns 0 when the fit has no maximum. */
static int fit_parabola(const double *t, const double *y, const double *wt, int n,
                        double *off, double *peak, double *curv)
{
  double s0 = 0, s1 = 0, s2 = 0, s3 = 0, s4 = 0, r0 = 0, r1 = 0, r2 = 0;
  for (int i = 0; i < n; i++) {
    double w = wt[i], ti = t[i], t2 = ti * ti;
    s0 += w; s1 += w * ti; s2 += w * t2; s3 += w * t2 * ti; s4 += w * t2 * t2;
    r0 += w * y[i]; r1 += w * ti * y[i]; r2 += w * t2 * y[i];
  }
  /* Cramer's rule on the 3x3 normal equations [s0 s1 s2; s1 s2 s3; s2 s3 s4]. */
  double det = s0 * (s2 * s4 - s3 * s3) - s1 * (s1 * s4 - s3 * s2) + s2 * (s1 * s3 - s2 * s2);
  if (!(fabs(det) > 1e-300)) return 0;
  double a = (r0 * (s2 * s4 - s3 * s3) - s1 * (r1 * s4 - s3 * r2) + s2 * (r1 * s3 - s2 * r2)) / det;
  double b = (s0 * (r1 * s4 - r2 * s3) - r0 * (s1 * s4 - s3 * s2) + s2 * (s1 * r2 - r1 * s2)) / det;
  double c = (s0 * (s2 * r2 - s3 * r1) - s1 * (s1 * r2 - s2 * r1) + r0 * (s1 * s3 - s2 * s2)) / det;
  if (!(c < 0)) return 0;
  double o = -b / (2 * c);
  if (o > 1) o = 1;
  if (o < -1) o = -1;
  *off = o;
  *peak = a + b * o + c * o * o;
  *curv = c;
  return 1;
}

/* Refine one axis. `stride` steps along the axis in the data array, `pos`
 * is the peak's index on it and `len` the axis length. Writes the offset
 * (voxels), the width (voxels, 0 when unknown) and the refined value. */
static void refine_axis(const float *d, size_t ic, size_t stride, int pos, int len, int m,
                        elfm_refine_mode mode, double *off, double *sigma_vox, double *value)
{
  double t[33], y[33], wt[33];
  *off = 0;
  *sigma_vox = 0;
  *value = d[ic];
  if (mode == ELFM_REFINE_NONE) return;
  /* Largest symmetric window inside the volume with positive samples
   * (ln needs > 0; a zero means the blob ended there). */
  if (m > pos) m = pos;
  if (m > len - 1 - pos) m = len - 1 - pos;
  for (int k = 1; k <= m; k++) {
    if (!(d[ic - k * stride] > 0) || !(d[ic + k * stride] > 0)) { m = k - 1; break; }
  }
  if (m < 1 || !(d[ic] > 0)) return;
  int n = 0;
  for (int k = -m; k <= m; k++) {
    double f = d[(size_t)((ptrdiff_t)ic + (ptrdiff_t)k * (ptrdiff_t)stride)];
    t[n] = k;
    if (mode == ELFM_REFINE_GAUSSIAN) {
      y[n] = log(f);
      wt[n] = f * f;  /* ln-domain weights ~ f^2 undo the noise blow-up in the tails */
    } else {
      y[n] = f;
      wt[n] = 1;
    }
    n++;
  }
  double o, pk, c;
  if (!fit_parabola(t, y, wt, n, &o, &pk, &c)) return;
  *off = o;
  if (mode == ELFM_REFINE_GAUSSIAN) {
    *sigma_vox = sqrt(-1.0 / (2 * c));   /* ln G = const - t^2 / (2 sigma^2) */
    *value = exp(pk);
  } else {
    *sigma_vox = pk > 0 ? sqrt(-pk / (2 * c)) : 0;  /* f0 (1 - t^2/(2 sigma^2)) */
    *value = pk;
  }
}

/* The streaming pass of elfm_peaks_detect (see there): per-row maximum as
 * int32 bits, the largest magnitude (NaN check) and the non-zero count.
 * Memory-bound; on x86-64 an AVX2 clone is picked at load time when the CPU
 * has it (SSE2 has no 32-bit integer max: 4 instructions instead of 1). */
#if defined(__x86_64__) && defined(__GNUC__) && defined(__linux__)
__attribute__((target_clones("avx2", "default")))
#endif
static void scan_rows(const float *restrict d, int w, size_t nrows, int32_t *restrict row_max,
                      uint32_t *mag_max_out, int32_t *imax_out, size_t *nonzero_out)
{
  uint32_t mag_max = 0;
  size_t nonzero = 0;
  int32_t imax = INT32_MIN;
  for (size_t r = 0; r < nrows; r++) {
    const float *restrict row = d + r * (size_t)w;
    uint32_t rmag = 0, rnz = 0;
    int32_t rmax = INT32_MIN;
    for (int x = 0; x < w; x++) {
      uint32_t b;
      memcpy(&b, &row[x], sizeof b);
      uint32_t mag = b & 0x7fffffffu;
      int32_t sb = (int32_t)b;
      rmag = mag > rmag ? mag : rmag;
      rmax = sb > rmax ? sb : rmax;
      rnz += mag != 0;
    }
    row_max[r] = rmax;
    mag_max = rmag > mag_max ? rmag : mag_max;
    imax = rmax > imax ? rmax : imax;
    nonzero += rnz;
  }
  *mag_max_out = mag_max;
  *imax_out = imax;
  *nonzero_out = nonzero;
}

/* above[x] = 1 where row[x] > thr, else 0: a loop the compiler vectorises,
 * so that the candidate search of elfm_peaks_detect reads a row's voxels
 * above the threshold one by one and skips the rest eight at a time
 * (any8). In a flow volume most voxels of a row whose maximum passes lie
 * below the threshold. */
static void mark_above(const float *restrict row, int w, float thr, uint8_t *restrict above)
{
  for (int x = 0; x < w; x++) above[x] = row[x] > thr;
}

/* Is any of the eight flags at a set? */
static int any8(const uint8_t *a)
{
  uint64_t m;
  memcpy(&m, a, sizeof m);
  return m != 0;
}

/* The blob's lateral width along its widest axis at voxel (x, y, z) of v
 * (elfm_detection.width_um), in voxels: the larger eigenvalue's square root
 * of the second moments, in the peak's plane, of the values above half the
 * peak's, within +-WIDTH_HALF_VOX. Why the widest axis and not the per-axis
 * fits: a moving bead's events form an arc across its motion, and the arc's
 * length (how far the image's tail reaches above the sensor's threshold:
 * the beads' brightness) shows on the x or y fit only when the motion lies
 * along the other axis (docs/tracker.md "Motion bias"). */
#define WIDTH_HALF_VOX 6
static double blob_width_vox(const elfm_volume *v, int x, int y, int z, double f0)
{
  const float *pl = v->data + (size_t)z * v->h * v->w;
  double m = 0, mx = 0, my = 0, mxx = 0, myy = 0, mxy = 0;
  for (int yy = y - WIDTH_HALF_VOX; yy <= y + WIDTH_HALF_VOX; yy++) {
    if (yy < 0 || yy >= v->h) continue;
    for (int xx = x - WIDTH_HALF_VOX; xx <= x + WIDTH_HALF_VOX; xx++) {
      if (xx < 0 || xx >= v->w) continue;
      const double f = pl[(size_t)yy * v->w + xx] - 0.5 * f0;
      if (!(f > 0)) continue;
      const double dx = xx - x, dy = yy - y;
      m += f;
      mx += f * dx;
      my += f * dy;
      mxx += f * dx * dx;
      myy += f * dy * dy;
      mxy += f * dx * dy;
    }
  }
  if (!(m > 0)) return 0;
  mx /= m;
  my /= m;
  const double cxx = mxx / m - mx * mx, cyy = myy / m - my * my, cxy = mxy / m - mx * my;
  const double half_tr = 0.5 * (cxx + cyy);
  const double r = sqrt(0.25 * (cxx - cyy) * (cxx - cyy) + cxy * cxy);
  return sqrt(fmax(half_tr + r, 0.0));
}

/* Refine the peak at voxel (x, y, z) of v and fill det (elfm_peaks_detect). */
static void fill_detection(const elfm_peaks_options *o, const elfm_volume *v, int x, int y, int z,
                           int weak, elfm_detection *det)
{
  const int w = v->w, h = v->h, nz = v->nz;
  const float *d = v->data;
  size_t ic = ((size_t)z * h + y) * w + x;
  double ox, oy, oz, sx, sy, sz, vx, vy, vz;
  refine_axis(d, ic, 1, x, w, o->fit_half_xy, o->refine, &ox, &sx, &vx);
  refine_axis(d, ic, (size_t)w, y, h, o->fit_half_xy, o->refine, &oy, &sy, &vy);
  refine_axis(d, ic, (size_t)w * h, z, nz, o->fit_half_z, o->refine, &oz, &sz, &vz);
  det->weak = weak;
  det->view_fit = 0;
  det->deep_only = 0;
  det->fit_sd_px = 0;
  det->nearest_um = 0;
  det->claims = 0;
  det->frame = v->frame;
  det->t_us = v->t_us;
  det->x_um = elfm_volume_x_um(v, x + ox);
  det->y_um = elfm_volume_y_um(v, y + oy);
  det->z_um = elfm_volume_z_um(v, z + oz);
  /* Each axis' fit runs through the voxel centre of the other two; for a
   * separable blob the peak value is the product of the three per-axis
   * gains over the centre voxel. */
  double f0 = d[ic];
  det->intensity = f0 > 0 ? vx * (vy / f0) * (vz / f0) : f0;
  det->sigma_x_um = sx * v->um_per_px;
  det->sigma_y_um = sy * v->um_per_px;
  det->sigma_z_um = sz * v->z_step_um;
  det->width_um = f0 > 0 ? blob_width_vox(v, x, y, z, f0) * v->um_per_px : 0;
}

void elfm_peaks_refine_at(const elfm_peaks *p, const elfm_volume *v, int x, int y, int z,
                          elfm_detection *det)
{
  const int deep = det->deep_only;
  fill_detection(&p->opt, v, x, y, z, det->weak, det);
  det->deep_only = deep;
}

elfm_status elfm_peaks_find_near(const elfm_peaks *p, const elfm_volume *v, const double xyz_um[3],
                                 double radius_xy_um, double radius_z_um, double min_value,
                                 elfm_detection *out, int *found, elfm_error *err)
{
  if (!p || !v || !v->data || !xyz_um || !out || !found || !(radius_xy_um >= 0) ||
      !(radius_z_um >= 0) || !(v->um_per_px > 0) || !(v->z_step_um > 0))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "peaks: bad arguments to find_near");
  *found = 0;
  if (!isfinite(xyz_um[0]) || !isfinite(xyz_um[1]) || !isfinite(xyz_um[2])) return ELFM_OK;
  const int w = v->w, h = v->h, nz = v->nz;
  /* voxel box around the point, clipped to the volume (the inverse of
   * elfm_volume_x_um etc.: voxel i sits at origin + i x step) */
  double cx = (xyz_um[0] - elfm_volume_x_um(v, 0)) / v->um_per_px,
         cy = (xyz_um[1] - elfm_volume_y_um(v, 0)) / v->um_per_px,
         cz = (xyz_um[2] - elfm_volume_z_um(v, 0)) / v->z_step_um;
  double rx = radius_xy_um / v->um_per_px, rz = radius_z_um / v->z_step_um;
  double fx0 = ceil(cx - rx), fx1 = floor(cx + rx), fy0 = ceil(cy - rx), fy1 = floor(cy + rx),
         fz0 = ceil(cz - rz), fz1 = floor(cz + rz);
  if (fx1 < 0 || fy1 < 0 || fz1 < 0 || fx0 > w - 1 || fy0 > h - 1 || fz0 > nz - 1) return ELFM_OK;
  int x0 = fx0 < 0 ? 0 : (int)fx0, x1 = fx1 > w - 1 ? w - 1 : (int)fx1;
  int y0 = fy0 < 0 ? 0 : (int)fy0, y1 = fy1 > h - 1 ? h - 1 : (int)fy1;
  int z0 = fz0 < 0 ? 0 : (int)fz0, z1 = fz1 > nz - 1 ? nz - 1 : (int)fz1;
  const float *d = v->data;
  int bx = -1, by = -1, bz = -1;
  float best = 0;
  for (int z = z0; z <= z1; z++)
    for (int y = y0; y <= y1; y++)
      for (int x = x0; x <= x1; x++) {
        float c = d[((size_t)z * h + y) * w + x];
        if (isnan(c))
          return elfm_error_set(err, ELFM_ERR_NUMERIC, NULL, -1, "peaks: NaN voxel");
        double ex = (x - cx) / rx, ey = (y - cy) / rx, ez = rz > 0 ? (z - cz) / rz : 0;
        if (rx > 0 && ex * ex + ey * ey + ez * ez > 1) continue;  /* ellipsoid, as the gate */
        if (!((double)c > min_value) || (bx >= 0 && !(c > best))) continue;
        if (!is_box_max(d, w, h, nz, x, y, z, 1, 1)) continue;  /* a maximum, not a slope */
        best = c;
        bx = x;
        by = y;
        bz = z;
      }
  if (bx < 0) return ELFM_OK;
  fill_detection(&p->opt, v, bx, by, bz, 1, out);
  *found = 1;
  return ELFM_OK;
}

elfm_status elfm_peaks_detect(elfm_peaks *p, const elfm_volume *v, elfm_detection *out, int cap,
                              int *n_out, elfm_error *err)
{
  if (n_out) *n_out = 0;
  if (!p || !v || !v->data || !n_out || cap < 0 || (cap > 0 && !out))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "peaks: NULL argument");
  if (v->w != p->w || v->h != p->h || v->nz != p->nz)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "peaks: volume is %d x %d x %d, detector was made for %d x %d x %d",
                          v->w, v->h, v->nz, p->w, p->h, p->nz);
  if (!(v->um_per_px > 0) || !(v->z_step_um > 0) || !isfinite(v->z_min_um))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "peaks: volume has no valid axes");
  const elfm_peaks_options *o = &p->opt;
  const int w = v->w, h = v->h, nz = v->nz;
  const size_t nvox = (size_t)w * h * nz;
  const float *d = v->data;

  /* One streaming pass over the volume (the only one that reads every
   * voxel): per-row maximum, the non-zero count and NaN. Done on the bit
   * patterns in integers so that it vectorises (a float max reduction does
   * not without -ffast-math): for IEEE floats a magnitude above inf's is
   * NaN, magnitude 0 is zero, and among non-negative floats the integer
   * order is the float order (negative values never make a peak: only a
   * positive maximum matters). The row maxima let the candidate search
   * below skip every row with nothing above the threshold (in a time
   * surface nearly all of them) without reading it again. */
  const size_t nrows = (size_t)h * nz;
  uint32_t mag_max = 0;
  size_t nonzero = 0;
  int32_t imax = INT32_MIN;
  scan_rows(d, w, nrows, p->row_max, &mag_max, &imax, &nonzero);
  int nan_seen = mag_max > 0x7f800000u;
  float vmax = 0;
  if (imax > 0) memcpy(&vmax, &imax, sizeof vmax);
  if (nan_seen) {
    size_t i = 0;
    while (!isnan(d[i])) i++;
    return elfm_error_set(err, ELFM_ERR_NUMERIC, NULL, -1,
                          "peaks: NaN voxel at index %zu of frame %lld", i, (long long)v->frame);
  }
  /* thr: the depth-independent rules; the absolute one is per plane below */
  double thr = -INFINITY;
  if (o->relative > 0 && o->relative * vmax > thr) thr = o->relative * vmax;
  if (o->k_sigma > 0 && nonzero > 0) {
    /* A strided sample of the volume; in mostly-zero volumes (thresholded
     * surfaces, MAD 0) only its non-zero voxels, where the noise lives,
     * sampling more densely until there are enough of them. */
    int nonzero_only = nonzero * 2 < nvox;
    size_t n = 0;
    /* 64 runs of consecutive voxels (256: 1 KB each) spread over the volume
     * (sequential reads: single strided voxels cost a cache miss each);
     * more runs until there are enough non-zero samples or the whole volume
     * was seen. */
    const size_t run = PEAKS_NOISE_SAMPLES / 64;
    for (size_t nruns = 64;; nruns *= 8) {
      n = 0;
      size_t step = nvox / nruns;
      if (step < run) step = run;
      for (size_t s0 = 0; s0 < nvox && n < PEAKS_NOISE_SAMPLES; s0 += step) {
        size_t e = s0 + run < nvox ? s0 + run : nvox;
        for (size_t i = s0; i < e && n < PEAKS_NOISE_SAMPLES; i++)
          if (!nonzero_only || d[i] != 0) p->sample[n++] = d[i];
      }
      if (n >= PEAKS_NOISE_SAMPLES / 16 || step == run) break;
    }
    double med, sig;
    robust_stats(p->sample, n, p->keys, &med, &sig);
    double t = med + o->k_sigma * sig;
    if (t > thr) thr = t;
  }
  /* Absolute rule per plane: abs / (1 + (z / depth_range)^2), at least
   * absolute_min (see elfm_peaks.h: the peak of a defocused image falls as
   * 1 / sigma(z)^2). */
  double thr0 = thr;
  for (int k = 0; k < nz; k++) {
    double t = thr0;
    if (o->absolute > 0) {
      double a = o->absolute;
      if (o->depth_range_um > 0) {
        double q = elfm_volume_z_um(v, k) / o->depth_range_um;
        a = o->absolute / (1 + q * q);
        if (a < o->absolute_min) a = o->absolute_min;
      }
      if (a > t) t = a;
    }
    if (t == -INFINITY) t = 0;
    p->thr_plane[k] = t;
    /* low threshold: the hysteresis value in place of the absolute rule */
    double lo = t;
    if (o->hysteresis_low > 0) {
      lo = thr0 > o->hysteresis_low ? thr0 : o->hysteresis_low;
      if (lo > t) lo = t;
    }
    p->thr_low[k] = lo;
  }
  thr = o->absolute > thr0 ? o->absolute : thr0;
  if (thr == -INFINITY) thr = 0;
  p->last_threshold = thr;

  /* Candidates: above threshold and maximum of the 3x3x3 neighbourhood, then
   * of the full anisotropic box. */
  int rx = (int)ceil(o->radius_xy_um / v->um_per_px - 1e-9);
  int rz = (int)ceil(o->radius_z_um / v->z_step_um - 1e-9);
  if (rx < 1) rx = 1;
  if (rz < 1) rz = 1;
  size_t nc = 0;
  for (int z = 0; z < nz; z++) {
    /* compare in float: a voxel passes when its float value exceeds thr
     * (the low threshold; above thr_hi the peak is strong) */
    const double thr = p->thr_low[z], thr_hi = p->thr_plane[z];
    const float thr_f = thr > 0 ? (float)thr : 0.0f;
    int32_t thr_bits;
    memcpy(&thr_bits, &thr_f, sizeof thr_bits);
    for (int y = 0; y < h; y++) {
      /* a row whose maximum is not above the threshold has no candidate
       * (thr_f >= 0, where the bits' integer order is the float order) */
      if (p->row_max[(size_t)z * h + y] <= thr_bits) continue;
      const float *row = d + ((size_t)z * h + y) * w;
      mark_above(row, w, thr_f, p->above);
      for (int x = 0; x < w; x++) {
        if ((x & 7) == 0 && !any8(p->above + x)) {
          x += 7; /* eight voxels at or below the threshold */
          continue;
        }
        if (!p->above[x]) continue;
        float c = row[x];
        if ((double)c <= thr) continue;
        /* the row's two neighbours first (most voxels above the
         * threshold lie on a blob's slope), with is_box_max's tie rule:
         * an equal voxel at a lower index wins */
        if ((x > 0 && row[x - 1] >= c) || (x + 1 < w && row[x + 1] > c)) continue;
        if (!is_box_max(d, w, h, nz, x, y, z, 1, 1)) continue;
        if (!is_box_max(d, w, h, nz, x, y, z, rx, rz)) continue;
        int weak = !((double)c > thr_hi);
        double f = 1;
        if (p->views) {
          /* threshold x (N / n)^e where n views sample the voxel (elfm_peaks.h) */
          f = p->view_scale[p->views[((size_t)z * h + y) * w + x]];
          if (!((double)c > thr * f)) continue;
          weak = !((double)c > thr_hi * f);
        }
        /* would the plain absolute rule (no depth scaling) have let it in? */
        int deep = o->depth_range_um > 0 && o->absolute > 0 && !weak &&
                   !((double)c > (o->absolute > thr0 ? o->absolute : thr0) * f);
        if (nc < p->cand_cap) p->cand[nc++] = (peak_cand){c, x, y, z, weak, deep};
      }
    }
  }
  qsort(p->cand, nc, sizeof *p->cand, cand_cmp);

  /* Minimum separation (anisotropic) against the stronger accepted peaks,
   * then refinement of the accepted ones. */
  const double kz = o->kz, sep2 = o->min_separation_um * o->min_separation_um;
  int n = 0;
  for (size_t c = 0; c < nc && n < cap; c++) {
    const peak_cand *pc = &p->cand[c];
    double xv = elfm_volume_x_um(v, pc->x), yv = elfm_volume_y_um(v, pc->y),
           zv = elfm_volume_z_um(v, pc->z);
    int keep = 1;
    for (int a = 0; a < n && keep; a++) {
      /* compare voxel positions (refinement moves peaks by < 1 voxel) */
      double dx = xv - out[a].x_um, dy = yv - out[a].y_um, dz = (zv - out[a].z_um) / kz;
      if (dx * dx + dy * dy + dz * dz < sep2) keep = 0;
    }
    if (!keep) continue;
    fill_detection(o, v, pc->x, pc->y, pc->z, pc->weak, &out[n]);
    out[n++].deep_only = pc->deep;
  }
  *n_out = n;
  return ELFM_OK;
}

/* ln erfc(z) without underflow: the asymptotic series beyond z = 5
 * (relative error < 1e-6 there; Abramowitz & Stegun 7.1.23). */
static double log_erfc(double z)
{
  if (z < 5) return log(erfc(z));
  double z2 = z * z;
  return -z2 - log(z * 1.7724538509055160) + log1p(-1 / (2 * z2) + 3 / (4 * z2 * z2));
}

double elfm_peaks_trail_lag_um(double trail_um, double sigma_um)
{
  if (!(trail_um > 0) || !(sigma_um > 0) || !isfinite(trail_um) || !isfinite(sigma_um)) return 0;
  const double L = trail_um, s = sigma_um;
  /* A trail much shorter than the blob only shifts it by its mean length
   * (the search below would lose all digits to cancellation there). */
  if (L < 1e-3 * s) return L;
  /* log g(x) = x/L + ln erfc((x + s^2/L)/(s sqrt 2)) is concave (the
   * convolution of two log-concave functions), so golden-section search on
   * [-(L + 4 s), 0] finds its maximum; erfc underflow is avoided by
   * staying within 4 sigma ahead of the trail's centre. */
  double lo = -(L + 4 * s), hi = 0;
  const double gr = 0.6180339887498949;
#define LOGG(x) ((x) / L + log_erfc(((x) + s * s / L) / (s * 1.4142135623730951)))
  double a = hi - gr * (hi - lo), b = lo + gr * (hi - lo);
  double fa = LOGG(a), fb = LOGG(b);
  for (int it = 0; it < 80 && hi - lo > 1e-9 * (L + s); it++) {
    if (fa < fb) { lo = a; a = b; fa = fb; b = lo + gr * (hi - lo); fb = LOGG(b); }
    else { hi = b; b = a; fb = fa; a = hi - gr * (hi - lo); fa = LOGG(a); }
  }
#undef LOGG
  double xmax = 0.5 * (lo + hi);
  return xmax < 0 ? -xmax : 0;
}

void elfm_detection_correct_lag(elfm_detection *d, double vx, double vy, double vz, double tau_us)
{
  elfm_detection_correct_lag_lead(d, vx, vy, vz, tau_us, 0.0);
}

void elfm_detection_correct_lag_lead(elfm_detection *d, double vx, double vy, double vz,
                                     double tau_us, double lead_sigmas)
{
  double speed = sqrt(vx * vx + vy * vy + vz * vz);
  if (!d || !(speed > 0) || !(tau_us > 0) || !isfinite(speed)) return;
  double ux = vx / speed, uy = vy / speed, uz = vz / speed;
  /* blob width along the motion: project the per-axis widths */
  double s2 = ux * ux * d->sigma_x_um * d->sigma_x_um + uy * uy * d->sigma_y_um * d->sigma_y_um +
              uz * uz * d->sigma_z_um * d->sigma_z_um;
  double s = s2 > 0 ? sqrt(s2) : 0;
  if (!(s > 0)) return;
  double lag = elfm_peaks_trail_lag_um(speed * tau_us * 1e-3, s) - lead_sigmas * s;
  d->x_um += ux * lag;
  d->y_um += uy * lag;
  d->z_um += uz * lag;
}
