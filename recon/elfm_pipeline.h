/* elfm_pipeline.h — the streaming driver (events -> frames -> median ->
 * refocused volumes) shared by `eventlfm recon`, `track` and the benchmark,
 * the same for conventional light-field TIFF stacks, and the volume writers
 * (OpenEXR volumes, depth-coded MIP PNGs).
 *
 *   elfm_recon_options o;
 *   elfm_recon_options_default(&o);            then change what you need
 *   elfm_recon_run(events_path, &calib, &o, on_volume, user, &stats, &err);
 *
 * The driver reads fixed-size chunks and builds frames sequentially,
 * refocuses several frames at once (OpenMP threads; each slot of a ring
 * owns a frame, a volume and a refocus workspace) and calls `on_volume` IN
 * FRAME ORDER, one call at a time, while the other threads go on reading
 * and refocusing the next frames. The calls may come on any of the run's
 * threads, but never two at once, and each sees what the previous one left:
 * a callback needs no locks. Memory is fixed by the options (chunk size,
 * slots, volume size), independent of the recording's length.
 */
#ifndef ELFM_PIPELINE_H
#define ELFM_PIPELINE_H

#include <stdint.h>

#include "elfm_calib.h"
#include "elfm_error.h"
#include "elfm_events.h"
#include "elfm_frames.h"
#include "elfm_refocus.h"
#include "elfm_volume.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct elfm_recon_stats {
  int64_t events;          /* events taken in (inside from/to, before the polarity filter) */
  int64_t triggers;        /* external trigger edges inside from/to (e.g. an LED driver's) */
  int64_t frames;          /* volumes delivered to the callback */
  int64_t frames_sparse, frames_dense; /* refocus path taken (neither with no_refocus) */
  int64_t t_first_us, t_last_us; /* first/last event time taken (INT64_MIN/MAX if none) */
  double span_s;           /* recording span processed: windows' end - first window start */
  double wall_s;           /* the whole run */
  double read_s, frame_s;  /* reading/decoding, building frames (one thread at a time) */
  double refocus_s;        /* median + refocus + the worker hook, summed over the threads */
  double callback_s;       /* time spent in the callback (one thread at a time) */
  double events_per_s, volumes_per_s;
  double realtime_factor;  /* span_s / wall_s: > 1 is faster than real time */
  double done_frac;        /* how far through the input, 0..1: by event time up to
                            * to_us when one is given, else by the file's bytes;
                            * -1 unknown (a pipe). Set in progress calls and at the end */
  int input_error;         /* 1: the run stopped at an error of its input (a truncated or
                            * corrupt file) after delivering every volume built before it;
                            * what was delivered is good, so a caller may finish its own
                            * outputs before reporting the error */
} elfm_recon_stats;

/* Called now and then (about every 0.25 s of wall time) with the stats so
 * far, right after a callback and on its thread (so it may read what the
 * callback keeps); may be NULL. */
typedef void (*elfm_recon_progress_fn)(const elfm_recon_stats *s, void *user);

/* Optional per-volume work done on the worker thread right after the
 * volume is refocused (e.g. peak detection), so that it runs in parallel
 * with other frames'. `slot` (0 .. slots-1, see elfm_recon_layout) names
 * the ring slot the volume lives in (a slot takes a new frame only after
 * its volume was delivered); `thread` (0 .. threads-1) the worker, so
 * the hook can use a per-thread workspace and store its output per slot.
 * The same slot is passed to on_volume_slot for this volume afterwards, in
 * frame order. Must not touch state shared with other slots or threads. A
 * non-OK return stops the run like a callback error. `frame` is the frame
 * the volume was refocused from (after the median filter) and `plan` the
 * run's refocus plan, for per-view tests such as elfm_refocus_view_support. */
typedef elfm_status (*elfm_volume_worker_fn)(const elfm_volume *vol, const elfm_frame *frame,
                                             const elfm_refocus_plan *plan, int slot, int thread,
                                             void *user, elfm_error *err);
/* The ordered callback with the volume's ring slot (see above). */
typedef elfm_status (*elfm_volume_slot_fn)(const elfm_volume *vol, int slot, void *user,
                                           elfm_error *err);

