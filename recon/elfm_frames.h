/* elfm_frames.h — events -> frames (time surfaces, event counts) and the
 * median filter that cleans them.
 *
 * A frame is a full-sensor image of floats that is mostly zero: besides the
 * dense `data`, it lists the pixels that may be non-zero (`idx`), so that
 * building, filtering, clearing and the event-sparse refocus cost O(listed
 * pixels), not O(sensor). Invariant: data[i] != 0 only if i is in
 * idx[0..nnz); each index is listed at most once; nnz <= w*h.
 *
 * Windows (SPEC §5): window n covers [start + n*stride, start + n*stride + dt).
 * With ELFM_START_EACH_TRIGGER every rising trigger edge (an LED driver's
 * "on") also restarts that grid: the window the edge falls in ends at the
 * edge, and the next window starts there. Each light pulse then opens a
 * window of its own, whatever its phase against the grid; without it a
 * 1 ms pulse at a random phase spreads over two 1 ms windows (blinking
 * beads, docs/tracker.md "Windows opened by the LED").
 * Representations, evaluated at the window's end t1 from the events inside
 * the window (events before the window do not contribute):
 *   EXP   255 * exp(-(t1 - t_last) / tau)       t_us = t1 (window end)
 *   LIN   255 * max(0, 1 - (t1 - t_last) / tau) t_us = t1
 *   COUNT number of events                      t_us = window centre
 * where t_last is the pixel's latest event in the window. Polarity: ON or
 * OFF keep only those events; BOTH keeps all; SIGNED gives a time surface
 * the sign of the latest event (+ ON, - OFF) and counts ON minus OFF.
 *
 * INTEGRAL is the one representation with memory across windows: each
 * pixel integrates every event since the start, +1 per ON and -off_weight
 * per OFF (off_weight = the OFF/ON contrast thresholds' ratio), with a leak
 * exp(-age / tau_us) towards 0. An event marks a log-brightness step of one
 * threshold, so the sum is the pixel's log brightness relative to where it
 * started, in ON-threshold units: an image of the object where it is *now*,
 * not of its leading edge (ON events crowd ahead of a moving blob, so an ON
 * time surface leads the object along its motion). The leak forgets the
 * thresholds' per-pixel mismatch and noise; it must be long against the
 * time an object takes to cross its own width (tau_us x speed >> size),
 * else the sum is again a temporal derivative that leads. A level above 0
 * (an object there) may leak more slowly, with tau_bright_us: when an
 * object leaves a pixel, its OFF events undo the level it had built, not
 * the level it leaked to, and leave a dark residue that a second object
 * arriving there soon after fills first (a C. elegans neuron following
 * its partner along the body, 6 um and ~60 ms behind). With L the sum
 * plus the expected half step of the latest event (+1/2 after ON,
 * -off_weight/2 after OFF: a pixel fires only once a whole step is
 * crossed), the frame is
 *   INTEGRAL  (255 / 8) * (L - F) where L > F, else 0    t_us = t1
 * with the floor F = ELFM_INTEGRAL_FLOOR (8 steps above it, a brightness
 * ratio of ~5 at a 0.2 threshold, map to 255 as a fresh time-surface pixel
 * does).
 * Needs both polarities: polarity BOTH or SIGNED (the same here).
 *
 * The framer is stateful across chunks: it keeps the events of the windows
 * still open (a FIFO whose size is bounded by the event rate x (dt + one
 * chunk)), so memory does not grow with the recording; nothing is allocated
 * per event or per frame once the FIFO has reached its working size.
 */
#ifndef ELFM_FRAMES_H
#define ELFM_FRAMES_H

#include <stddef.h>
#include <stdint.h>

#include "elfm_error.h"
#include "elfm_events.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum elfm_repr {
  ELFM_REPR_EXP = 0,  /* exponential time surface (the paper's) */
  ELFM_REPR_LIN,      /* linear time surface */
  ELFM_REPR_COUNT,    /* plain event count */
  ELFM_REPR_INTEGRAL  /* leaky integral of signed events: log brightness (see above) */
} elfm_repr;

typedef enum elfm_polarity {
  ELFM_POL_BOTH = 0,
  ELFM_POL_ON,
  ELFM_POL_OFF,
  ELFM_POL_SIGNED
} elfm_polarity;

typedef enum elfm_frame_start {
  ELFM_START_FIRST_EVENT = 0, /* first window starts at the first event */
  ELFM_START_AT_TIME,         /* ... at options.start_us */
  ELFM_START_FIRST_TRIGGER,   /* ... at the first trigger edge (stimulus onset) */
  ELFM_START_EACH_TRIGGER     /* ... at the first, and every rising edge restarts the grid */
} elfm_frame_start;

