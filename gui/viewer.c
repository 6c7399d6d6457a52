/* viewer.c — the viewer's life: GLFW window and OpenGL 3.3 core context,
 * buffers uploaded once, one frame drawn, read back, timed.
 *
 * Everything that depends on the data (vertices of 1,000 tracks x 1,000
 * points = 20 MB) is uploaded at creation; a frame only sets uniforms (the
 * camera matrix, the time cursor, the colour mode) and rebuilds the small
 * 2D overlay. That is what keeps a million-point scene smooth.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "gl_internal.h"

/* Background: dark grey, not black, so the dark-blue early end of the colour
 * map stays visible. */
static const float gui_bg[3] = {0.09f, 0.09f, 0.10f};

void elfm_viewer_options_default(elfm_viewer_options *o)
{
  memset(o, 0, sizeof *o);
  o->width = 1280;
  o->height = 800;
  o->visible = 1;
  o->color_mode = ELFM_COLOR_TIME;
  o->show_truth = o->show_detections = o->show_mip = 1;
  o->title = NULL;
}

static float t_ms_of(const elfm_viewer *v, int64_t t_us)
{
  return (float)((double)(t_us - v->data->t_min_us) / 1000.0);
}

/* Upload a series (all levels of detail, series_lod.c) into its buffer. */
static elfm_status series_upload(elfm_viewer *v, const elfm_view_series *s, gui_series_gl *g,
                                 elfm_error *err)
{
  glGenVertexArrays(1, &g->vao);
  glGenBuffers(1, &g->vbo);
  glBindVertexArray(g->vao);
  glBindBuffer(GL_ARRAY_BUFFER, g->vbo);
  float *buf = NULL;
  elfm_status st = gui_series_build(s, v->data->t_min_us, g, &buf, err);
  if (st != ELFM_OK) return st;
  glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(g->n_vertices * GUI_VERTEX_FLOATS * sizeof *buf),
               buf, GL_STATIC_DRAW);
  free(buf);
  return ELFM_OK;
}

/* Attribute layout shared by every vertex buffer of the lines program
 * (GUI_VERTEX_FLOATS; bound VAO+VBO). */
static void vertex_layout(void)
{
  GLsizei stride = GUI_VERTEX_FLOATS * sizeof(float);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride, (void *)0);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 1, GL_FLOAT, GL_FALSE, stride, (void *)(3 * sizeof(float)));
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 1, GL_FLOAT, GL_FALSE, stride, (void *)(4 * sizeof(float)));
  glEnableVertexAttribArray(3);
  glVertexAttribPointer(3, 1, GL_FLOAT, GL_FALSE, stride, (void *)(5 * sizeof(float)));
}

static elfm_status detections_upload(elfm_viewer *v, elfm_error *err)
{
  const elfm_view_data *d = v->data;
  glGenVertexArrays(1, &v->det_vao);
  glGenBuffers(1, &v->det_vbo);
  glBindVertexArray(v->det_vao);
  glBindBuffer(GL_ARRAY_BUFFER, v->det_vbo);
  vertex_layout();
  if (d->n_detections == 0) return ELFM_OK;
  if (d->n_detections > (size_t)INT32_MAX)
    return elfm_error_set(err, ELFM_ERR_RANGE, NULL, -1, "too many detections to draw");
  float *buf = malloc(d->n_detections * GUI_VERTEX_FLOATS * sizeof *buf);
  if (!buf) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory");
  for (size_t i = 0; i < d->n_detections; i++) {
    float *q = buf + i * GUI_VERTEX_FLOATS;
    memcpy(q, d->det_xyz_um + 3 * i, 3 * sizeof *q);
    q[3] = t_ms_of(v, d->det_t_us[i]);
    q[4] = q[5] = 0.0f;
  }
  glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(d->n_detections * GUI_VERTEX_FLOATS * sizeof *buf),
               buf, GL_STATIC_DRAW);
  free(buf);
  v->n_det = (GLsizei)d->n_detections;
  return ELFM_OK;
}

/* The box: its 12 edges. Ticks and their labels depend on the view (they
 * go on the outline edges), so overlay.c draws them each frame. */
