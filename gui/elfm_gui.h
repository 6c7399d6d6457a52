/* elfm_gui.h — the viewer of time-coded 3D tracks (issue 6): the gui
 * module's one public header.
 *
 * Three layers, each usable on its own:
 *   1. Data (no OpenGL): elfm_view_data_load() reads a run directory or one
 *      CSV file (tracks.csv, truth.csv, detections.csv) into polylines and
 *      points with their time and the box of the reconstructed volume;
 *      elfm_view_data_synthetic() makes test/benchmark data in memory.
 *   2. Maths (no OpenGL): the colour map, the orthographic orbit camera and
 *      its projection to pixels, the 5x7 bitmap font. Tests use these to
 *      know where a point must appear in a rendered picture.
 *   3. Viewer (OpenGL 3.3 core through GLFW): elfm_viewer_create() opens a
 *      window (visible, or hidden for screenshots/benchmarks), uploads every
 *      buffer once; elfm_viewer_render_rgb() renders one frame into an
 *      off-screen framebuffer and reads it back; elfm_viewer_run() is the
 *      interactive loop; elfm_viewer_bench() times frames.
 *
 * Errors: every call that can fail returns an elfm_status and fills the caller's
 * elfm_error; ELFM_ERR_DISPLAY when there is no display or no OpenGL 3.3.
 * Nothing here prints or exits.
 *
 * Threads: GLFW must be driven from the main thread, and each viewer
 * initialises and terminates GLFW (process-wide library state), so keep at
 * most one elfm_viewer at a time; viewers one after another are fine.
 */
#ifndef ELFM_GUI_H
#define ELFM_GUI_H

#include <stddef.h>
#include <stdint.h>

#include "elfm_error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- 1. data ------------------------------------------------------------ */

/* A set of polylines (tracks or truth objects): polyline k holds points
 * first[k] .. first[k+1]-1, sorted by time. Arrays are owned by the
 * elfm_view_data that holds the series. */
typedef struct elfm_view_series {
  size_t n_lines;
  size_t n_points;
  size_t *first;     /* n_lines + 1 offsets into the point arrays */
  int64_t *id;       /* n_lines: track_id / truth id */
  float *xyz_um;     /* 3 * n_points */
  int64_t *t_us;     /* n_points */
  /* n_points, or NULL when the file has no `claims` column (truth, older
   * runs): 1 where the point's detection lay in the gates of two or more
   * live tracks when it was linked (tracks.csv's claims >= 2), the
   * stretches where the linker could have given it to another track
   * (docs/tracker.md "Where identities are uncertain") */
  uint8_t *shared;
} elfm_view_series;

/* One saved MIP picture (PNG) or volume (OpenEXR, projected by the viewer)
 * and the time it stands for. */
typedef struct elfm_view_mip {
  char path[1024];
  int64_t t_us;
  int is_volume;     /* 1: an .exr volume, 0: a .png MIP */
} elfm_view_mip;

typedef struct elfm_view_data {
  elfm_view_series tracks;     /* smoothed track positions */
  elfm_view_series truth;      /* simulator truth (grey overlay), may be empty */
  size_t n_detections;
  float *det_xyz_um;           /* 3 * n_detections */
  int64_t *det_t_us;           /* n_detections */
  size_t n_mips;
  elfm_view_mip *mips;         /* sorted by t_us; MIP PNGs if any, else EXR volumes */
  int64_t t_min_us, t_max_us;  /* time span of everything loaded */
  int64_t frame_dt_us;         /* typical step between frames (arrow keys) */
  /* Box of the reconstructed volume in um: from calib.json (SPEC §3) when one
   * was found, else the data's extent with a 5 % margin. */
  double box_min_um[3], box_max_um[3];
  int box_from_calib;
  int volume_w_px, volume_h_px; /* calib.json's view_size_px (x-y panel of a MIP), 0 if none */
  /* Frame index -> time, from the frame and t_us columns of the CSVs:
   * t = frame0_t_us + (frame - frame0) * us_per_frame (when has_frame_clock). */
  int has_frame_clock;
  double frame0, frame0_t_us, us_per_frame;
  char calib_path[1024];       /* "" when none was found */
} elfm_view_data;