typedef struct elfm_frame {
  int w, h;            /* sensor size */
  float *data;         /* w*h, row-major, zero outside idx */
  uint32_t *idx;       /* pixels that may be non-zero (y*w + x) */
  size_t nnz, cap;     /* listed pixels; cap == w*h */
  int64_t t_us;        /* time the representation stands for (SPEC §5) */
  int64_t t_start_us, t_end_us; /* the window [t_start, t_end) */
  int64_t index;       /* window number n, 0 for the first window */
  size_t n_events;     /* events that fell into the window (after polarity) */
  int64_t n_triggers;  /* rising trigger edges (of trigger_channel, or any) from the
                          recording's start up to the window's end: a caller can tell
                          pulsed light from the frames alone */
  float recent_floor;  /* > 0 on a deep window's frame (elfm_framer_options.deep_window_us):
                          a value >= it is a pixel whose latest event lies in the
                          window [t_start, t_end), a smaller one older; 0: every
                          pixel is the window's */
  size_t nnz_recent;   /* with recent_floor > 0: idx[nnz_recent .. nnz) hold older pixels
                          only (the framer lists the window's first), so a reader of
                          the window's pixels may stop there; before it, a pixel may
                          be either (test the floor) */
} elfm_frame;

/* A reader of the window's pixels alone (the refocus, the occupancy): it
 * goes over idx[0 .. elfm_frame_n_window(f)) and keeps the nonzero values v
 * for which elfm_frame_in_window(f, v) holds; on a frame without a deep
 * window, every listed pixel. */
static inline size_t elfm_frame_n_window(const elfm_frame *f)
{
  return f->recent_floor > 0 ? f->nnz_recent : f->nnz;
}
static inline int elfm_frame_in_window(const elfm_frame *f, float v)
{
  return !(f->recent_floor > 0 && v < f->recent_floor);
}

/* A zero frame of w x h; NULL (err filled) when out of memory.
 * Free with elfm_frame_free (NULL is a no-op). */
elfm_frame *elfm_frame_create(int w, int h, elfm_error *err);
void elfm_frame_free(elfm_frame *f);
/* Zero the listed pixels and empty the list (no deep window's floor either):
 * O(nnz). */
void elfm_frame_clear(elfm_frame *f);
/* Set pixel i (< w*h) to value, listing it if needed. O(nnz) per call when
 * the pixel was zero (it searches the list): for tests and small edits only. */
void elfm_frame_set(elfm_frame *f, uint32_t i, float value);
/* Clear dst (O(its nnz)) and give it src's times, index and event count:
 * the start of a filter's output frame (without a deep window's floor: a
 * filter mixes the pixels). */
void elfm_frame_clear_like(elfm_frame *dst, const elfm_frame *src);
/* Copy src into dst (same size): dst is cleared first. O(nnz). */
elfm_status elfm_frame_copy(elfm_frame *dst, const elfm_frame *src, elfm_error *err);
/* src binned factor x factor into dst, which must be ceil(w / factor) x
 * ceil(h / factor): each output pixel takes the value of largest magnitude
 * among the window's pixels of its block (elfm_frame_in_window; the older
 * pixels of a deep window are left out, and dst has no floor), with src's
 * times, index and counts. On a time surface that is the block's latest
 * event: a bead's image keeps its height, which a mean would lower by a
 * quarter or more at the paper's 2 px FWHM. O(src's nnz). ELFM_ERR_INVALID
 * for a factor below 1 or a dst of another size. */
elfm_status elfm_frame_bin(elfm_frame *dst, const elfm_frame *src, int factor, elfm_error *err);

/* A leak for INTEGRAL: 100 ms. Worm neurons (0.1-0.34 um/ms, images
 * ~8 um wide) cross their width in 25-80 ms. Measured on worm 200 ms at
 * 500 Hz, seeds 1-4 (`eventlfm track --repr integral`), mean alpha at a
 * leak of 50 / 100 / 200 ms: 0.683 / 0.719 / 0.721 (F1 0.889 / 0.890 /
 * 0.872). */
#define ELFM_INTEGRAL_TAU_US 100000.0
/* A level above 0 leaks this many times more slowly (tau_bright_us): worm
 * 200 ms seeds 1-4 / 5-7 / 8-12, 150 ms, 500 ms, mean alpha at 1 / 1.5 /
 * 2 / 3 x (threshold 20): 0.911 / 0.886 / 0.911 / 0.875 / 0.864, 0.904 /
 * 0.911 / 0.922 / 0.914 / 0.899, 0.923 / 0.898 / 0.924 / 0.915 / 0.895,
 * 0.918 / 0.898 / 0.904 / 0.889 / 0.895 (docs/recon.md "A brighter level
 * leaks more slowly"). */