static elfm_status box_upload(elfm_viewer *v, elfm_error *err)
{
  const double *lo = v->data->box_min_um, *hi = v->data->box_max_um;
  float buf[24 * GUI_VERTEX_FLOATS];
  int n = 0;
  for (int a = 0; a < 3; a++) { /* edges parallel to axis a */
    int b = (a + 1) % 3, c = (a + 2) % 3;
    for (int k = 0; k < 4; k++)
      for (int end = 0; end < 2; end++) {
        double p[3];
        p[a] = end ? hi[a] : lo[a];
        p[b] = (k & 1) ? hi[b] : lo[b];
        p[c] = (k & 2) ? hi[c] : lo[c];
        float *q = buf + n * GUI_VERTEX_FLOATS;
        q[0] = (float)p[0];
        q[1] = (float)p[1];
        q[2] = (float)p[2];
        q[3] = q[4] = q[5] = 0.0f;
        n++;
      }
  }
  v->n_box = n;
  glGenVertexArrays(1, &v->box_vao);
  glGenBuffers(1, &v->box_vbo);
  glBindVertexArray(v->box_vao);
  glBindBuffer(GL_ARRAY_BUFFER, v->box_vbo);
  glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(n * GUI_VERTEX_FLOATS * sizeof(float)), buf,
               GL_STATIC_DRAW);
  vertex_layout();
  (void)err;
  return ELFM_OK;
}

static elfm_status overlay_create(elfm_viewer *v, elfm_error *err)
{
  v->ov = malloc((size_t)GUI_OVERLAY_CAP * GUI_OVERLAY_FLOATS * sizeof *v->ov);
  if (!v->ov) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory");
  glGenVertexArrays(1, &v->ov_vao);
  glGenBuffers(1, &v->ov_vbo);
  glBindVertexArray(v->ov_vao);
  glBindBuffer(GL_ARRAY_BUFFER, v->ov_vbo);
  glBufferData(GL_ARRAY_BUFFER,
               (GLsizeiptr)((size_t)GUI_OVERLAY_CAP * GUI_OVERLAY_FLOATS * sizeof(float)), NULL,
               GL_DYNAMIC_DRAW);
  GLsizei stride = GUI_OVERLAY_FLOATS * sizeof(float);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, stride, (void *)0);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 4, GL_FLOAT, GL_FALSE, stride, (void *)(2 * sizeof(float)));
  return ELFM_OK;
}

/* The MIP plane: a quad over the box's x-y extent at its deepest-first z
 * (z_min), texture coordinates set when a picture is loaded. */
static void mip_create(elfm_viewer *v)
{
  glGenVertexArrays(1, &v->mip_vao);
  glGenBuffers(1, &v->mip_vbo);
  glGenTextures(1, &v->mip_tex);
  glBindVertexArray(v->mip_vao);
  glBindBuffer(GL_ARRAY_BUFFER, v->mip_vbo);
  glBufferData(GL_ARRAY_BUFFER, 6 * 5 * sizeof(float), NULL, GL_DYNAMIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 5 * sizeof(float), (void *)0);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 2, GL_FLOAT, GL_FALSE, 5 * sizeof(float), (void *)(3 * sizeof(float)));
  glBindTexture(GL_TEXTURE_2D, v->mip_tex);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  v->mip_loaded = -1;
}

