/* cmd_calib_refine.h — what `calib refine` (cmd_calib_refine.c) shares
 * with its sweep's step (cmd_calib_sweep.c): the options, the passes'
 * context, and the calls both use. Internal to the command line. */
#ifndef CMD_CALIB_REFINE_H
#define CMD_CALIB_REFINE_H

#include "cli.h"
#include "elfm_tracker.h"

typedef struct refine_opts {
  const char *calib, *events, *out;
  elfm_recon_options recon;
  double ms;          /* how much of the recording each pass reads */
  int passes;
  double threshold;   /* peaks above this value only (bright points fit best) */
  int min_views;      /* views that must agree with a point's fit (0: 12, scaled below 25 views) */
  int min_points;     /* misses a view needs to move */
  int search_px;      /* the coarse step's reach (0: none) */
  double turn_deg;    /* the lens array's turn is searched within +-turn_deg (0: none) */
  int quiet;
  double planes_um[3]; /* --z-*-um for the passes' volumes (NaN: the calibration's) */
  /* none of --repr, --tau-us, --polarity, --blur-px given: too few peaks on
   * the time surface, and the integral (recon_integral, its defaults) is
   * tried (choose_repr) */
  int repr_auto;
  elfm_recon_options recon_integral;
  int threshold_given; /* --threshold given: the integral keeps it too */
  int sweep;           /* --sweep: one object swept through z, its views found frame by frame */
  double sweep_speed;  /* --sweep-um-per-ms: its known axial speed (0: not known) */
  int keep_focus;      /* --keep-focal-plane: the sweep's focus not made z = 0 */
  int keep_scale;      /* --keep-scale: nor the relay's magnification taken from its grid */
  int istart_given;    /* --integral-start-ms given (a one-way sweep read both ways keeps it) */
  int median_given;    /* --median given (else a sweep taken for several objects is read again
                          through the 3 x 3 median: sensor noise) */
  int ms_given;
} refine_opts;

/* Per batch slot: the points of the slot's volume, misses and weights. */
typedef struct refine_slot {
  int n;
  double *miss, *wt; /* [max_pts][2 nv], [max_pts][nv] */
  double *at;        /* [max_pts][2 nv]: where the point projects in each view, px */
  double (*pos)[3];  /* the coarse step: the points, um */
  const elfm_frame *frame; /* and their frame (the driver's, valid until the callback) */
  double score;            /* the turn's search: the volume's sharpness */
  int64_t t_us;            /* the sweep's step: the frame's time */
  elfm_calib_sweep_image *img; /* ... and its spots */
  int n_scored;            /* and the peaks it sums */
} refine_slot;

typedef struct refine_ctx {
  const refine_opts *o;
  int nv, max_pts;
  elfm_localize_options lo;
  elfm_peaks **pk;     /* [threads] */
  int threads;
  elfm_detection *det; /* [threads][max_pts] */
  refine_slot *slot;   /* [slots] */
  elfm_calib_refine *acc;
  const elfm_calib *cal; /* the centres of this pass */
  int voting;            /* this pass is the coarse step */
  elfm_calib_sweep *sweep; /* this pass is the sweep's step (--sweep) */
  int scoring;           /* this pass scores a turn of the lens array */
  int64_t count_stop;    /* ... and stops once this many peaks are scored (0: never) */
  int count_stopped;     /* the pass was stopped so */
  double score;          /* its sum over the volumes, in frame order */
  int64_t n_scored;      /* the peaks summed */
  int64_t volumes;
  const char *events;    /* the file the passes read: o->events, or the sweep read backwards */
} refine_ctx;

/* One pass: refocus, fit, collect (into c->acc), over c->events. */
elfm_status refine_run_pass(refine_ctx *c, const elfm_calib *cal, elfm_recon_options ro, elfm_error *err);
/* The peak detectors (one per thread) for peaks above thr */
elfm_status refine_set_threshold(refine_ctx *c, const elfm_calib *cal, double thr, elfm_error *err);
/* The integral's threshold: --threshold if given, else its own */
double refine_integral_threshold(const refine_opts *o);
/* A pass's moves (2 per view) into the running totals; their RMS and
 * largest, px, for the progress line. */
void refine_add_moves(int nv, const double *shift, double *total, double *rms, double *worst);
/* --sweep's step in place of the turn's search and the coarse step
 * (cmd_calib_sweep.c): CLI_OK, or a CLI_ code with its message said. */
int refine_sweep_step(refine_ctx *c, elfm_calib *cal, refine_opts *o, double *total, elfm_error *err);

#endif
