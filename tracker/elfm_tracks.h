/* elfm_tracks.h — the track type, the track store, and the track writers
 * (tracks.csv, detections.csv, ISBI 2012 XML, TrackMate XML; SPEC §5).
 *
 * A track holds its REAL points (detections the linker attached), in
 * increasing frame order; frames between them are gaps (filled only in the
 * smoothed output). After smoothing (elfm_track_smooth, elfm_smooth.h) it
 * also holds one smoothed state per frame of its span first..last, with
 * raw_index[k] the real point at that frame or -1 for a gap-filled frame.
 *
 * The store (elfm_track_store) owns finished tracks, for callers that want
 * them all in memory (tests, small runs). A long run does not keep them: it
 * writes each track as it ends (tracks.csv, elfm_track_xml), a long one in
 * pieces as it goes (elfm_link_take_piece), and keeps its elfm_track_info
 * (104 bytes) whatever its length.
 */
#ifndef ELFM_TRACKS_H
#define ELFM_TRACKS_H

#include <stdint.h>
#include <stdio.h>

#include "elfm_recon.h"
#include "elfm_peaks.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- Frame times ----
 * The time (t_us) of every frame of a run, for the frames of a track's span
 * that have no real point (gaps), whose times the smoother and tracks.csv
 * need. Evenly spaced frames need nothing: a gap's times lie on the line
 * between its ends. Windows opened by trigger edges (`--start
 * each-trigger`) are not evenly spaced, so the run records each frame's
 * time here as it goes. Stored as runs of evenly spaced frames (first
 * frame, its time, the step): one run for a fixed frame rate, two or three
 * per trigger edge otherwise, so memory grows with the edges, not the
 * frames (16 bytes x 3 per light pulse), and a run forgets the frames
 * no track still needs (elfm_frame_times_forget_before). */
typedef struct elfm_frame_times {
  size_t n, cap;
  int64_t *frame, *t_us, *step_us; /* per run; step 0 while the run has one frame */
  int64_t last_frame;               /* latest frame added, -1 none */
} elfm_frame_times;

void elfm_frame_times_init(elfm_frame_times *ft);
void elfm_frame_times_free(elfm_frame_times *ft);
/* dst = a copy of src (dst initialised, its old runs freed); NOMEM. */
elfm_status elfm_frame_times_copy(elfm_frame_times *dst, const elfm_frame_times *src,
                                  elfm_error *err);
/* Record frame's time; frames must be added in increasing order, each after
 * the previous one (ELFM_ERR_INVALID otherwise), times increasing. */
elfm_status elfm_frame_times_add(elfm_frame_times *ft, int64_t frame, int64_t t_us,
                                 elfm_error *err);
/* The time of a recorded frame (one between two recorded frames that was
 * skipped lies on its run's line); 0 with *t_us untouched for a frame
 * before the first or after the last. */
int elfm_frame_times_get(const elfm_frame_times *ft, int64_t frame, int64_t *t_us);
/* Forget the frames before `frame` (the run holding it stays): a run asks
 * only for the frames of tracks still to be smoothed, so what it holds
 * stays bounded on a recording of many trigger edges. Frames before it
 * are then unknown (elfm_frame_times_get returns 0). */
void elfm_frame_times_forget_before(elfm_frame_times *ft, int64_t frame);

/* Motion models the smoother chooses from (elfm_smooth.h). */
typedef enum elfm_motion_model {
  ELFM_MODEL_AUTO = 0,       /* choose per track by BIC */
  ELFM_MODEL_CONST_VELOCITY,
  ELFM_MODEL_CONST_ACCEL,
  ELFM_MODEL_SPLINE,         /* smoothing spline, weight chosen by GCV */
  ELFM_MODEL_STATIC          /* one point, or all points at one time: position only */
} elfm_motion_model;

const char *elfm_motion_model_name(elfm_motion_model m);

typedef struct elfm_track {
  int64_t id;
  size_t n, cap;
  elfm_detection *pts;        /* real points, strictly increasing frame */
  /* Smoothed, one entry per frame of the span (n_span = last - first + 1);
   * all NULL / 0 until smoothed. pos, vel and the sd arrays are n_span x 3 (x, y, z). */
  size_t n_span;
  int64_t *span_t_us;
  double *pos_um, *vel_um_per_ms, *pos_sd_um, *vel_sd_um_per_ms;
  int32_t *raw_index;
  elfm_motion_model model;    /* the model the smoother chose */
  double spline_weight_ms3;   /* chosen spline weight (SPLINE only) */
  double spline_omega_rad_per_ms; /* the turn rate its prior left alone (SPLINE with
                                     elfm_smooth_options.spline_turn), else 0 */
  double edf;                 /* effective parameters per axis */
  int n_outliers;             /* points beyond twice the loss scale (elfm_smooth.h) */
  int ceres;                  /* 1: Ceres polished the fit kept (elfm_smooth_info.ceres) */
  /* A piece of a long track (elfm_link_take_piece): partial = 1, and only
   * the frames in [write_from_frame, write_to_frame) are its own, written
   * to tracks.csv, ISBI and TrackMate; its points outside them are the
   * smoother's context, written with the pieces before and after it. The
   * end of a track that gave pieces is one too (write_to_frame INT64_MAX).
   * piece: how many pieces of the track came before. */
  int partial, piece;
  int64_t write_from_frame, write_to_frame;
} elfm_track;

