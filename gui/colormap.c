/* colormap.c — the colour map for time and depth, and hue (for tests).
 *
 * Turbo (A. Mikhailov, Google 2019) through its published degree-5 polynomial
 * fit (R. Du; Apache-2.0): a rainbow whose hue falls monotonically from blue
 * to red, so "earlier" and "later" read at a glance. The fit's two ends are
 * nearly black, invisible on the dark background, so s in [0,1] maps to
 * turbo's [0.10, 0.95]. gl_shaders.c evaluates the same polynomial; the
 * constants here and there must stay equal.
 */
#include <math.h>

#include "elfm_gui.h"

void elfm_colormap_rgb(double s, float rgb[3])
{
  static const double kr[6] = {0.13572138, 4.61539260, -42.66032258, 132.13108234,
                               -152.94239396, 59.28637943};
  static const double kg[6] = {0.09140261, 2.19418839, 4.84296658, -14.18503333,
                               4.27729857, 2.82956604};
  static const double kb[6] = {0.10667330, 12.64194608, -60.58204836, 110.36276771,
                               -89.90310912, 27.34824973};
  if (!(s >= 0.0)) s = 0.0; /* also NaN */
  if (s > 1.0) s = 1.0;
  double x = 0.10 + 0.85 * s;
  double r = 0, g = 0, b = 0, p = 1;
  for (int k = 0; k < 6; k++) {
    r += kr[k] * p;
    g += kg[k] * p;
    b += kb[k] * p;
    p *= x;
  }
  const double c[3] = {r, g, b};
  for (int k = 0; k < 3; k++)
    rgb[k] = (float)(c[k] < 0 ? 0 : c[k] > 1 ? 1 : c[k]);
}

double elfm_color_hue_deg(int r, int g, int b)
{
  double rf = r / 255.0, gf = g / 255.0, bf = b / 255.0;
  double mx = fmax(rf, fmax(gf, bf)), mn = fmin(rf, fmin(gf, bf));
  double d = mx - mn;
  if (d <= 0) return 0.0;
  double h;
  if (mx == rf) h = fmod((gf - bf) / d, 6.0);
  else if (mx == gf) h = (bf - rf) / d + 2.0;
  else h = (rf - gf) / d + 4.0;
  h *= 60.0;
  if (h < 0) h += 360.0;
  return h;
}
