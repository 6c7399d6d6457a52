/* shaders.c — the viewer's GLSL 3.30 programs: compiled and linked once.
 *
 *  lines:   tracks, truth, detections and the box. Colour by time, depth,
 *           track, shared stretches (magenta over the track's colour at
 *           40 %; the flag is the segment's last vertex's, `flat`) or a
 *           flat colour (u_mode, GUI_MODE_FLAT = 9), per fragment;
 *           the time cursor is a uniform the fragment shader compares each
 *           fragment's interpolated time with, so scrubbing never touches
 *           the vertex buffers and a segment ends exactly at the cursor.
 *  overlay: 2D triangles in pixels (text, colour bar, scale bar).
 *  tex:     the MIP plane.
 * The turbo polynomial must equal colormap.c's (same constants, same
 * [0.10, 0.95] remap).
 */
#include <stdio.h>

#include "gl_internal.h"

static const char *lines_vs =
  "#version 330 core\n"
  "layout(location = 0) in vec3 a_pos;\n"
  "layout(location = 1) in float a_t;\n"
  "layout(location = 2) in float a_key;\n"
  "layout(location = 3) in float a_shared;\n"
  "uniform mat4 u_mvp;\n"
  "uniform int u_mode;\n"
  "uniform float u_t0, u_t1, u_z0, u_z1, u_point_size;\n"
  "out float v_t;\n"
  "out float v_s;\n"
  "flat out float v_shared;\n"
  "void main() {\n"
  "  gl_Position = u_mvp * vec4(a_pos, 1.0);\n"
  "  v_shared = a_shared;\n"
  "  gl_PointSize = u_point_size;\n"
  "  v_t = a_t;\n"
  "  float s = a_key;\n"
  "  if (u_mode == 0) s = (a_t - u_t0) / max(u_t1 - u_t0, 1e-6);\n"
  "  else if (u_mode == 1) s = (a_pos.z - u_z0) / max(u_z1 - u_z0, 1e-6);\n"
  "  v_s = s;\n"
  "}\n";

/* The colour map is evaluated per fragment from the interpolated time or
 * depth: a long chord of a coarse level of detail (series_lod.c) then still
 * runs through the map's colours instead of blending its two ends. */
static const char *lines_fs =
  "#version 330 core\n"
  "in float v_t;\n"
  "in float v_s;\n"
  "flat in float v_shared;\n"
  "uniform int u_mode;\n"
  "uniform vec4 u_color;\n"
  "uniform float u_cursor, u_trail;\n"
  "out vec4 o_color;\n"
  "vec3 turbo(float s) {\n"
  "  float x = 0.10 + 0.85 * clamp(s, 0.0, 1.0);\n"
  "  vec4 v4 = vec4(1.0, x, x * x, x * x * x);\n"
  "  vec2 v2 = v4.zw * v4.z;\n"
  "  return clamp(vec3(\n"
  "    dot(v4, vec4(0.13572138, 4.61539260, -42.66032258, 132.13108234)) +\n"
  "      dot(v2, vec2(-152.94239396, 59.28637943)),\n"
  "    dot(v4, vec4(0.09140261, 2.19418839, 4.84296658, -14.18503333)) +\n"
  "      dot(v2, vec2(4.27729857, 2.82956604)),\n"
  "    dot(v4, vec4(0.10667330, 12.64194608, -60.58204836, 110.36276771)) +\n"
  "      dot(v2, vec2(-89.90310912, 27.34824973))), 0.0, 1.0);\n"
  "}\n"
  "void main() {\n"
  "  if (v_t > u_cursor || (u_trail >= 0.0 && v_t < u_cursor - u_trail)) discard;\n"
  "  if (u_mode == " GUI_STR(GUI_MODE_FLAT) ") o_color = u_color;\n"
  "  else if (u_mode == 3) o_color = v_shared > 0.5 ? vec4(" GUI_STR(GUI_SHARED_RGB) ", u_color.a)\n"
  "                                                : vec4(" GUI_STR(GUI_SHARED_DIM) " * turbo(v_s), u_color.a);\n"
  "  else o_color = vec4(turbo(v_s), u_color.a);\n"
  "}\n";

static const char *overlay_vs =
  "#version 330 core\n"
  "layout(location = 0) in vec2 a_px;\n"
  "layout(location = 1) in vec4 a_color;\n"
  "uniform vec2 u_viewport;\n"
  "out vec4 v_color;\n"
  "void main() {\n"
  "  gl_Position = vec4(a_px.x / u_viewport.x * 2.0 - 1.0,\n"
  "                     1.0 - a_px.y / u_viewport.y * 2.0, 0.0, 1.0);\n"
  "  v_color = a_color;\n"
  "}\n";