/* Load what `path` names:
 *   - a directory: its tracks.csv (or, without one, truth.csv as the main
 *     lines), detections.csv, MIP pictures (mips/ or mip/ *.png) or else
 *     volumes (volumes/ or exr/ *.exr), and calib.json from the directory,
 *     its parent, or the path its summary.json names ("calib"). A picture's or volume's time comes from its name:
 *     "t<digits>" or "t_us<digits>" is a time in us, otherwise its last
 *     number is a frame index (mapped to time through the frame and t_us
 *     columns of tracks.csv/detections.csv);
 *   - a .csv file: its kind is told by its header (track_id -> tracks,
 *     id + brightness -> truth, frame + intensity -> detections).
 * `truth_path` (may be NULL) adds a truth.csv as the grey overlay.
 * On success *out is owned by the caller (elfm_view_data_free); on failure
 * *out is NULL and err names the file and line. Empty files (no rows) are an
 * error: there would be nothing to show. */
elfm_status elfm_view_data_load(const char *path, const char *truth_path,
                                elfm_view_data **out, elfm_error *err);

/* Replace the MIPs with those of `dir`: a folder of *.png MIPs or *.exr
 * volumes, or a run directory with mips/ or volumes/ (eventlfm recon
 * --save-mips names them by frame number: mips/mip_000123.png). Frame
 * numbers become times through d's frame clock. On failure d is unchanged;
 * finding nothing usable is an error naming the directory. */
elfm_status elfm_view_data_load_mips(elfm_view_data *d, const char *dir, elfm_error *err);

/* Synthetic data: n_tracks helices of n_points each (one point per 1 ms
 * frame), inside a 130 x 130 x 200 um box: benchmark and test input.
 * Deterministic (fixed seed). Free with elfm_view_data_free. */
elfm_status elfm_view_data_synthetic(size_t n_tracks, size_t n_points,
                                     elfm_view_data **out, elfm_error *err);

/* Free everything; NULL is a no-op. */
void elfm_view_data_free(elfm_view_data *d);

/* ---- 2. maths ------------------------------------------------------------ */

/* Colour map used for time and depth: s in [0,1] (clamped) -> rgb in [0,1].
 * "Turbo" (Mikhailov 2019, polynomial fit): hue runs blue -> cyan -> green
 * -> yellow -> red as s grows, so early/shallow is blue and late/deep red.
 * The shaders evaluate the same polynomial. */
void elfm_colormap_rgb(double s, float rgb[3]);

/* Hue in degrees [0, 360) of an 8-bit colour (for tests and tools). */
double elfm_color_hue_deg(int r, int g, int b);

/* Orthographic orbit camera. The picture is centred on `target_um`;
 * `half_height_um` of object space fill half the picture's height (so
 * pixels per um = height_px / (2 half_height_um), exact everywhere: the scale
 * bar is true). yaw turns about the object's y axis, pitch about the
 * screen's horizontal axis. Plain value type. */
typedef struct elfm_camera {
  double yaw_rad, pitch_rad;
  double half_height_um;
  double target_um[3];
  double depth_um;         /* half extent of the depth range (clip planes) */
} elfm_camera;

/* The camera that shows the whole box from a slight angle (the `r` key). */
void elfm_camera_reset(elfm_camera *cam, const double box_min_um[3],
                       const double box_max_um[3]);

/* Column-major 4x4 matrix object (um) -> clip space for a picture of
 * aspect = width / height. */
void elfm_camera_matrix(const elfm_camera *cam, double aspect, float m[16]);

/* Pixel position (column, row from the top-left, pixel centres at +0.5) of
 * object point p in a width x height picture. */
void elfm_camera_project(const elfm_camera *cam, int width, int height,
                         const double p_um[3], double *col_px, double *row_px);

