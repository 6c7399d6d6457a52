/* gl_internal.h — private to gui/: the viewer's state and the OpenGL
 * entry points. Not installed, not included outside gui/.
 *
 * OpenGL 3.3 core functions are called directly (GL_GLEXT_PROTOTYPES): the
 * Linux libGL exports every core entry point, so there is no loader and no
 * table of function pointers to keep in global state.
 */
#ifndef ELFM_GUI_GL_INTERNAL_H
#define ELFM_GUI_GL_INTERNAL_H

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include "elfm_gui.h"

/* Vertex of tracks, truth, detections and the box: 6 floats. t is in ms
 * since the data's t_min_us: a float's step is ~1 us up to 16 s and 0.25 ms
 * at one hour, finer than a 1 ms frame for recordings up to ~2 h. key in
 * [0,1] picks a track's colour. shared (0 or 1) marks the segment that ends
 * at this vertex (ELFM_COLOR_SHARED; series_lod.c). */
#define GUI_VERTEX_FLOATS 6
/* u_mode of the lines program beside the public colour modes: one flat
 * colour (u_color) for the box, truth and detections */
#define GUI_MODE_FLAT 9
/* ELFM_COLOR_SHARED's colours, in the lines shader and the colour bar
 * alike: shared stretches magenta, the rest of a track at 40 % of its
 * colour. GUI_STR puts them (and GUI_MODE_FLAT) into the GLSL text. */
#define GUI_SHARED_RGB 1.0, 0.2, 1.0
#define GUI_SHARED_DIM 0.4
#define GUI_STR_(...) #__VA_ARGS__
#define GUI_STR(...) GUI_STR_(__VA_ARGS__)
/* Overlay vertex: x, y in pixels from the top-left, then r, g, b, a. */
#define GUI_OVERLAY_FLOATS 6
/* Overlay capacity in vertices, allocated once: ~150 label characters of
 * up to 35 dots x 6 vertices, plus bars: 64 k vertices is 1.5 MB. */
#define GUI_OVERLAY_CAP 65536

typedef struct gui_lines_prog {
  GLuint prog;
  GLint u_mvp, u_mode, u_t0, u_t1, u_z0, u_z1, u_color, u_cursor, u_trail, u_point_size;
} gui_lines_prog;

/* Levels of detail: level l keeps every 2^l-th point of a polyline (and
 * its last). 8 levels reach 1 point in 128, enough for 1 kHz tracks seen
 * whole; together they hold < 2x the points. */
#define GUI_LOD_LEVELS 8
/* A level is used while it strays from the full polyline by at most this
 * much on screen (in space and, along the chords, in time). Half a pixel
 * is well inside the 2-pixel line width: test_gui_render measures < 3 % of
 * the lit pixels changing against full detail. */
#define GUI_LOD_MAX_ERR_PX 0.5

/* A series on the GPU: every level of every polyline in one buffer,
 * uploaded once. Per frame only the draw lists (first/count per polyline)
 * are refilled on the CPU: level by zoom, count cut at the time cursor. */
typedef struct gui_series_gl {
  GLuint vao, vbo;
  GLsizei n_lines;
  size_t n_vertices;                    /* over all levels */
  GLint *lvl_first[GUI_LOD_LEVELS];     /* [level][line] first vertex */
  GLsizei *lvl_count[GUI_LOD_LEVELS];   /* [level][line] vertex count */
  float *t_ms;                          /* n_vertices: each vertex's time (cursor cut) */
  float *lvl_err_um[GUI_LOD_LEVELS];    /* [level][line] largest deviation from level 0 */
  uint8_t *lvl_mixed[GUI_LOD_LEVELS];   /* [level][line] 1: a chord stands for shared and
                                           unshared points (not drawn in shared mode) */
  GLint *draw_first;                    /* per line, refilled each frame */
  GLsizei *draw_count;
} gui_series_gl;

struct elfm_viewer {
  GLFWwindow *win;
  const elfm_view_data *data;
  elfm_viewer_options opt;
  elfm_camera cam;
  elfm_color_mode mode;
  int64_t cursor_us;        /* tracks shown up to here */
  int playing;
  double play_us_per_s;     /* playback speed: recording us per wall second */
  double play_default_us_per_s;
  double line_width_px;
  size_t drawn_vertices;    /* in the last frame (elfm_viewer_drawn_vertices) */

  gui_lines_prog lines;
  GLuint prog_overlay;
  GLint u_ov_viewport;
  GLuint prog_tex;
  GLint u_tex_mvp, u_tex_sampler, u_tex_alpha;

  gui_series_gl tracks, truth;
  GLuint det_vao, det_vbo;
  GLsizei n_det;
  GLuint box_vao, box_vbo;
  GLsizei n_box;

  GLuint ov_vao, ov_vbo;
  float *ov;                /* GUI_OVERLAY_CAP * GUI_OVERLAY_FLOATS */
  size_t ov_n;

  GLuint mip_vao, mip_vbo, mip_tex;
  long mip_loaded;          /* index into data->mips, -1 none */
  int mip_ok;               /* the loaded picture is on the texture */
  uint8_t *mip_rgba;        /* reused decode buffer */
  size_t mip_cap;

  GLuint fbo, fbo_color, fbo_depth;
  int fbo_w, fbo_h;

  /* interactive state */
  double mouse_x, mouse_y;
  int drag_rotate, drag_pan;
  int show_help;            /* key help lines in the window (h) */
  char status_line[128];    /* shown bottom-left in the window, e.g. errors */
};

/* shaders.c */
elfm_status gui_shaders_create(elfm_viewer *v, elfm_error *err);
void gui_shaders_free(elfm_viewer *v);

/* overlay.c: rebuild the 2D overlay (labels, colour bar, scale bar, HUD)
 * for a width x height picture into v->ov; no allocation. */
void gui_overlay_build(elfm_viewer *v, int width, int height);

/* mip_plane.c: make the texture show the MIP of the cursor's frame (reads a
 * PNG only when the frame changes); 1 if a MIP is ready to draw. */
int gui_mip_update(elfm_viewer *v);

/* png_io.c: decode into a reusable buffer (grown only when too small). */
elfm_status gui_png_read_into(const char *path, uint8_t **buf, size_t *cap, int *width,
                              int *height, elfm_error *err);

/* series_lod.c: build all levels of a series into a vertex array of
 * GUI_VERTEX_FLOATS (malloc'ed, the caller uploads then frees it) and g's
 * index arrays; free g's arrays; refill g's draw lists for a zoom, a cursor
 * and whether shared stretches are shown (ELFM_COLOR_SHARED). */
elfm_status gui_series_build(const elfm_view_series *s, int64_t t0_us, gui_series_gl *g,
                             float **vertices, elfm_error *err);
void gui_series_arrays_free(gui_series_gl *g);
/* ... and returns the number of vertices the draw lists hold. */
size_t gui_series_prepare(gui_series_gl *g, double px_per_um, float cursor_ms, int full_detail,
                          int shared_mode);

/* viewer.c: draw one frame into the bound framebuffer. */
void gui_draw(elfm_viewer *v, int width, int height);

#endif