elfm_status elfm_viewer_create(const elfm_viewer_options *opt, const elfm_view_data *data,
                               elfm_viewer **out, elfm_error *err)
{
  *out = NULL;
  if (!opt || !data || opt->width < 16 || opt->height < 16 || opt->width > 16384 ||
      opt->height > 16384)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "viewer size must be 16..16384 pixels per side");
  const char *desc = NULL;
  if (!glfwInit()) {
    glfwGetError(&desc);
    return elfm_error_set(err, ELFM_ERR_DISPLAY, NULL, -1,
                          "no display: cannot start GLFW (%s); set DISPLAY, or run under "
                          "xvfb-run for screenshots",
                          desc ? desc : "unknown reason");
  }
  glfwDefaultWindowHints();
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_VISIBLE, opt->visible ? GLFW_TRUE : GLFW_FALSE);
  glfwWindowHint(GLFW_SAMPLES, opt->visible ? 4 : 0);
  GLFWwindow *win = glfwCreateWindow(opt->width, opt->height,
                                     opt->title ? opt->title : "eventlfm view", NULL, NULL);
  if (!win) {
    glfwGetError(&desc);
    elfm_error_set(err, ELFM_ERR_DISPLAY, NULL, -1,
                   "no OpenGL 3.3 core profile on this display (%s)",
                   desc ? desc : "unknown reason");
    glfwTerminate();
    return ELFM_ERR_DISPLAY;
  }
  glfwMakeContextCurrent(win);
  elfm_viewer *v = calloc(1, sizeof *v);
  if (!v) {
    glfwDestroyWindow(win);
    glfwTerminate();
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory");
  }
  v->win = win;
  v->data = data;
  v->opt = *opt;
  v->mode = opt->color_mode;
  v->show_help = 1;
  v->cursor_us = INT64_MAX;
  /* Play the whole recording in 10 s of wall time by default. */
  double span = (double)(data->t_max_us - data->t_min_us);
  v->play_us_per_s = span > 0 ? span / 10.0 : 1000.0;
  v->play_default_us_per_s = v->play_us_per_s;
  elfm_camera_reset(&v->cam, data->box_min_um, data->box_max_um);

  elfm_status st = gui_shaders_create(v, err);
  if (st == ELFM_OK) st = series_upload(v, &data->tracks, &v->tracks, err);
  if (st == ELFM_OK) vertex_layout();
  if (st == ELFM_OK) st = series_upload(v, &data->truth, &v->truth, err);
  if (st == ELFM_OK) vertex_layout();
  if (st == ELFM_OK) st = detections_upload(v, err);
  if (st == ELFM_OK) st = box_upload(v, err);
  if (st == ELFM_OK) st = overlay_create(v, err);
  if (st == ELFM_OK) mip_create(v);
  glBindVertexArray(0);
  if (st == ELFM_OK && glGetError() != GL_NO_ERROR)
    st = elfm_error_set(err, ELFM_ERR_DISPLAY, NULL, -1,
                        "OpenGL refused the vertex buffers (out of video memory?)");
  if (st != ELFM_OK) {
    elfm_viewer_free(v);
    return st;
  }
  /* Core profiles only promise 1-pixel lines; Mesa and most drivers draw
   * wider ones (non-forward-compatible context). Two pixels read well. */
  GLfloat range[2] = {1, 1};
  glGetFloatv(GL_ALIASED_LINE_WIDTH_RANGE, range);
  v->line_width_px = range[1] >= 2.0f ? 2.0 : 1.0;
  glGetError(); /* the query may be unsupported: not an error for us */
  *out = v;
  return ELFM_OK;
}

static void series_gl_free(gui_series_gl *g)
{
  if (g->vbo) glDeleteBuffers(1, &g->vbo);
  if (g->vao) glDeleteVertexArrays(1, &g->vao);
  gui_series_arrays_free(g);
  memset(g, 0, sizeof *g);
}

void elfm_viewer_free(elfm_viewer *v)
{
  if (!v) return;
  glfwMakeContextCurrent(v->win);
  series_gl_free(&v->tracks);
  series_gl_free(&v->truth);
  GLuint bufs[4] = {v->det_vbo, v->box_vbo, v->ov_vbo, v->mip_vbo};
  GLuint vaos[4] = {v->det_vao, v->box_vao, v->ov_vao, v->mip_vao};
  glDeleteBuffers(4, bufs);
  glDeleteVertexArrays(4, vaos);
  if (v->mip_tex) glDeleteTextures(1, &v->mip_tex);
  if (v->fbo) glDeleteFramebuffers(1, &v->fbo);
  if (v->fbo_color) glDeleteRenderbuffers(1, &v->fbo_color);
  if (v->fbo_depth) glDeleteRenderbuffers(1, &v->fbo_depth);
  gui_shaders_free(v);
  free(v->ov);
  free(v->mip_rgba);
  glfwDestroyWindow(v->win);
  glfwTerminate();
  free(v);
}

elfm_camera *elfm_viewer_camera(elfm_viewer *v) { return &v->cam; }
void elfm_viewer_set_color_mode(elfm_viewer *v, elfm_color_mode mode) { v->mode = mode; }
void elfm_viewer_show(elfm_viewer *v, int truth, int detections, int mip)
{
  v->opt.show_truth = truth;
  v->opt.show_detections = detections;
  v->opt.show_mip = mip;
}
void elfm_viewer_set_cursor(elfm_viewer *v, int64_t t_us) { v->cursor_us = t_us; }
size_t elfm_viewer_drawn_vertices(const elfm_viewer *v) { return v->drawn_vertices; }

/* One line strip per polyline (glMultiDrawArrays). Drawing all of them with
 * one primitive-restart index list instead measured no faster on llvmpipe
 * and would lose the cut at the cursor (docs/viewer.md). */