#define ELFM_INTEGRAL_TAU_BRIGHT_FACTOR 2.0

/* The integral's floor, in steps: a lone ON event (1.5 with its half
 * step; sensor noise looks like this) and the +-1 step a passing object
 * leaves behind are below it, two ON events (2.5) above. Pixels below it
 * cost nothing per frame (recon/frames.c). Worm 200 ms seeds 1-4, means,
 * floor 1.5 / 2 / 2.5 / 3 (each with its best threshold, 20 / 15 / 5 / 5):
 * alpha 0.773 / 0.778 / 0.768 / 0.754, F1 0.912 / 0.905 / 0.907 / 0.904,
 * `track` wall time on seed 1 0.69-0.78 / 0.56-0.60 / 0.42 / 0.43-0.44 s
 * (the time surface's: 0.42-0.47 s). */
#define ELFM_INTEGRAL_FLOOR 2.0

typedef struct elfm_framer_options {
  int64_t dt_us;        /* window length; >= 50 us. Default 1000 (1 kHz volumes, the paper) */
  int64_t stride_us;    /* window start to next start; 0 = dt; 1..dt */
  elfm_frame_start start;
  int64_t start_us;     /* for ELFM_START_AT_TIME */
  int trigger_channel;  /* the trigger starts: only this channel's edges; -1 (default) any */
  elfm_repr repr;
  double tau_us;        /* time-surface decay; default 1000 (= dt, so the oldest event of
                           a window still shows at 255/e). INTEGRAL: the leak time
                           (ELFM_INTEGRAL_TAU_US is a good start) */
  elfm_polarity polarity;
  double off_weight;    /* INTEGRAL: an OFF event's step over an ON event's; default 1 */
  double tau_bright_us; /* INTEGRAL: the leak of a level above 0; default 0 = tau_us
                           (ELFM_INTEGRAL_TAU_BRIGHT_FACTOR x tau_us is a good start) */
  int64_t deep_window_us; /* EXP, not signed, > dt_us: each frame's surface holds the
                           pixels of the last deep_window_us before its end, not only
                           of its window; those whose latest event lies before the
                           window (older, so smaller) sit below frame.recent_floor.
                           The refocus, view support and occupancy leave them out; a
                           view fit reads them where elfm_localize_options.deep_z_um
                           asks (deep beads, which fire few events per window).
                           Times, windows and n_events stay the window's. 0 (default)
                           = off */
} elfm_framer_options;

void elfm_framer_options_default(elfm_framer_options *o);
/* Check ranges; ELFM_ERR_INVALID with a message naming the option. */
elfm_status elfm_framer_options_check(const elfm_framer_options *o, elfm_error *err);

typedef struct elfm_framer elfm_framer;

/* A framer for a width x height sensor. Free with elfm_framer_free. */
elfm_status elfm_framer_create(const elfm_framer_options *o, int width, int height,
                               elfm_framer **out, elfm_error *err);
void elfm_framer_free(elfm_framer *f);

/* Take a chunk's events (times must not decrease across pushes; pixels must
 * lie inside the sensor, else ELFM_ERR_RANGE). The chunk is not kept. */
elfm_status elfm_framer_push(elfm_framer *f, const elfm_event_chunk *c, elfm_error *err);

/* End of stream: from now on every window that begins at or before the
 * last pushed event counts as closed (the last one is partial). */
void elfm_framer_finish(elfm_framer *f);

/* Build the next closed window into `out` (cleared first; size must match
 * the sensor). Returns 1 if a frame was produced, 0 if no window is closed
 * yet. Windows without events give empty frames (a fixed volume rate). */
int elfm_framer_next(elfm_framer *f, elfm_frame *out);

/* Start of the first window, or INT64_MIN while still unknown. */
int64_t elfm_framer_origin_us(const elfm_framer *f);