/* Drag/scroll helpers: rotate by pixel motion, zoom by scroll steps, pan by
 * pixel motion in a picture of the given height. */
void elfm_camera_rotate(elfm_camera *cam, double dx_px, double dy_px);
void elfm_camera_zoom(elfm_camera *cam, double steps);
void elfm_camera_pan(elfm_camera *cam, double dx_px, double dy_px, int height_px);

/* 5x7 bitmap font: the glyph of character c as 7 rows of 5 bits (bit 4 =
 * leftmost column). Characters outside the table give a filled box;
 * returns 1 if c is in the table. Covers digits, letters (upper case is
 * used for lower case), space and . , - + : = / ( ) % _ */
int elfm_font_glyph(char c, uint8_t rows[7]);

/* Where the colour bar is drawn in a width x height picture: columns
 * [x0, x1), rows [y0, y1) from the top-left; colour value 1 (latest, deepest)
 * at the top row, 0 at the bottom. */
void elfm_overlay_colorbar_rect(int width, int height, int *x0, int *y0, int *x1, int *y1);

/* "Nice" tick step (1, 2 or 5 x 10^k) giving about `n` ticks over span. */
double elfm_nice_step(double span, int n);

/* ---- 3. viewer ----------------------------------------------------------- */

typedef enum elfm_color_mode {
  ELFM_COLOR_TIME = 0,
  ELFM_COLOR_DEPTH = 1,
  ELFM_COLOR_TRACK = 2,
  /* each track's colour dimmed, and magenta where its detections were
   * shared (elfm_view_series.shared) */
  ELFM_COLOR_SHARED = 3
} elfm_color_mode;

typedef struct elfm_viewer_options {
  int width, height;         /* window / picture size in pixels */
  int visible;               /* 0: hidden window (screenshots, benchmarks) */
  elfm_color_mode color_mode;
  int show_truth, show_detections, show_mip;
  int full_detail;           /* 1: draw every point (no level of detail) */
  const char *title;         /* window title; NULL -> "eventlfm view" */
} elfm_viewer_options;

/* Defaults: 1280 x 800, visible, colour by time, everything shown. */
void elfm_viewer_options_default(elfm_viewer_options *o);

typedef struct elfm_viewer elfm_viewer;

/* Open GLFW, a window and an OpenGL 3.3 core context; compile the shaders and
 * upload every buffer of `data` once. `data` must outlive the viewer (MIP
 * paths are read from it as the cursor moves). ELFM_ERR_DISPLAY (with the
 * GLFW message) when there is no display or no OpenGL 3.3 core.
 * Free with elfm_viewer_free (which closes GLFW). */
elfm_status elfm_viewer_create(const elfm_viewer_options *opt, const elfm_view_data *data,
                               elfm_viewer **out, elfm_error *err);
void elfm_viewer_free(elfm_viewer *v);

/* The camera in use (read/write): tests project points with it. */
elfm_camera *elfm_viewer_camera(elfm_viewer *v);
void elfm_viewer_set_color_mode(elfm_viewer *v, elfm_color_mode mode);
/* Which layers are drawn (each 0 or 1); the `t`, `d`, `m` keys toggle them. */
void elfm_viewer_show(elfm_viewer *v, int truth, int detections, int mip);
/* Tracks are drawn up to the time cursor t_us (INT64_MAX: everything). */
void elfm_viewer_set_cursor(elfm_viewer *v, int64_t t_us);