/* Whether a frame is t's to write (always, unless t is a piece). */
static inline int elfm_track_writes_frame(const elfm_track *t, int64_t frame)
{
  return !t->partial || (frame >= t->write_from_frame && frame < t->write_to_frame);
}

/* Whether t's smoothed velocity was measured: its span holds more than one
 * frame. A track of one frame (under the LED's windows, a bead seen in one
 * pulse) is fitted STATIC, velocity 0; that 0 is the model's, and averaged
 * with the others it pulls a stage's mean velocity toward rest
 * (blink_moving seed 1: 8 such tracks of 49, 1.6 % of the speed). So
 * tracks.csv leaves its velocity empty and elfm_track_info_get reports it
 * NAN. Pieces of long tracks always span more. */
static inline int elfm_track_velocity_known(const elfm_track *t)
{
  return t->n_span > 1;
}

/* A new empty track; free with elfm_track_free (NULL is a no-op). */
elfm_track *elfm_track_create(int64_t id, elfm_error *err);
void elfm_track_free(elfm_track *t);
/* Append a real point; its frame must exceed the last one's. */
elfm_status elfm_track_append(elfm_track *t, const elfm_detection *d, elfm_error *err);
/* Insert a real point at its frame, which must not have one yet (a gap's
 * frame, or one before the first / after the last). O(n). */
elfm_status elfm_track_insert(elfm_track *t, const elfm_detection *d, elfm_error *err);
/* Mean smoothed velocity over the span (um/ms); zeros when not smoothed. */
void elfm_track_mean_velocity(const elfm_track *t, double v_um_per_ms[3]);

/* What a run reports of a finished track once the track itself is freed:
 * summary.json's entry and the stage analysis (elfm_analysis_stage_info). */
typedef struct elfm_track_info {
  int64_t id, first_frame, last_frame; /* frames of the first and last real point */
  size_t n;                   /* real points */
  size_t n_rows;              /* frames first_frame .. last_frame written (smoothed) */
  int n_pieces;               /* 1, or the pieces of a long track merged (elfm_track_info_merge) */
  elfm_motion_model model;    /* of a long track: its largest piece's (model_n points), */
  double spline_weight_ms3, spline_omega_rad_per_ms, edf; /* as are these */
  size_t model_n;
  int n_outliers;
  int smoothed;               /* 0: not smoothed; the velocities below are 0 / NAN */
  double mean_vel_um_per_ms[3];        /* elfm_track_mean_velocity; NAN when the track
                                          spans one frame (elfm_track_velocity_known) */
  double mean_lateral_speed_um_per_ms; /* mean over the span of |(vx, vy)|; NAN when
                                          not smoothed, not finite or not known */
  /* Over the same rows, for the velocity's slope in time (the stage's
   * acceleration, elfm_analysis_stage_info): their mean time, the sum of
   * (t - mean_t)^2 in ms^2 and of (t - mean_t)(v - mean_vel) in um; 0 when
   * not smoothed. Pieces fold together exactly (elfm_track_info_merge). */
  double mean_t_us, s_tt_ms2, s_tv_um[3];
  /* The real points' scatter about the smoothed path, per axis: their
   * number and the sums of (raw - smoothed) and of its square (um, um^2);
   * 0 when not smoothed. How well the track's points place it, axis by
   * axis, for the stage's pooled velocity (elfm_analysis_stage_info).
   * Pieces add up. */
  size_t n_res;
  double s_res_um[3], s_res2_um2[3];
} elfm_track_info;

/* t's info (of a piece: of its own frames only). */
void elfm_track_info_get(const elfm_track *t, elfm_track_info *out);
/* Fold the info of a later piece of the same track into *acc: counts and
 * frames add up, the mean velocities are weighted by rows, the model,
 * spline weight and edf are those of the piece with more points. */
void elfm_track_info_merge(elfm_track_info *acc, const elfm_track_info *piece);

/* The store: takes ownership of finished tracks. */
typedef struct elfm_track_store {
  size_t n, cap;
  elfm_track **tracks;
} elfm_track_store;

void elfm_track_store_init(elfm_track_store *s);
/* Take ownership of t (also on failure: t is freed then). */
elfm_status elfm_track_store_add(elfm_track_store *s, elfm_track *t, elfm_error *err);
/* Free every track and the array; the store is empty afterwards. */
void elfm_track_store_clear(elfm_track_store *s);