static size_t draw_series(gui_series_gl *g, double px_per_um, float cursor_ms, int full_detail,
                          int shared_mode)
{
  if (!g->n_lines) return 0;
  size_t drawn = gui_series_prepare(g, px_per_um, cursor_ms, full_detail, shared_mode);
  glBindVertexArray(g->vao);
  glMultiDrawArrays(GL_LINE_STRIP, g->draw_first, g->draw_count, g->n_lines);
  return drawn;
}

void gui_draw(elfm_viewer *v, int width, int height)
{
  const elfm_view_data *d = v->data;
  glViewport(0, 0, width, height);
  glClearColor(gui_bg[0], gui_bg[1], gui_bg[2], 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glEnable(GL_PROGRAM_POINT_SIZE);
  float mvp[16];
  elfm_camera_matrix(&v->cam, (double)width / height, mvp);
  /* Cursor in the shaders' ms since t_min; "everything" is past the end. */
  float cursor_ms = v->cursor_us >= d->t_max_us ? 1e30f
                    : v->cursor_us <= d->t_min_us ? 0.0f : t_ms_of(v, v->cursor_us);
  double px_per_um = height / (2.0 * v->cam.half_height_um);
  /* Pixels grow with the picture so a 4K screenshot reads like a window. */
  double scale = height > 1100 ? 2.0 : 1.0;

  glDisable(GL_DEPTH_TEST);
  if (v->opt.show_mip && gui_mip_update(v)) {
    glUseProgram(v->prog_tex);
    glUniformMatrix4fv(v->u_tex_mvp, 1, GL_FALSE, mvp);
    glUniform1i(v->u_tex_sampler, 0);
    glUniform1f(v->u_tex_alpha, 0.9f);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, v->mip_tex);
    glBindVertexArray(v->mip_vao);
    glDrawArrays(GL_TRIANGLES, 0, 6);
  }
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);

  const gui_lines_prog *l = &v->lines;
  glUseProgram(l->prog);
  glUniformMatrix4fv(l->u_mvp, 1, GL_FALSE, mvp);
  glUniform1f(l->u_t0, 0.0f);
  glUniform1f(l->u_t1, t_ms_of(v, d->t_max_us));
  glUniform1f(l->u_z0, (float)d->box_min_um[2]);
  glUniform1f(l->u_z1, (float)d->box_max_um[2]);
  glUniform1f(l->u_point_size, (float)(3.0 * scale));
  glLineWidth((float)(v->line_width_px * (v->line_width_px > 1 ? scale : 1)));

  /* The box: flat, always whole. */
  glUniform1i(l->u_mode, GUI_MODE_FLAT);
  glUniform4f(l->u_color, 0.55f, 0.57f, 0.62f, 1.0f);
  glUniform1f(l->u_cursor, 1e30f);
  glUniform1f(l->u_trail, -1.0f);
  glBindVertexArray(v->box_vao);
  glDrawArrays(GL_LINES, 0, v->n_box);

  glUniform1f(l->u_cursor, cursor_ms);
  v->drawn_vertices = 0;
  if (v->opt.show_truth && v->truth.n_lines) {
    glUniform4f(l->u_color, 0.62f, 0.62f, 0.62f, 0.8f);
    v->drawn_vertices += draw_series(&v->truth, px_per_um, cursor_ms, v->opt.full_detail, 0);
  }
  glUniform1i(l->u_mode, (int)v->mode);
  glUniform4f(l->u_color, 1.0f, 1.0f, 1.0f, 1.0f);
  v->drawn_vertices += draw_series(&v->tracks, px_per_um, cursor_ms, v->opt.full_detail,
                                   v->mode == ELFM_COLOR_SHARED);

  if (v->opt.show_detections && v->n_det) {
    /* Raw detections of the last 10 frames before the cursor, as white dots
     * (all of them when the cursor is at the end). */
    glUniform1i(l->u_mode, GUI_MODE_FLAT);
    glUniform4f(l->u_color, 1.0f, 1.0f, 1.0f, 1.0f);
    glUniform1f(l->u_trail, cursor_ms >= 1e29f ? -1.0f : (float)(10.0 * d->frame_dt_us / 1000.0));
    glBindVertexArray(v->det_vao);
    glDrawArrays(GL_POINTS, 0, v->n_det);
  }

  glDisable(GL_DEPTH_TEST);
  gui_overlay_build(v, width, height);
  glUseProgram(v->prog_overlay);
  glUniform2f(v->u_ov_viewport, (float)width, (float)height);
  glBindVertexArray(v->ov_vao);
  glBindBuffer(GL_ARRAY_BUFFER, v->ov_vbo);
  glBufferSubData(GL_ARRAY_BUFFER, 0, (GLsizeiptr)(v->ov_n * GUI_OVERLAY_FLOATS * sizeof(float)),
                  v->ov);
  glDrawArrays(GL_TRIANGLES, 0, (GLsizei)v->ov_n);
  glBindVertexArray(0);
}