static const char *overlay_fs =
  "#version 330 core\n"
  "in vec4 v_color;\n"
  "out vec4 o_color;\n"
  "void main() { o_color = v_color; }\n";

static const char *tex_vs =
  "#version 330 core\n"
  "layout(location = 0) in vec3 a_pos;\n"
  "layout(location = 1) in vec2 a_uv;\n"
  "uniform mat4 u_mvp;\n"
  "out vec2 v_uv;\n"
  "void main() { gl_Position = u_mvp * vec4(a_pos, 1.0); v_uv = a_uv; }\n";

static const char *tex_fs =
  "#version 330 core\n"
  "in vec2 v_uv;\n"
  "uniform sampler2D u_tex;\n"
  "uniform float u_alpha;\n"
  "out vec4 o_color;\n"
  "void main() {\n"
  "  vec3 c = texture(u_tex, v_uv).rgb;\n"
  /* Dark means empty in a MIP: let it fade out so the box and the tracks
   * behind stay visible (full opacity from a third of full brightness). */
  "  o_color = vec4(c, u_alpha * clamp(3.0 * max(c.r, max(c.g, c.b)), 0.0, 1.0));\n"
  "}\n";

static elfm_status shader_compile(GLenum type, const char *src, const char *name,
                                  GLuint *out, elfm_error *err)
{
  GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &src, NULL);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[400];
    glGetShaderInfoLog(s, sizeof log, NULL, log);
    glDeleteShader(s);
    return elfm_error_set(err, ELFM_ERR_DISPLAY, NULL, -1,
                          "OpenGL: %s shader does not compile: %s", name, log);
  }
  *out = s;
  return ELFM_OK;
}

static elfm_status program_link(const char *vs, const char *fs, const char *name,
                                GLuint *out, elfm_error *err)
{
  GLuint v = 0, f = 0;
  elfm_status st = shader_compile(GL_VERTEX_SHADER, vs, name, &v, err);
  if (st != ELFM_OK) return st;
  st = shader_compile(GL_FRAGMENT_SHADER, fs, name, &f, err);
  if (st != ELFM_OK) {
    glDeleteShader(v);
    return st;
  }
  GLuint p = glCreateProgram();
  glAttachShader(p, v);
  glAttachShader(p, f);
  glLinkProgram(p);
  glDeleteShader(v);
  glDeleteShader(f);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[400];
    glGetProgramInfoLog(p, sizeof log, NULL, log);
    glDeleteProgram(p);
    return elfm_error_set(err, ELFM_ERR_DISPLAY, NULL, -1,
                          "OpenGL: %s program does not link: %s", name, log);
  }
  *out = p;
  return ELFM_OK;
}

elfm_status gui_shaders_create(elfm_viewer *v, elfm_error *err)
{
  elfm_status st = program_link(lines_vs, lines_fs, "lines", &v->lines.prog, err);
  if (st == ELFM_OK) st = program_link(overlay_vs, overlay_fs, "overlay", &v->prog_overlay, err);
  if (st == ELFM_OK) st = program_link(tex_vs, tex_fs, "texture", &v->prog_tex, err);
  if (st != ELFM_OK) return st;
  gui_lines_prog *l = &v->lines;
  l->u_mvp = glGetUniformLocation(l->prog, "u_mvp");
  l->u_mode = glGetUniformLocation(l->prog, "u_mode");
  l->u_t0 = glGetUniformLocation(l->prog, "u_t0");
  l->u_t1 = glGetUniformLocation(l->prog, "u_t1");
  l->u_z0 = glGetUniformLocation(l->prog, "u_z0");
  l->u_z1 = glGetUniformLocation(l->prog, "u_z1");
  l->u_color = glGetUniformLocation(l->prog, "u_color");
  l->u_cursor = glGetUniformLocation(l->prog, "u_cursor");
  l->u_trail = glGetUniformLocation(l->prog, "u_trail");
  l->u_point_size = glGetUniformLocation(l->prog, "u_point_size");
  v->u_ov_viewport = glGetUniformLocation(v->prog_overlay, "u_viewport");
  v->u_tex_mvp = glGetUniformLocation(v->prog_tex, "u_mvp");
  v->u_tex_sampler = glGetUniformLocation(v->prog_tex, "u_tex");
  v->u_tex_alpha = glGetUniformLocation(v->prog_tex, "u_alpha");
  return ELFM_OK;
}

void gui_shaders_free(elfm_viewer *v)
{
  if (v->lines.prog) glDeleteProgram(v->lines.prog);
  if (v->prog_overlay) glDeleteProgram(v->prog_overlay);
  if (v->prog_tex) glDeleteProgram(v->prog_tex);
  v->lines.prog = v->prog_overlay = v->prog_tex = 0;
}