typedef struct elfm_recon_options {
  elfm_framer_options framer;   /* dt, stride, representation, tau, polarity, start */
  int median;                   /* 0 (off), 3 (the paper's) or 5 */
  int blur_px;                  /* 0 (off), 1 or 2: binomial blur after the median
                                   (elfm_blur; for dim objects) */
  elfm_refocus_options refocus; /* path (auto/dense/sparse), ghost suppression */
  int threads;                  /* 0: OpenMP's default */
  int batch;                    /* slots: frames in flight (read, refocused or being
                                   delivered); 0: 2 x threads */
  int64_t from_us, to_us;       /* event time range [from, to); INT64_MIN / INT64_MAX: all.
                                   With from_us set and start FIRST_EVENT, windows start at from_us. */
  size_t chunk_events;          /* events per read; default 65536 */
  elfm_reader_options reader;   /* geometry for DAT files without one */
  int64_t tiff_frame_us;        /* TIFF stacks: time between pages; 0 = dt_us */
  /* INTEGRAL only: read the first integral_start_us of events once more
   * before the run and start the integral from the levels they give
   * (elfm_levels in elfm_frames.h), scaled by exp(-integral_start_age_us
   * / tau) and held until each pixel's first event; 0 = start from 0
   * (default). */
  int64_t integral_start_us;
  int64_t integral_start_age_us;
  elfm_recon_progress_fn progress;
  void *progress_user;
  /* Optional (NULL: off). With on_volume_slot set it is called in frame
   * order instead of the on_volume argument, with the `user` argument. */
  elfm_volume_worker_fn worker;
  void *worker_user;
  elfm_volume_slot_fn on_volume_slot;
  /* Optional work a callback leaves for the run's other threads (NULL:
   * none), such as `eventlfm track` smoothing the tracks that ended. After
   * each delivery, a thread with no delivery or read to do calls
   * side_work(side_user, thread) before it refocuses, until a call returns
   * 0 (nothing waiting). It runs beside the callback, other side_work calls
   * and refocusing: it takes its work under its own lock, and the callback
   * collects the results. What is left when the run ends is the caller's
   * to finish. */
  int (*side_work)(void *side_user, int thread);
  void *side_user;
  /* 1: frames only, no refocus (for work that reads the frames alone, such
   * as elfm_refocus_sample at a few points: `eventlfm traces`). The worker
   * and the callbacks still get a volume, with the frame's times and the
   * plan's geometry set and its voxels left as they are. */
  int no_refocus;
  /* A plan the caller made with elfm_refocus_plan_create from this run's
   * calibration and `refocus` options, to use instead of making one
   * (NULL: the run makes its own). Borrowed: the caller frees it after the
   * run. A caller that refocuses beside the run (a tracker's view fits)
   * then makes the plan once: at the paper's geometry each plan takes
   * ~16 ms to make. A plan whose sensor, views or planes differ from the
   * calibration's is refused (ELFM_ERR_INVALID). */
  const elfm_refocus_plan *plan;
  /* 0 or 1: volumes at the calibration's sampling. 2 (to 4): volumes
   * refocused from each frame binned bin_px x bin_px (elfm_frame_bin, after
   * the median and the blur) with the binned calibration's plan
   * (elfm_calib_bin): bin_px times coarser across, for about 1 / bin_px^2
   * of the refocus's work. The worker still gets the full frame and `plan`,
   * so its view fits place objects at the full sampling
   * (`eventlfm track --bin 2`, docs/tracker.md "Peaks found in a binned
   * volume"). */
  int bin_px;
  /* With bin_px > 1: a plan the caller made from the binned calibration
   * (borrowed and checked as `plan` is); NULL: the run makes its own. */
  const elfm_refocus_plan *volume_plan;
} elfm_recon_options;

/* The worker threads and ring slots elfm_recon_run will use with `o`
 * (for sizing per-thread workspaces and per-slot outputs of a worker hook).
 * ELFM_ERR_INVALID for out-of-range threads / batch. */
elfm_status elfm_recon_layout(const elfm_recon_options *o, int *threads, int *slots,
                              elfm_error *err);

/* Defaults: dt 1000 us exponential time surface tau 1000 us, both
 * polarities, 3x3 median, auto path, ghost suppression by view agreement
 * 0.3 and no threshold (docs/recon.md has the measured comparison), all
 * threads. */
