/* viewer_run.c — the interactive loop: mouse orbit camera, keys, playback.
 *
 * GLFW callbacks find the viewer through the window's user pointer (no
 * global state); keys become elfm_viewer_command()s, chosen by
 * elfm_viewer_key_command (controls.c, where tests read the table). Controls:
 *   left-drag rotate, right-drag (or shift+left-drag) pan, scroll zoom,
 *   r reset camera, c cycle colour (time -> depth -> track -> shared), space play/pause,
 *   left/right arrows one frame (shift: 10 frames), home/end, +/- playback
 *   speed, t truth, d detections, m MIP plane, h key help, q or Esc quit.
 */
#include <stdio.h>

#include "gl_internal.h"

static elfm_viewer *viewer_of(GLFWwindow *w) { return glfwGetWindowUserPointer(w); }

static void on_key(GLFWwindow *w, int key, int scancode, int action, int mods)
{
  (void)scancode;
  if (action != GLFW_PRESS && action != GLFW_REPEAT) return;
  if (key == GLFW_KEY_ESCAPE || key == GLFW_KEY_Q) {
    glfwSetWindowShouldClose(w, GLFW_TRUE);
    return;
  }
  elfm_viewer_cmd cmd;
  if (elfm_viewer_key_command(key, (mods & GLFW_MOD_SHIFT) != 0, &cmd))
    elfm_viewer_command(viewer_of(w), cmd);
}

static void on_button(GLFWwindow *w, int button, int action, int mods)
{
  elfm_viewer *v = viewer_of(w);
  /* a press starts what elfm_viewer_drag_mode says (controls.c, where
   * tests read it); letting any button go ends the drag */
  const elfm_viewer_drag mode =
      action == GLFW_PRESS ? elfm_viewer_drag_mode(button, (mods & GLFW_MOD_SHIFT) != 0) : ELFM_DRAG_NONE;
  v->drag_rotate = mode == ELFM_DRAG_ROTATE;
  v->drag_pan = mode == ELFM_DRAG_PAN;
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
    elfm_viewer_advance(v, now - last);
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