/* What the keys do (viewer_run.c maps keys to these; docs/viewer.md). */
typedef enum elfm_viewer_cmd {
  ELFM_CMD_RESET_VIEW,      /* r */
  ELFM_CMD_CYCLE_COLOR,     /* c: time -> depth -> track -> shared -> time */
  ELFM_CMD_PLAY_PAUSE,      /* space; from the end, playback starts over */
  ELFM_CMD_STEP_FORWARD,    /* right arrow: one frame (pauses) */
  ELFM_CMD_STEP_BACK,       /* left arrow */
  ELFM_CMD_STEP_FORWARD_10, /* shift + right arrow */
  ELFM_CMD_STEP_BACK_10,    /* shift + left arrow */
  ELFM_CMD_HOME,            /* Home: cursor to the start */
  ELFM_CMD_END,             /* End: cursor to the end (everything shown) */
  ELFM_CMD_FASTER,          /* +: playback speed x 2 */
  ELFM_CMD_SLOWER,          /* -: playback speed / 2 */
  ELFM_CMD_TOGGLE_TRUTH,    /* t */
  ELFM_CMD_TOGGLE_DETECTIONS, /* d */
  ELFM_CMD_TOGGLE_MIP,      /* m */
  ELFM_CMD_TOGGLE_HELP      /* h: the key help lines in the window */
} elfm_viewer_cmd;

void elfm_viewer_command(elfm_viewer *v, elfm_viewer_cmd cmd);
/* The command a key gives (GLFW's key code and whether shift is held), as
 * the window's key handler applies it: 1 and *cmd set, or 0 for a key that
 * gives none (q and Esc, which close the window, give none either). The
 * table in docs/viewer.md lists the same keys. */
int elfm_viewer_key_command(int glfw_key, int shift, elfm_viewer_cmd *cmd);
/* What a mouse button pressed starts (GLFW's button and whether shift is
 * held), as the window's button handler applies it until a button is let
 * go: left rotates, shift+left, right and middle pan (docs/viewer.md). */
typedef enum { ELFM_DRAG_NONE, ELFM_DRAG_ROTATE, ELFM_DRAG_PAN } elfm_viewer_drag;
elfm_viewer_drag elfm_viewer_drag_mode(int glfw_button, int shift);
/* Playback: when playing, move the cursor by wall_s seconds of wall time at
 * the playback speed (by default the whole recording in 10 s); stops at the
 * end. */
void elfm_viewer_advance(elfm_viewer *v, double wall_s);
int64_t elfm_viewer_cursor(const elfm_viewer *v);
/* Track and truth vertices sent to OpenGL in the last frame drawn (after
 * the level of detail and the cursor cut). */
size_t elfm_viewer_drawn_vertices(const elfm_viewer *v);
int elfm_viewer_playing(const elfm_viewer *v);
elfm_color_mode elfm_viewer_color_mode(const elfm_viewer *v);

/* Render one frame at width x height into an off-screen framebuffer and read
 * it back as top-down rows of RGB bytes into rgb (3 * width * height bytes,
 * caller-owned). */
elfm_status elfm_viewer_render_rgb(elfm_viewer *v, int width, int height, uint8_t *rgb,
                                   elfm_error *err);

/* Interactive loop until the window closes (Esc, q). */
elfm_status elfm_viewer_run(elfm_viewer *v, elfm_error *err);

/* Render n_frames at width x height off-screen while the camera turns,
 * waiting for each frame to finish (glFinish); *ms_mean and *ms_max receive
 * the frame times. sweep = 1: the cursor plays through the recording (what
 * playback costs); 0: the cursor stays where it is (INT64_MAX: everything
 * drawn, the worst case). *cpu_ms_mean: CPU time of the whole process
 * (all renderer threads) per frame: with a software renderer on a busy
 * machine, a steadier figure than the wall time. */
elfm_status elfm_viewer_bench(elfm_viewer *v, int n_frames, int width, int height, int sweep,
                              double *ms_mean, double *ms_max, double *cpu_ms_mean,
                              elfm_error *err);

/* Write top-down RGB rows as an 8-bit PNG (libpng). */
elfm_status elfm_png_write_rgb(const char *path, int width, int height, const uint8_t *rgb,
                               elfm_error *err);

/* Read a PNG (any colour type, 8/16-bit) as top-down RGBA bytes. *rgba is
 * malloc'ed, the caller frees it with free(). */
elfm_status elfm_png_read_rgba(const char *path, int *width, int *height, uint8_t **rgba,
                               elfm_error *err);

#ifdef __cplusplus
}
#endif
#endif
