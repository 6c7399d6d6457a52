/* sim_ws.h — private to datasets/: the simulation workspace shared by the
 * physics (sim_step.c: images, pixel model, time steps, noise) and the
 * driver (sim.c: slices, time order, output files). */
#ifndef ELFM_SIM_WS_H
#define ELFM_SIM_WS_H

#include <stddef.h>
#include <stdint.h>

#include "sim_internal.h"

#define TWO_PI 6.283185307179586
#define STREAM_NOISE 0x4e4f495345ull  /* "NOISE" */
#define STREAM_SIGNAL 0x5349474eull   /* "SIGN" */
#define STREAM_THRESH 0x544852ull     /* "THR" */
#define STREAM_FRESH 0x465245ull      /* "FRE" */

/* Gaussian approximation of the Airy core: sigma = 0.21 lambda / NA
 * (Zhang, Zerubia & Olivo-Marin, Appl. Opt. 2007). */
#define AIRY_SIGMA_FACTOR 0.21
/* An image is cut where it adds less than 4 % to the background. ln(1.04)
 * = 0.04 is a fifth of the 0.2 contrast threshold; as an image approaches,
 * a pixel's light rises monotonically anyway, so the cut only moves that
 * pixel's first crossing a little earlier, it adds no events. */
#define BOX_EPS 0.04
/* Samples of each object's path per slice window (bounding boxes, speed). */
#define PATH_SAMPLES 9
/* Step length: an image moves at most this many PSF sigmas per step. ln I
 * of a Gaussian image is quadratic in position, so the chord between two
 * steps deviates from it by at most (0.75 sigma)^2 / (8 sigma^2) = 0.07 ln
 * units, a third of the 0.2 threshold: crossing times interpolated along the
 * chord err by a few us on an image's flanks, where most events are. */
#define STEP_SIGMA_FRACTION 0.75
#define MIN_STEP_US 2
/* Standard normal CDF table on [-8, 8], 64 points per sigma: linear
 * interpolation error < 1e-5. */
#define PHI_LIM 8.0
#define PHI_PER_SIGMA 64
#define PHI_N (2 * 8 * PHI_PER_SIGMA + 2) /* 2 * PHI_LIM * PHI_PER_SIGMA + 2 */

typedef struct sim_event {
  int64_t t_us;
  uint16_t x, y;
  uint8_t p;
} sim_event;

typedef struct sim_box {
  int obj, view, comp;   /* comp 0: core image, 1: scattering haze */
  int dynamic;
  int x0, y0, x1, y1;    /* [x0, x1) x [y0, y1) on the sensor */
  double r_px;           /* how far from the centre the image matters */
} sim_box;

/* Per object, per slice. */
typedef struct sim_objslice {
  int visible, dynamic;
  double amp_max_hz, sigma_max_px, sigma_min_px, speed_px_per_us;
  /* at the current step */
  double amp_hz, sigma_px;
  double pos[3];
  /* the object's contribution to the static base, if any */
  int in_base;
  double base_pos[3], base_amp_hz, base_sigma_px;
} sim_objslice;

typedef struct sim_stim {
  int64_t t_us;
  int channel, value;
} sim_stim;

typedef struct sim_rect {
  int x0, y0, x1, y1;
} sim_rect;

/* One image at one step: its pixels, amplitude, and where its x and y
 * profiles start in gbuf (x then y). */
typedef struct sim_img {
  sim_rect rc;
  double amp;
  size_t g;
} sim_img;

/* Rows per band of the step loop: the pixels touched in a band (~10^4 for
 * 100 beads) fit in a 2 MB L2 cache with their 32-byte records. */
#define SIM_BAND_ROWS 32

/* A pixel's state in one 32-byte record: the step loop touches all of it,
 * and one cache line then holds two pixels instead of seven arrays' worth
 * of lines (the loop is memory-bound). */
typedef struct sim_pixel {
  float ifull;    /* photocurrent accumulated for this step (== base between steps) */
  float base;     /* background + static images */
  float llp;      /* low-passed ln photocurrent */
  float lref;     /* reference level of the last event */
  float con, coff;/* ON / OFF thresholds; con == 0: never initialised */
  uint32_t mark;  /* step that last processed the pixel */
  uint32_t tlast_q; /* last event (crossing) time in quarter us, modulo 2^32 */
} sim_pixel;

/* Event times in the refractory check: quarter microseconds in 32 bits
 * wrap after 1074 s; differences are taken modulo 2^32, so only a pixel
 * silent for more than 537 s could be wrongly held back, once. */
#define TQ_PER_US 4.0

typedef struct sim_ws {
  const elfm_scene *s;
  int W, H;
  size_t npix;
  double umpp, na_sub, dmax, bg;
  double phi[PHI_N];
  /* Full-sensor pixel state. Invariant between steps: ifull == base, the
   * photocurrent of background + static images; a step adds the moving /
   * blinking images into ifull and puts base back as it reads each pixel. */
  sim_pixel *px;
  uint32_t step_id;
  int first_step;  /* the very first step: pixels start settled at the light they see */
  /* pixels still settling (low-pass not yet at its input): stepped until settled */
  int32_t *carry, *carry_next;
  size_t n_carry, n_carry_next, cap_carry, cap_carry_next;
  sim_box *box;
  size_t n_box, cap_box;
  sim_img *img;
  size_t n_img, cap_img;
  double *gbuf;
  size_t cap_gbuf;
  sim_objslice *os;
  int *dyn_obj;
  size_t n_dyn;
  sim_event *ev, *sorted;
  size_t n_ev, cap_ev, cap_sorted;
  uint32_t *counts;
  size_t cap_counts;
  int64_t *steps;
  size_t cap_steps;
  double *gx, *gy;
  size_t cap_gx, cap_gy;
  /* output chunk (our arrays) */
  int64_t *c_t;
  uint16_t *c_x, *c_y;
  uint8_t *c_p;
  size_t cap_ct, cap_cx, cap_cy, cap_cp;
  elfm_trigger *c_trig;
  size_t cap_trig;
  sim_stim *stim;
  size_t n_stim, cap_stim;
  sim_rng rng;     /* this slice's latency jitter */
  elfm_sim_stats st;
} sim_ws;

/* A pixel counts as settled when its low-pass output is within this of its
 * input (ln units): 1/200 of the 0.2 threshold, so what is left of the
 * relaxation cannot cross a threshold except by a hair. */
#define SETTLE_TOL 1e-3f

/* Grow *p (elements of `elem` bytes) to hold `need`, doubling; 0 when out
 * of memory (then *p and *cap are unchanged). Called only when a slice
 * needs more than any before it. */
int sim_grow(void **p, size_t *cap, size_t need, size_t elem);
/* Allocate the pixel state for s (free with sim_ws_free, even after a failure). */
elfm_status sim_ws_init(sim_ws *w, const elfm_scene *s, elfm_error *err);
void sim_ws_free(sim_ws *w);
/* Slice [a, b) (us from t0), index q: which images change, then step the
 * pixels under them (events into w->ev), then the background activity. */
elfm_status sim_plan_slice(sim_ws *w, int64_t a, int64_t b, elfm_error *err);
elfm_status sim_step_slice(sim_ws *w, int64_t q, int64_t a, int64_t b, elfm_error *err);
elfm_status sim_noise_slice(sim_ws *w, int64_t q, int64_t a, int64_t b, elfm_error *err);

#endif