/* ---- INTEGRAL: the start levels ----
 * The integral starts at 0 everywhere: a pixel's sum is its log brightness
 * relative to where it was at the first event. An object that is already
 * in view then shows only where it has moved on to, its leading part; the
 * part still over where it started cancels against its own start (worm
 * neurons, 0.1 um/ms: 1-2 um ahead along their motion for the first
 * 20 ms, docs/recon.md "The integral's start"). Those start levels can
 * be read back from the events themselves: when the object leaves a pixel,
 * the pixel's sum falls to minus what it was brighter than the background
 * at the start. elfm_levels accumulates, over the first events of a
 * recording, each pixel's sum (ON +1, OFF -off_weight, no leak) and its
 * lowest value; the start level is that depth plus half a step (what an
 * OFF event leaves on average), 0 where the sum never went below 0. Set
 * on a framer before its first event, the integral starts from them, and
 * each is held, not leaked, until that pixel's first event: the object is
 * there until it leaves. (Leaked from the start instead, a level is
 * smaller than the OFF steps that later undo it, and the dark residue hides
 * whatever arrives there next, such as the trailing neuron of a pair:
 * docs/recon.md.) From its first event on the pixel leaks as any other.
 * Memory: two floats per pixel. */
typedef struct elfm_levels {
  int w, h;
  float *sum;          /* running sum; after elfm_levels_result, the levels */
  float *min;          /* lowest sum so far (0 at the start) */
  int64_t t_first_us;  /* first event added, INT64_MIN before */
} elfm_levels;

/* The age to give the start levels (elfm_recon_options.integral_start_age_us):
 * 20 ms, i.e. they are scaled by exp(-20 ms / tau). An object moving
 * through the leaky integral shows, on average, what it added since it
 * arrived at each pixel, leaked over the half of its crossing time that has
 * passed (worm neurons: 4-6 um at ~0.12 um/ms, 20-25 ms); levels as fresh
 * as 0 ms make the first frames brighter than any later one, and their
 * ghosts rise above the detector's threshold. Worm 200 ms seeds 1-4, levels
 * from the first 200 ms (leaked, before they were held), age 0 / 20 / 35 ms:
 * alpha 0.878 / 0.869 / 0.853, F1 0.861 / 0.912 / 0.917; held at the final
 * defaults, 10 / 20 / 30 ms: docs/recon.md. */
#define ELFM_INTEGRAL_START_AGE_US 20000

elfm_status elfm_levels_create(int width, int height, elfm_levels *out, elfm_error *err);
void elfm_levels_free(elfm_levels *l);
/* Add c's events before t_end_us (pixels outside are skipped); returns how
 * many of c's events were before t_end_us (c->n when all). */
size_t elfm_levels_add(elfm_levels *l, const elfm_event_chunk *c, double off_weight, int64_t t_end_us);
/* Turn the sums into start levels (in l->sum), in ON steps. */
void elfm_levels_result(elfm_levels *l, double off_weight);
/* Start an INTEGRAL framer from level_steps (w x h, ON steps; <= 0: none),
 * each held until its pixel's first event. ELFM_ERR_INVALID for another
 * representation or once events were pushed. */
elfm_status elfm_framer_set_levels(elfm_framer *f, const float *level_steps, elfm_error *err);

/* ---- median filter ---- */
typedef struct elfm_median elfm_median;

/* A size x size (3 or 5) median for w x h frames, with zero padding outside
 * the sensor. Holds a ring of `size` rows of counters and a w*h list of the
 * frame's non-zero pixels in row order (no per-frame allocation). Free with
 * elfm_median_free. */
elfm_status elfm_median_create(int size, int w, int h, elfm_median **out, elfm_error *err);
void elfm_median_free(elfm_median *m);

/* out = median(in). in and out must differ and match the median's size.
 * Only pixels next to a listed pixel of `in` are computed (every other
 * median is 0), and a window with fewer than half its pixels non-zero
 * of each sign is 0 without sorting. Not thread-safe on the same `m`. */
void elfm_median_apply(elfm_median *m, const elfm_frame *in, elfm_frame *out);

/* ---- blur ---- */
typedef struct elfm_blur elfm_blur;

/* A binomial blur of radius 1 (3 x 3, [1 2 1] / 4 per axis) or 2 (5 x 5,
 * [1 4 6 4 1] / 16) for w x h frames, zero outside the sensor; its sum is
 * kept. Holds a w*h byte mask. Free with elfm_blur_free. Why: a dim
 * object's views get about one event each per frame, which rarely meet at
 * the voxel where its images do; spread over the image's size, they do
 * (recon/blur.c). */
elfm_status elfm_blur_create(int radius_px, int w, int h, elfm_blur **out, elfm_error *err);
void elfm_blur_free(elfm_blur *b);

/* out = blur(in): in and out must differ and match the blur's size.
 * O(listed pixels x (2r+1)^2). Not thread-safe on the same `b`. */
void elfm_blur_apply(elfm_blur *b, const elfm_frame *in, elfm_frame *out);

#ifdef __cplusplus
}
#endif
#endif