/* ---- writers. Each takes an open FILE (the caller opens/closes it) and a
 * `path` used in error messages; write errors are ELFM_ERR_IO. ---- */

/* detections.csv: header then rows
 * frame,t_us,x_um,y_um,z_um,intensity,sigma_x_um,sigma_y_um,sigma_z_um,
 * width_um,fit_sd_px,view_fit,weak,nearest_um,claims,raw_x_um,raw_y_um,
 * raw_z_um (width, scatter and nearest empty when not measured: 0 in the
 * struct). bias_um (3 per detection, NULL: none) is each one's motion bias
 * (elfm_motion_bias): x/y/z_um are d's position minus it, where the object
 * was at t_us, and raw_x/y/z_um d's position as measured. */
elfm_status elfm_detections_write_header(FILE *f, const char *path, elfm_error *err);
elfm_status elfm_detections_write(FILE *f, const char *path, const elfm_detection *d,
                                  const double *bias_um, int n,
                                  elfm_error *err);

/* tracks.csv: header then, per smoothed track, one row per frame of its
 * span: track_id,frame,t_us,x_um,y_um,z_um (smoothed), raw_x_um,raw_y_um,
 * raw_z_um (empty on gap frames), vx_um_per_ms,vy_um_per_ms,vz_um_per_ms,
 * intensity (empty on gap frames), sd_x_um,sd_y_um,sd_z_um,
 * sd_vx_um_per_ms,sd_vy_um_per_ms,sd_vz_um_per_ms (empty where undetermined:
 * the velocity of a one-point track, and every uncertainty of a track too
 * short to tell its own noise, under 5 points: elfm_smooth_noise_known),
 * nearest_um (the real point's
 * elfm_detection.nearest_um; empty on gap frames and where not measured).
 * All fields numeric or empty, so
 * elfm_table reads it back; the chosen model goes to summary.json.
 * A track that is not smoothed is an ELFM_ERR_INVALID. */
elfm_status elfm_tracks_write_csv_header(FILE *f, const char *path, elfm_error *err);
elfm_status elfm_tracks_write_csv(FILE *f, const char *path, const elfm_track *t, elfm_error *err);

/* ISBI 2012 particle-tracking challenge XML: one <particle> per track, one
 * <detection t= x= y= z=/> per REAL point (the evaluator fills gaps), at the
 * smoothed positions; t is the frame index, x/y/z in um (snr, density and
 * scenario are the header attributes the challenge files carry). */
elfm_status elfm_tracks_write_isbi(FILE *f, const char *path, const elfm_track_store *s,
                                   elfm_error *err);

/* TrackMate XML (the TmXmlReader layout: Model/AllSpots/SpotsInFrame/Spot,
 * AllTracks/Track/Edge, FilteredTracks), positions in um, frame interval
 * in ms, one spot per real point at its smoothed position. */
elfm_status elfm_tracks_write_trackmate(FILE *f, const char *path, const elfm_track_store *s,
                                        double frame_interval_ms, elfm_error *err);

/* Both XML files from tracks given one at a time as they end, and from the
 * pieces of long tracks (elfm_link_take_piece), in bounded memory. Both
 * list a track's points together and TrackMate lists every spot by frame
 * before the tracks, while the points come track by track, a long track's
 * in pieces: so each real point (of a piece: of its own frames) waits in a
 * scratch file, created at scratch_path and unlinked as soon as it is open
 * (nothing is left behind), and each writer sorts them, by track or by
 * frame, in passes over it that hold at most ~max_sort_spots points each
 * (0: 262144, 16 MB; at least one block of 1024 frames or 64 tracks).
 * In memory: 32 bytes per track and 24 per piece. A later piece joins
 * the earlier ones of its track (same id): one ISBI particle, one
 * TrackMate track whose edges run on from piece to piece. Tracks are
 * listed in the order they first came; for whole tracks the files are byte
 * for byte elfm_tracks_write_isbi's and elfm_tracks_write_trackmate's. A
 * track with no point of its own is not listed. */
typedef struct elfm_track_xml elfm_track_xml;

/* NULL (err filled) on no memory or a scratch file that cannot be made. */
elfm_track_xml *elfm_track_xml_create(const char *scratch_path, size_t max_sort_spots,
                                      elfm_error *err);
elfm_status elfm_track_xml_add(elfm_track_xml *w, const elfm_track *t, elfm_error *err);
/* Write the whole file to f (path: for messages); each may be called once
 * or more, after the last add. */
elfm_status elfm_track_xml_write_isbi(elfm_track_xml *w, FILE *f, const char *path,
                                      elfm_error *err);
elfm_status elfm_track_xml_write_trackmate(elfm_track_xml *w, FILE *f, const char *path,
                                           double frame_interval_ms, elfm_error *err);
/* Close the scratch file (removing it if it still has a name); NULL is a no-op. */
void elfm_track_xml_free(elfm_track_xml *w);

#ifdef __cplusplus
}
#endif
#endif
