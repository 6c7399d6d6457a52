/* viewer_run.c — the interactive loop: mouse orbit camera, keys, playback.
 *
 * GLFW callbacks find the viewer through the window's user pointer (no
 * global state). Controls:
 *   left-drag rotate, right-drag (or shift+left-drag) pan, scroll zoom,
 *   r reset camera, c cycle colour (time -> depth -> track), space play/pause,
 *   left/right arrows one frame (shift: 10 frames), home/end, +/- playback
 *   speed, t truth, d detections, m MIP plane, q or Esc quit.
 */
#include <math.h>
#include <stdio.h>

#include "gl_internal.h"

static elfm_viewer *viewer_of(GLFWwindow *w) { return glfwGetWindowUserPointer(w); }

static void cursor_clamp(elfm_viewer *v)
{
  const elfm_view_data *d = v->data;
  if (v->cursor_us < d->t_min_us) v->cursor_us = d->t_min_us;
  if (v->cursor_us > d->t_max_us) v->cursor_us = d->t_max_us;
}

static void on_key(GLFWwindow *w, int key, int scancode, int action, int mods)
{
  (void)scancode;
  elfm_viewer *v = viewer_of(w);
  if (action != GLFW_PRESS && action != GLFW_REPEAT) return;
  const elfm_view_data *d = v->data;
  int64_t step = d->frame_dt_us * ((mods & GLFW_MOD_SHIFT) ? 10 : 1);
  switch (key) {
  case GLFW_KEY_ESCAPE:
  case GLFW_KEY_Q: glfwSetWindowShouldClose(w, GLFW_TRUE); break;
  case GLFW_KEY_R: elfm_camera_reset(&v->cam, d->box_min_um, d->box_max_um); break;
  case GLFW_KEY_C: v->mode = (elfm_color_mode)(((int)v->mode + 1) % 3); break;
  case GLFW_KEY_T: v->opt.show_truth = !v->opt.show_truth; break;
  case GLFW_KEY_D: v->opt.show_detections = !v->opt.show_detections; break;
  case GLFW_KEY_M: v->opt.show_mip = !v->opt.show_mip; break;
  case GLFW_KEY_SPACE:
    /* Play from the start when the cursor sits at the end. */
    if (!v->playing && v->cursor_us >= d->t_max_us) v->cursor_us = d->t_min_us;
    v->playing = !v->playing;
    break;
  case GLFW_KEY_RIGHT:
    v->playing = 0;
    if (v->cursor_us >= d->t_max_us) break;
    v->cursor_us += step;
    cursor_clamp(v);
    break;
  case GLFW_KEY_LEFT:
    v->playing = 0;
    v->cursor_us -= step;
    cursor_clamp(v);
    break;
  case GLFW_KEY_HOME: v->cursor_us = d->t_min_us; break;
  case GLFW_KEY_END: v->cursor_us = d->t_max_us; v->playing = 0; break;
  case GLFW_KEY_EQUAL:
  case GLFW_KEY_KP_ADD: v->play_us_per_s *= 2.0; break;
  case GLFW_KEY_MINUS:
  case GLFW_KEY_KP_SUBTRACT: v->play_us_per_s *= 0.5; break;
  default: break;
  }
}

static void on_button(GLFWwindow *w, int button, int action, int mods)
{
  elfm_viewer *v = viewer_of(w);
  int down = action == GLFW_PRESS;
  if (button == GLFW_MOUSE_BUTTON_LEFT) {
    v->drag_rotate = down && !(mods & GLFW_MOD_SHIFT);
    v->drag_pan = down && (mods & GLFW_MOD_SHIFT);
  } else if (button == GLFW_MOUSE_BUTTON_RIGHT || button == GLFW_MOUSE_BUTTON_MIDDLE) {
    v->drag_pan = down;
  }
  glfwGetCursorPos(w, &v->mouse_x, &v->mouse_y);
}

static void on_motion(GLFWwindow *w, double x, double y)
{
  elfm_viewer *v = viewer_of(w);
  double dx = x - v->mouse_x, dy = y - v->mouse_y;
  v->mouse_x = x;
  v->mouse_y = y;
  if (v->drag_rotate) elfm_camera_rotate(&v->cam, dx, dy);
  if (v->drag_pan) {
    int ww, wh;
    glfwGetWindowSize(w, &ww, &wh);
    elfm_camera_pan(&v->cam, dx, dy, wh);
  }
}

static void on_scroll(GLFWwindow *w, double dx, double dy)
{
  (void)dx;
  elfm_camera_zoom(&viewer_of(w)->cam, dy);
}

elfm_status elfm_viewer_run(elfm_viewer *v, elfm_error *err)
{
  (void)err;
  GLFWwindow *w = v->win;
  glfwMakeContextCurrent(w);
  glfwSetWindowUserPointer(w, v);
  glfwSetKeyCallback(w, on_key);
  glfwSetMouseButtonCallback(w, on_button);
  glfwSetCursorPosCallback(w, on_motion);
  glfwSetScrollCallback(w, on_scroll);
  glfwSwapInterval(1); /* vsync: no faster than the screen */
  glfwShowWindow(w);
  if (v->cursor_us > v->data->t_max_us) v->cursor_us = v->data->t_max_us;
  double last = glfwGetTime();
  while (!glfwWindowShouldClose(w)) {
    double now = glfwGetTime();
    if (v->playing) {
      v->cursor_us += (int64_t)llround((now - last) * v->play_us_per_s);
      if (v->cursor_us >= v->data->t_max_us) {
        v->cursor_us = v->data->t_max_us;
        v->playing = 0;
      }
    }
    last = now;
    int fw, fh;
    glfwGetFramebufferSize(w, &fw, &fh);
    if (fw > 0 && fh > 0) {
      glBindFramebuffer(GL_FRAMEBUFFER, 0);
      gui_draw(v, fw, fh);
      glfwSwapBuffers(w);
    }
    if (v->playing) glfwPollEvents();
    else glfwWaitEventsTimeout(0.1); /* idle: no busy loop while paused */
  }
  glfwSetWindowUserPointer(w, NULL);
  return ELFM_OK;
}