void elfm_recon_options_default(elfm_recon_options *o);

/* Receives each volume in frame order (vol->frame counts windows from 0,
 * vol->t_us per SPEC §5). The volume is only valid during the call. A non-OK
 * return stops the run; elfm_recon_run then returns that status with the
 * callback's err. */
typedef elfm_status (*elfm_volume_fn)(const elfm_volume *vol, void *user, elfm_error *err);

/* Refocus the events of `events_path` with `calib`. `stats` may be NULL.
 * Errors: the reader's (file + byte offset / line), geometry mismatch
 * between file and calibration (ELFM_ERR_INVALID), options (ELFM_ERR_INVALID).
 * A reader's error ends the recording where it is: the events decoded
 * before it are framed as a file ending there would be (its last window
 * too), every volume is delivered, then the error is returned
 * (stats->input_error 1); an error past to_us is not one. */
elfm_status elfm_recon_run(const char *events_path, const elfm_calib *calib,
                           const elfm_recon_options *opt, elfm_volume_fn on_volume, void *user,
                           elfm_recon_stats *stats, elfm_error *err);

/* The same for a conventional light-field recording: a multi-page 8/16-bit
 * (or float) grey TIFF stack of sensor frames, one volume per page (no median
 * unless asked for, dense path; page n has t_us = n x tiff_frame_us). */
elfm_status elfm_recon_run_tiff(const char *tiff_path, const elfm_calib *calib,
                                const elfm_recon_options *opt, elfm_volume_fn on_volume,
                                void *user, elfm_recon_stats *stats, elfm_error *err);

/* ---- TIFF stacks (lf_tiff.c, libtiff) ---- */
typedef struct elfm_tiff_stack elfm_tiff_stack;
/* Open a stack; every page must be single-channel 8/16-bit unsigned or
 * 32-bit float of the first page's size. Free with elfm_tiff_close. */
elfm_status elfm_tiff_open(const char *path, elfm_tiff_stack **out, elfm_error *err);
int elfm_tiff_width(const elfm_tiff_stack *s);
int elfm_tiff_height(const elfm_tiff_stack *s);
/* Read the next page into `out` (same size; cleared first, non-zero pixels
 * listed); *got = 0 after the last page. Errors name the file and page. */
elfm_status elfm_tiff_read(elfm_tiff_stack *s, elfm_frame *out, int *got, elfm_error *err);
void elfm_tiff_close(elfm_tiff_stack *s);
/* Write frames as a 16-bit stack (values rounded, clamped to 0..65535):
 * for tests and for exporting event frames to other tools. */
typedef struct elfm_tiff_writer elfm_tiff_writer;
elfm_status elfm_tiff_writer_open(const char *path, elfm_tiff_writer **out, elfm_error *err);
elfm_status elfm_tiff_writer_add(elfm_tiff_writer *w, const elfm_frame *f, elfm_error *err);
elfm_status elfm_tiff_writer_close(elfm_tiff_writer *w, elfm_error *err);

/* ---- volume outputs ---- */
/* OpenEXR (volume_exr.c): one scanline file per volume, W x H, one FLOAT
 * channel per z plane named "z000", "z001", ... (zero-padded so that EXR's
 * alphabetical channel order is the plane order), ZIP compressed; header
 * attributes t_us (double, exact below 2^53 us), frame (int), um_per_px,
 * z_min_um, z_step_um (double), nz (int). */
elfm_status elfm_volume_write_exr(const elfm_volume *v, const char *path, elfm_error *err);
/* Read such a file back; *out is allocated (elfm_volume_free). */
elfm_status elfm_volume_read_exr(const char *path, elfm_volume **out, elfm_error *err);

/* Depth-colour-coded maximum intensity projection (mip_png.c), 8-bit RGB:
 * the x-y MIP at top left, the x-z MIP below it (z downwards) and the y-z
 * MIP to its right (z rightwards), each z plane `z_px` pixels thick
 * (0 = 1; at most 64).
 * Hue = depth of the maximum (blue at z_min through red at z_max),
 * brightness = maximum / `scale` (scale <= 0: the volume's maximum). */
elfm_status elfm_volume_write_mip_png(const elfm_volume *v, const char *path, double scale,
                                      int z_px, elfm_error *err);

#ifdef __cplusplus
}
#endif
#endif