/* (Re)build the off-screen framebuffer when the size changes. */
static elfm_status fbo_ensure(elfm_viewer *v, int width, int height, elfm_error *err)
{
  if (v->fbo && v->fbo_w == width && v->fbo_h == height) {
    glBindFramebuffer(GL_FRAMEBUFFER, v->fbo);
    return ELFM_OK;
  }
  GLint max_rb = 0;
  glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_rb);
  if (width < 1 || height < 1 || width > max_rb || height > max_rb)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "picture size %dx%d outside 1..%d (this OpenGL's limit)", width,
                          height, (int)max_rb);
  if (!v->fbo) {
    glGenFramebuffers(1, &v->fbo);
    glGenRenderbuffers(1, &v->fbo_color);
    glGenRenderbuffers(1, &v->fbo_depth);
  }
  glBindRenderbuffer(GL_RENDERBUFFER, v->fbo_color);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
  glBindRenderbuffer(GL_RENDERBUFFER, v->fbo_depth);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, width, height);
  glBindFramebuffer(GL_FRAMEBUFFER, v->fbo);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, v->fbo_color);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, v->fbo_depth);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    v->fbo_w = v->fbo_h = 0;
    return elfm_error_set(err, ELFM_ERR_DISPLAY, NULL, -1,
                          "OpenGL: off-screen framebuffer %dx%d incomplete", width, height);
  }
  v->fbo_w = width;
  v->fbo_h = height;
  return ELFM_OK;
}

elfm_status elfm_viewer_render_rgb(elfm_viewer *v, int width, int height, uint8_t *rgb,
                                   elfm_error *err)
{
  glfwMakeContextCurrent(v->win);
  elfm_status st = fbo_ensure(v, width, height, err);
  if (st != ELFM_OK) return st;
  gui_draw(v, width, height);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, rgb);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (glGetError() != GL_NO_ERROR)
    return elfm_error_set(err, ELFM_ERR_DISPLAY, NULL, -1, "OpenGL: reading the picture failed");
  /* OpenGL's rows run bottom-up; pictures top-down: swap in place. */
  size_t row = (size_t)width * 3;
  for (int y = 0; y < height / 2; y++) {
    uint8_t *a = rgb + (size_t)y * row, *b = rgb + (size_t)(height - 1 - y) * row;
    for (size_t i = 0; i < row; i++) {
      uint8_t t = a[i];
      a[i] = b[i];
      b[i] = t;
    }
  }
  return ELFM_OK;
}

static double now_s(void)
{
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double cpu_s(void)
{
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

elfm_status elfm_viewer_bench(elfm_viewer *v, int n_frames, int width, int height, int sweep,
                              double *ms_mean, double *ms_max, double *cpu_ms_mean,
                              elfm_error *err)
{
  if (n_frames < 1)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "benchmark needs >= 1 frame");
  glfwMakeContextCurrent(v->win);
  elfm_status st = fbo_ensure(v, width, height, err);
  if (st != ELFM_OK) return st;
  const elfm_view_data *d = v->data;
  double total = 0, worst = 0;
  /* One untimed frame first: shader compilation in Mesa is lazy. */
  gui_draw(v, width, height);
  glFinish();
  double cpu0 = cpu_s();
  for (int i = 0; i < n_frames; i++) {
    /* The cursor sweeps the recording and the camera turns: what a user
     * playing back while orbiting sees. */
    if (sweep)
      v->cursor_us = d->t_min_us + (int64_t)((double)(d->t_max_us - d->t_min_us) *
                                             (i + 1) / n_frames);
    elfm_camera_rotate(&v->cam, 2.0, 0.0);
    double t0 = now_s();
    gui_draw(v, width, height);
    glFinish();
    double ms = 1000.0 * (now_s() - t0);
    total += ms;
    if (ms > worst) worst = ms;
  }
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  *cpu_ms_mean = 1000.0 * (cpu_s() - cpu0) / n_frames;
  *ms_mean = total / n_frames;
  *ms_max = worst;
  return ELFM_OK;
}
