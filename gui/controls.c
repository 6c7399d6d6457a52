/* controls.c — what the viewer's keys do, apart from GLFW's window: the
 * time cursor, playback, colour mode, layers, camera reset, and which key
 * gives which command (viewer_run.c's key handler applies it); tests call
 * them directly. */
#include <math.h>

#include "gl_internal.h"

static void cursor_step(elfm_viewer *v, int64_t frames)
{
  const elfm_view_data *d = v->data;
  v->playing = 0;
  int64_t c = v->cursor_us > d->t_max_us ? d->t_max_us : v->cursor_us;
  c += frames * d->frame_dt_us;
  if (c < d->t_min_us) c = d->t_min_us;
  if (c > d->t_max_us) c = d->t_max_us;
  v->cursor_us = c;
}

void elfm_viewer_command(elfm_viewer *v, elfm_viewer_cmd cmd)
{
  const elfm_view_data *d = v->data;
  switch (cmd) {
  case ELFM_CMD_RESET_VIEW: elfm_camera_reset(&v->cam, d->box_min_um, d->box_max_um); break;
  case ELFM_CMD_CYCLE_COLOR: v->mode = (elfm_color_mode)(((int)v->mode + 1) % 4); break;
  case ELFM_CMD_PLAY_PAUSE:
    if (!v->playing && v->cursor_us >= d->t_max_us) v->cursor_us = d->t_min_us;
    v->playing = !v->playing;
    break;
  case ELFM_CMD_STEP_FORWARD: cursor_step(v, 1); break;
  case ELFM_CMD_STEP_BACK: cursor_step(v, -1); break;
  case ELFM_CMD_STEP_FORWARD_10: cursor_step(v, 10); break;
  case ELFM_CMD_STEP_BACK_10: cursor_step(v, -10); break;
  case ELFM_CMD_HOME: v->cursor_us = d->t_min_us; break;
  case ELFM_CMD_END:
    v->cursor_us = d->t_max_us;
    v->playing = 0;
    break;
  /* Between 1/1024 and 1024 times the default speed. */
  case ELFM_CMD_FASTER:
    if (v->play_us_per_s < 1024 * v->play_default_us_per_s) v->play_us_per_s *= 2.0;
    break;
  case ELFM_CMD_SLOWER:
    if (v->play_us_per_s > v->play_default_us_per_s / 1024) v->play_us_per_s *= 0.5;
    break;
  case ELFM_CMD_TOGGLE_TRUTH: v->opt.show_truth = !v->opt.show_truth; break;
  case ELFM_CMD_TOGGLE_DETECTIONS: v->opt.show_detections = !v->opt.show_detections; break;
  case ELFM_CMD_TOGGLE_MIP: v->opt.show_mip = !v->opt.show_mip; break;
  case ELFM_CMD_TOGGLE_HELP: v->show_help = !v->show_help; break;
  }
}

int elfm_viewer_key_command(int glfw_key, int shift, elfm_viewer_cmd *cmd)
{
  switch (glfw_key) {
  case GLFW_KEY_R: *cmd = ELFM_CMD_RESET_VIEW; return 1;
  case GLFW_KEY_C: *cmd = ELFM_CMD_CYCLE_COLOR; return 1;
  case GLFW_KEY_T: *cmd = ELFM_CMD_TOGGLE_TRUTH; return 1;
  case GLFW_KEY_D: *cmd = ELFM_CMD_TOGGLE_DETECTIONS; return 1;
  case GLFW_KEY_M: *cmd = ELFM_CMD_TOGGLE_MIP; return 1;
  case GLFW_KEY_H: *cmd = ELFM_CMD_TOGGLE_HELP; return 1;
  case GLFW_KEY_SPACE: *cmd = ELFM_CMD_PLAY_PAUSE; return 1;
  case GLFW_KEY_RIGHT: *cmd = shift ? ELFM_CMD_STEP_FORWARD_10 : ELFM_CMD_STEP_FORWARD; return 1;
  case GLFW_KEY_LEFT: *cmd = shift ? ELFM_CMD_STEP_BACK_10 : ELFM_CMD_STEP_BACK; return 1;
  case GLFW_KEY_HOME: *cmd = ELFM_CMD_HOME; return 1;
  case GLFW_KEY_END: *cmd = ELFM_CMD_END; return 1;
  /* `+` is shift + `=` on most layouts; `=` alone does it too */
  case GLFW_KEY_EQUAL:
  case GLFW_KEY_KP_ADD: *cmd = ELFM_CMD_FASTER; return 1;
  case GLFW_KEY_MINUS:
  case GLFW_KEY_KP_SUBTRACT: *cmd = ELFM_CMD_SLOWER; return 1;
  default: return 0;
  }
}

elfm_viewer_drag elfm_viewer_drag_mode(int glfw_button, int shift)
{
  switch (glfw_button) {
  case GLFW_MOUSE_BUTTON_LEFT: return shift ? ELFM_DRAG_PAN : ELFM_DRAG_ROTATE;
  case GLFW_MOUSE_BUTTON_RIGHT:
  case GLFW_MOUSE_BUTTON_MIDDLE: return ELFM_DRAG_PAN;
  default: return ELFM_DRAG_NONE;
  }
}

void elfm_viewer_advance(elfm_viewer *v, double wall_s)
{
  if (!v->playing || !(wall_s > 0)) return;
  const elfm_view_data *d = v->data;
  v->cursor_us += (int64_t)llround(wall_s * v->play_us_per_s);
  if (v->cursor_us >= d->t_max_us) {
    v->cursor_us = d->t_max_us;
    v->playing = 0;
  }
}

int64_t elfm_viewer_cursor(const elfm_viewer *v) { return v->cursor_us; }
int elfm_viewer_playing(const elfm_viewer *v) { return v->playing; }
elfm_color_mode elfm_viewer_color_mode(const elfm_viewer *v) { return v->mode; }
