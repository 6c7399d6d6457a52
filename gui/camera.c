/* camera.c — the orthographic orbit camera: matrices and pixel projection.
 *
 * Orthographic rather than perspective because this is a measuring tool: a
 * micrometre is the same number of pixels at every depth, so the scale bar
 * and the box ticks are true everywhere in the picture.
 *
 * View = Rx(pitch) * Ry(yaw) * T(-target): yaw turns about the object's y
 * axis, pitch then tilts about the screen's horizontal axis. Object +y is
 * the sensor row direction (SPEC §1), which grows downwards in camera
 * images, so the view flips y to keep the reset view looking like the
 * camera picture (x right, y down).
 */
#include <math.h>
#include <string.h>

#include "elfm_gui.h"

/* Rotation and translation part: p_view = R (p - target), with the y flip. */
static void camera_view_rows(const elfm_camera *cam, double r[3][3])
{
  double cy = cos(cam->yaw_rad), sy = sin(cam->yaw_rad);
  double cp = cos(cam->pitch_rad), sp = sin(cam->pitch_rad);
  /* Ry(yaw) then Rx(pitch), then flip y and z (rotation by pi about x) so
   * object +y points down the screen and +z towards the viewer's back. */
  double ry[3][3] = {{cy, 0, sy}, {0, 1, 0}, {-sy, 0, cy}};
  double rx[3][3] = {{1, 0, 0}, {0, cp, -sp}, {0, sp, cp}};
  double m[3][3];
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      m[i][j] = 0;
      for (int k = 0; k < 3; k++) m[i][j] += rx[i][k] * ry[k][j];
    }
  for (int j = 0; j < 3; j++) {
    r[0][j] = m[0][j];
    r[1][j] = -m[1][j];
    r[2][j] = -m[2][j];
  }
}

void elfm_camera_reset(elfm_camera *cam, const double box_min_um[3],
                       const double box_max_um[3])
{
  double diag2 = 0;
  for (int k = 0; k < 3; k++) {
    cam->target_um[k] = 0.5 * (box_min_um[k] + box_max_um[k]);
    double e = box_max_um[k] - box_min_um[k];
    diag2 += e * e;
  }
  double diag = sqrt(diag2);
  if (!(diag > 0)) diag = 1.0;
  /* 30 deg of yaw and 25 deg of pitch show all three axes without hiding
   * the x-y layout; 0.62 of the diagonal leaves room for labels. */
  cam->yaw_rad = -30.0 * M_PI / 180.0;
  cam->pitch_rad = 25.0 * M_PI / 180.0;
  cam->half_height_um = 0.62 * diag;
  cam->depth_um = 2.0 * diag;
}

void elfm_camera_matrix(const elfm_camera *cam, double aspect, float m[16])
{
  double r[3][3];
  camera_view_rows(cam, r);
  double sx = 1.0 / (cam->half_height_um * (aspect > 0 ? aspect : 1.0));
  double sy = 1.0 / cam->half_height_um;
  double sz = 1.0 / (cam->depth_um > 0 ? cam->depth_um : 1.0);
  double s[3] = {sx, sy, -sz}; /* OpenGL clip z: -1 near, camera looks down -z */
  memset(m, 0, 16 * sizeof *m);
  for (int i = 0; i < 3; i++) {
    double t = 0;
    for (int j = 0; j < 3; j++) {
      m[j * 4 + i] = (float)(s[i] * r[i][j]);
      t += r[i][j] * cam->target_um[j];
    }
    m[12 + i] = (float)(-s[i] * t);
  }
  m[15] = 1.0f;
}

void elfm_camera_project(const elfm_camera *cam, int width, int height,
                         const double p_um[3], double *col_px, double *row_px)
{
  double r[3][3];
  camera_view_rows(cam, r);
  double d[3] = {p_um[0] - cam->target_um[0], p_um[1] - cam->target_um[1],
                 p_um[2] - cam->target_um[2]};
  double vx = r[0][0] * d[0] + r[0][1] * d[1] + r[0][2] * d[2];
  double vy = r[1][0] * d[0] + r[1][1] * d[1] + r[1][2] * d[2];
  double px_per_um = height / (2.0 * cam->half_height_um);
  /* Clip-space y grows upwards; picture rows grow downwards. */
  *col_px = 0.5 * width + vx * px_per_um;
  *row_px = 0.5 * height - vy * px_per_um;
}

void elfm_camera_rotate(elfm_camera *cam, double dx_px, double dy_px)
{
  /* 0.4 deg per pixel: a drag across a 900-pixel window turns a full turn. */
  const double rad_per_px = 0.4 * M_PI / 180.0;
  cam->yaw_rad += dx_px * rad_per_px;
  cam->pitch_rad += dy_px * rad_per_px;
  if (cam->pitch_rad > M_PI / 2) cam->pitch_rad = M_PI / 2;
  if (cam->pitch_rad < -M_PI / 2) cam->pitch_rad = -M_PI / 2;
}

void elfm_camera_zoom(elfm_camera *cam, double steps)
{
  /* 10 % per wheel notch: fine enough to frame, 22 notches per decade. */
  cam->half_height_um *= pow(0.9, steps);
  if (cam->half_height_um < 1e-3) cam->half_height_um = 1e-3;
  if (cam->half_height_um > 1e7) cam->half_height_um = 1e7;
}

void elfm_camera_pan(elfm_camera *cam, double dx_px, double dy_px, int height_px)
{
  double r[3][3];
  camera_view_rows(cam, r);
  double um_per_px = 2.0 * cam->half_height_um / (height_px > 0 ? height_px : 1);
  /* Screen right is view +x, screen down is view -y: move the target the
   * opposite way so the picture follows the mouse. */
  double ax = -dx_px * um_per_px, ay = dy_px * um_per_px;
  for (int j = 0; j < 3; j++) cam->target_um[j] += r[0][j] * ax + r[1][j] * ay;
}

double elfm_nice_step(double span, int n)
{
  if (!(span > 0) || n < 1) return 1.0;
  double raw = span / n;
  double p = pow(10.0, floor(log10(raw)));
  double f = raw / p;
  double nice = f < 1.5 ? 1 : f < 3.5 ? 2 : f < 7.5 ? 5 : 10;
  return nice * p;
}
