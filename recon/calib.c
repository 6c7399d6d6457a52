/* calib.c — Fourier LFM calibration (SPEC §2) and calib.json (SPEC §3).
 *
 * from_optics follows SPEC §2 to the letter (exact, non-paraxial view angles);
 * load checks every field (present, right type, finite, in range) and names
 * the file and the key path ("views[3].cx") of the first bad one; save writes
 * what load reads, with doubles printed so that they round-trip exactly
 * (cJSON prints %.15g and falls back to %.17g when that would lose bits).
 */
#include "elfm_calib.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

/* Sanity limits of the loader. They are far outside anything physical so
 * they only reject garbage: a 16-bit sensor coordinate is the EVT formats'
 * limit; 10 px/um of depth shift would mean a view angle of several radians
 * for the paper's 0.93 um/px; 4096 z planes is ~100x the usual 101. */
#define CALIB_MAX_SENSOR_PX 65535
#define CALIB_MAX_SHIFT_PX_PER_UM 10.0
#define CALIB_MAX_PLANES 4096
#define CALIB_MAX_LENSLET_OFFSET 4 /* 9 x 9 array = ELFM_MAX_VIEWS */

void elfm_optics_default(elfm_optics *o)
{
  /* The EventLFM paper's system (SPEC §2). */
  o->na = 0.75;
  o->n_medium = 1.0;       /* dry objective */
  o->magnification = 20.0; /* f_tube / f_objective = 200 mm / 10 mm */
  o->f_tube_mm = 200.0;
  o->f_fourier_mm = 80.0;
  o->f_mla_mm = 16.8;
  o->mla_pitch_um = 600.0;
  o->relay = 1.25;
  o->wavelength_um = 0.52; /* GFP / green bead emission */
  o->lenslets_per_side = 5;
  o->mla_rotation_deg = 0.0;
}

static int optics_valid(const elfm_optics *o, const char **bad)
{
#define OPT_POS(f)                                  \
  if (!(isfinite(o->f) && o->f > 0)) { *bad = #f; return 0; }
  OPT_POS(na);
  OPT_POS(n_medium);
  OPT_POS(magnification);
  OPT_POS(f_tube_mm);
  OPT_POS(f_fourier_mm);
  OPT_POS(f_mla_mm);
  OPT_POS(mla_pitch_um);
  OPT_POS(relay);
  OPT_POS(wavelength_um);
#undef OPT_POS
  if (o->na >= o->n_medium) { *bad = "na (must be < n_medium)"; return 0; }
  if (o->lenslets_per_side < 1 || o->lenslets_per_side > 2 * CALIB_MAX_LENSLET_OFFSET + 1 ||
      o->lenslets_per_side % 2 == 0) {
    *bad = "lenslets_per_side (odd, 1..9)";
    return 0;
  }
  /* beyond 45 degrees the array is another array's turn the other way */
  if (!(isfinite(o->mla_rotation_deg) && fabs(o->mla_rotation_deg) <= 45.0)) {
    *bad = "mla_rotation_deg (-45..45)";
    return 0;
  }
  return 1;
}

elfm_status elfm_calib_from_optics(const elfm_optics *o, int sensor_width_px,
                                   int sensor_height_px, double pixel_um,
                                   elfm_calib *out, elfm_error *err)
{
  const char *bad = NULL;
  if (!o || !out) return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "calib: NULL argument");
  if (!optics_valid(o, &bad))
    return elfm_error_set(err, ELFM_ERR_RANGE, NULL, -1, "optics: bad %s", bad);
  if (sensor_width_px < 1 || sensor_width_px > CALIB_MAX_SENSOR_PX || sensor_height_px < 1 ||
      sensor_height_px > CALIB_MAX_SENSOR_PX)
    return elfm_error_set(err, ELFM_ERR_RANGE, NULL, -1, "sensor size %dx%d out of range",
                          sensor_width_px, sensor_height_px);
  if (!(isfinite(pixel_um) && pixel_um > 0))
    return elfm_error_set(err, ELFM_ERR_RANGE, NULL, -1, "pixel_um must be > 0");

  memset(out, 0, sizeof *out);
  out->sensor_width_px = sensor_width_px;
  out->sensor_height_px = sensor_height_px;
  out->pixel_um = pixel_um;
  out->has_optics = 1;
  out->optics = *o;

  /* SPEC §2: M_T = M f_mla relay / f_fourier; N = 2 NA f_fourier / (M d). */
  const double m_total = o->magnification * o->f_mla_mm * o->relay / o->f_fourier_mm;
  const double n_lenslets = 2.0 * o->na * (o->f_fourier_mm * 1000.0) /
                            (o->magnification * o->mla_pitch_um);
  const double na_rel = o->na / o->n_medium;
  const double spacing_px = o->mla_pitch_um * o->relay / pixel_um;
  const double px_per_rad = m_total / pixel_um; /* object-space um of lateral shift -> px */
  out->um_per_px = pixel_um / m_total;

  /* Views around the sensor centre, the same convention as the volume's
   * voxel centres ((W-1)/2): pixel centres at integer coordinates. */
  const double cx0 = (sensor_width_px - 1) * 0.5, cy0 = (sensor_height_px - 1) * 0.5;
  const int half = o->lenslets_per_side / 2;
  const double rot_rad = o->mla_rotation_deg * (3.14159265358979323846 / 180.0);
  const double ca = cos(rot_rad), sa = sin(rot_rad);
  int n = 0;
  for (int j = -half; j <= half; j++) {
    for (int i = -half; i <= half; i++) {
      const double ui = 2.0 * i / n_lenslets, uj = 2.0 * j / n_lenslets;
      const double r2 = ui * ui + uj * uj;
      if (r2 >= 1.0) continue; /* outside the pupil: dark */
      const double root = sqrt(1.0 - na_rel * na_rel * r2);
      elfm_view *v = &out->views[n++];
      v->i = i;
      v->j = j;
      /* A turned array turns the lenslet's offset, in the pupil (its
       * disparity, along that offset) and on the sensor alike; the angle's
       * root above depends on the distance from the axis only. */
      const double ox = i * spacing_px, oy = j * spacing_px;
      const double dx = px_per_rad * na_rel * ui / root, dy = px_per_rad * na_rel * uj / root;
      v->cx_px = cx0 + ca * ox - sa * oy;
      v->cy_px = cy0 + sa * ox + ca * oy;
      v->dx_px_per_um = ca * dx - sa * dy;
      v->dy_px_per_um = sa * dx + ca * dy;
    }
  }
  if (n == 0)
    return elfm_error_set(err, ELFM_ERR_RANGE, NULL, -1,
                          "optics: no view inside the pupil (N = %.3g lenslets)", n_lenslets);
  out->n_views = n;
  out->view_w_px = 144; /* just under the ~154 px view spacing: views don't overlap */
  out->view_h_px = 144;
  out->z_min_um = -100.0; /* the paper's usable depth, +-100 um */
  out->z_max_um = 100.0;
  out->z_step_um = 2.0;   /* ~1/10 of the 21 um axial FWHM */
  return ELFM_OK;
}

void elfm_calib_project(const elfm_calib *c, int v, double x_um, double y_um, double z_um,
                        double *u_px, double *v_px)
{
  const elfm_view *w = &c->views[v];
  *u_px = w->cx_px + x_um / c->um_per_px + z_um * w->dx_px_per_um;
  *v_px = w->cy_px + y_um / c->um_per_px + z_um * w->dy_px_per_um;
}

double elfm_calib_view_on_sensor(const elfm_calib *c, int v)
{
  if (v < 0 || v >= c->n_views) return 0;
  const elfm_view *w = &c->views[v];
  const double x0 = w->cx_px - 0.5 * c->view_w_px, x1 = x0 + c->view_w_px;
  const double y0 = w->cy_px - 0.5 * c->view_h_px, y1 = y0 + c->view_h_px;
  const double ox = fmin(x1, c->sensor_width_px) - fmax(x0, 0);
  const double oy = fmin(y1, c->sensor_height_px) - fmax(y0, 0);
  if (ox <= 0 || oy <= 0) return 0;
  const double f = ox * oy / ((double)c->view_w_px * c->view_h_px);
  return f > 1 - 1e-9 ? 1 : f; /* x1 - x0 may round a hair below the width */
}

int elfm_calib_n_planes(const elfm_calib *c)
{
  return (int)floor((c->z_max_um - c->z_min_um) / c->z_step_um + 0.5) + 1;
}

/* What is wrong with a z range, or NULL: one rule for calib.json and for
 * elfm_calib_set_planes. Which key (or option) it is, the caller says. */
static const char *planes_problem(double z_min_um, double z_max_um, double z_step_um, int *which)
{
  *which = 0;
  if (!(fabs(z_min_um) <= 1e4)) return "not a finite number in -10000..10000";
  *which = 1;
  if (!(fabs(z_max_um) <= 1e4)) return "not a finite number in -10000..10000";
  if (z_max_um < z_min_um) return "below z.min_um";
  *which = 2;
  if (!(z_step_um >= 1e-3 && z_step_um <= 1e4)) return "not a finite number in 0.001..10000";
  if ((z_max_um - z_min_um) / z_step_um + 1 > CALIB_MAX_PLANES) return "more than 4096 z planes";
  return NULL;
}

elfm_status elfm_calib_set_planes(elfm_calib *c, double z_min_um, double z_max_um, double z_step_um,
                                  elfm_error *err)
{
  if (isnan(z_min_um)) z_min_um = c->z_min_um;
  if (isnan(z_max_um)) z_max_um = c->z_max_um;
  if (isnan(z_step_um)) z_step_um = c->z_step_um;
  static const char *const key[3] = {"z.min_um", "z.max_um", "z.step_um"};
  int which;
  const char *why = planes_problem(z_min_um, z_max_um, z_step_um, &which);
  if (why)
    return elfm_error_set(err, ELFM_ERR_RANGE, NULL, -1,
                          "z planes %g..%g um step %g: %s: %s", z_min_um, z_max_um, z_step_um,
                          key[which], why);
  c->z_min_um = z_min_um;
  c->z_max_um = z_max_um;
  c->z_step_um = z_step_um;
  return ELFM_OK;
}

elfm_status elfm_calib_bin(const elfm_calib *c, int factor, elfm_calib *out, elfm_error *err)
{
  if (factor < 1 || c->view_w_px / factor < 3 || c->view_h_px / factor < 3)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "binning %d: views of %d x %d px would be under 3 x 3 px", factor,
                          c->view_w_px, c->view_h_px);
  *out = *c;
  const double f = factor, half = 0.5 * (factor - 1);
  out->sensor_width_px = (c->sensor_width_px + factor - 1) / factor;
  out->sensor_height_px = (c->sensor_height_px + factor - 1) / factor;
  out->pixel_um = c->pixel_um * f;
  out->um_per_px = c->um_per_px * f;
  out->view_w_px = c->view_w_px / factor;
  out->view_h_px = c->view_h_px / factor;
  for (int v = 0; v < c->n_views; v++) {
    out->views[v].cx_px = (c->views[v].cx_px - half) / f;
    out->views[v].cy_px = (c->views[v].cy_px - half) / f;
    out->views[v].dx_px_per_um = c->views[v].dx_px_per_um / f;
    out->views[v].dy_px_per_um = c->views[v].dy_px_per_um / f;
  }
  return ELFM_OK;
}

/* ---- loading ---- */

/* Context of one load: the file name and the error to fill. */
typedef struct calib_ctx {
  const char *path;
  elfm_error *err;
} calib_ctx;

static elfm_status key_error(calib_ctx *cx, elfm_status code, const char *key, const char *what)
{
  return elfm_error_set(cx->err, code, cx->path, -1, "key \"%s\": %s", key, what);
}

/* A number at obj[name], finite and in [lo, hi]. key is the full path for
 * messages. */
static elfm_status get_number(calib_ctx *cx, const cJSON *obj, const char *name, const char *key,
                              double lo, double hi, double *out)
{
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, name);
  if (!it) return key_error(cx, ELFM_ERR_FORMAT, key, "missing");
  if (!cJSON_IsNumber(it)) return key_error(cx, ELFM_ERR_FORMAT, key, "not a number");
  double v = it->valuedouble;
  if (!isfinite(v)) return key_error(cx, ELFM_ERR_RANGE, key, "not finite");
  if (v < lo || v > hi) {
    return elfm_error_set(cx->err, ELFM_ERR_RANGE, cx->path, -1,
                          "key \"%s\": %.17g outside [%g, %g]", key, v, lo, hi);
  }
  *out = v;
  return ELFM_OK;
}

static elfm_status get_int(calib_ctx *cx, const cJSON *obj, const char *name, const char *key,
                           int lo, int hi, int *out)
{
  double v = 0;
  elfm_status s = get_number(cx, obj, name, key, lo, hi, &v);
  if (s) return s;
  if (v != floor(v)) return key_error(cx, ELFM_ERR_FORMAT, key, "not an integer");
  *out = (int)v;
  return ELFM_OK;
}

static elfm_status get_object(calib_ctx *cx, const cJSON *obj, const char *name,
                              const cJSON **out)
{
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, name);
  if (!it) return key_error(cx, ELFM_ERR_FORMAT, name, "missing");
  if (!cJSON_IsObject(it)) return key_error(cx, ELFM_ERR_FORMAT, name, "not an object");
  *out = it;
  return ELFM_OK;
}

static elfm_status parse_optics(calib_ctx *cx, const cJSON *o, elfm_optics *op)
{
  elfm_status s;
  elfm_optics_default(op);
  /* Physical ranges: NA of any objective < 1.7 (oil/TIRF); focal lengths up
   * to a metre; pitch up to 10 mm; wavelengths in the optical band. */
  if ((s = get_number(cx, o, "na", "optics.na", 1e-3, 1.7, &op->na))) return s;
  if ((s = get_number(cx, o, "n_medium", "optics.n_medium", 1.0, 2.0, &op->n_medium))) return s;
  if (op->na >= op->n_medium) return key_error(cx, ELFM_ERR_RANGE, "optics.na", "must be < n_medium");
  if ((s = get_number(cx, o, "magnification", "optics.magnification", 0.1, 1000, &op->magnification)))
    return s;
  if ((s = get_number(cx, o, "f_tube_mm", "optics.f_tube_mm", 1, 1000, &op->f_tube_mm))) return s;
  if ((s = get_number(cx, o, "f_fourier_mm", "optics.f_fourier_mm", 1, 1000, &op->f_fourier_mm)))
    return s;
  if ((s = get_number(cx, o, "f_mla_mm", "optics.f_mla_mm", 0.1, 1000, &op->f_mla_mm))) return s;
  if ((s = get_number(cx, o, "mla_pitch_um", "optics.mla_pitch_um", 1, 10000, &op->mla_pitch_um)))
    return s;
  if ((s = get_number(cx, o, "relay", "optics.relay", 0.01, 100, &op->relay))) return s;
  if ((s = get_number(cx, o, "wavelength_um", "optics.wavelength_um", 0.2, 2.0, &op->wavelength_um)))
    return s;
  /* lenslets_per_side is ours, not in SPEC §3's example: optional. */
  if (cJSON_GetObjectItemCaseSensitive(o, "lenslets_per_side")) {
    if ((s = get_int(cx, o, "lenslets_per_side", "optics.lenslets_per_side", 1,
                     2 * CALIB_MAX_LENSLET_OFFSET + 1, &op->lenslets_per_side)))
      return s;
  }
  /* ours too, and optional (0: the array aligned with the sensor's rows) */
  if (cJSON_GetObjectItemCaseSensitive(o, "mla_rotation_deg")) {
    if ((s = get_number(cx, o, "mla_rotation_deg", "optics.mla_rotation_deg", -45, 45,
                        &op->mla_rotation_deg)))
      return s;
  }
  return ELFM_OK;
}

static elfm_status parse_calib(calib_ctx *cx, const cJSON *root, elfm_calib *c)
{
  elfm_status s;
  const cJSON *sensor = NULL, *z = NULL;
  if (!cJSON_IsObject(root))
    return elfm_error_set(cx->err, ELFM_ERR_FORMAT, cx->path, 0, "top level is not a JSON object");

  if ((s = get_object(cx, root, "sensor", &sensor))) return s;
  if ((s = get_int(cx, sensor, "width", "sensor.width", 1, CALIB_MAX_SENSOR_PX, &c->sensor_width_px)))
    return s;
  if ((s = get_int(cx, sensor, "height", "sensor.height", 1, CALIB_MAX_SENSOR_PX,
                   &c->sensor_height_px)))
    return s;
  if ((s = get_number(cx, sensor, "pixel_um", "sensor.pixel_um", 0.1, 1000, &c->pixel_um))) return s;

  const cJSON *optics = cJSON_GetObjectItemCaseSensitive(root, "optics");
  if (optics) {
    if (!cJSON_IsObject(optics)) return key_error(cx, ELFM_ERR_FORMAT, "optics", "not an object");
    if ((s = parse_optics(cx, optics, &c->optics))) return s;
    c->has_optics = 1;
  }

  if ((s = get_number(cx, root, "um_per_px", "um_per_px", 1e-4, 1e4, &c->um_per_px))) return s;
  if (c->um_per_px <= 0) return key_error(cx, ELFM_ERR_RANGE, "um_per_px", "must be > 0");

  const cJSON *vs = cJSON_GetObjectItemCaseSensitive(root, "view_size_px");
  if (!vs) return key_error(cx, ELFM_ERR_FORMAT, "view_size_px", "missing");
  if (!cJSON_IsArray(vs) || cJSON_GetArraySize(vs) != 2)
    return key_error(cx, ELFM_ERR_FORMAT, "view_size_px", "not an array of 2 integers");
  {
    /* Wrap the two elements so the generic checker names them. */
    const cJSON *a = cJSON_GetArrayItem(vs, 0), *b = cJSON_GetArrayItem(vs, 1);
    const char *names[2] = {"view_size_px[0]", "view_size_px[1]"};
    const cJSON *items[2] = {a, b};
    int *dst[2] = {&c->view_w_px, &c->view_h_px};
    for (int k = 0; k < 2; k++) {
      if (!cJSON_IsNumber(items[k])) return key_error(cx, ELFM_ERR_FORMAT, names[k], "not a number");
      double v = items[k]->valuedouble;
      if (!isfinite(v) || v != floor(v) || v < 1 || v > CALIB_MAX_SENSOR_PX)
        return key_error(cx, ELFM_ERR_RANGE, names[k], "not an integer in [1, 65535]");
      *dst[k] = (int)v;
    }
  }

  const cJSON *views = cJSON_GetObjectItemCaseSensitive(root, "views");
  if (!views) return key_error(cx, ELFM_ERR_FORMAT, "views", "missing");
  if (!cJSON_IsArray(views)) return key_error(cx, ELFM_ERR_FORMAT, "views", "not an array");
  int nv = cJSON_GetArraySize(views);
  if (nv < 1 || nv > ELFM_MAX_VIEWS) {
    return elfm_error_set(cx->err, ELFM_ERR_RANGE, cx->path, -1,
                          "key \"views\": %d views, need 1..%d", nv, ELFM_MAX_VIEWS);
  }
  /* View centres may lie off the sensor (SPEC §2: a 5x5 grid overhangs the
   * 720-row EVK4), but not absurdly far: one sensor size beyond each edge. */
  const double cx_lo = -(double)c->sensor_width_px, cx_hi = 2.0 * c->sensor_width_px;
  const double cy_lo = -(double)c->sensor_height_px, cy_hi = 2.0 * c->sensor_height_px;
  const int L = CALIB_MAX_LENSLET_OFFSET;
  c->n_views = nv;
  for (int k = 0; k < nv; k++) {
    const cJSON *v = cJSON_GetArrayItem(views, k);
    char key[64];
    elfm_view *w = &c->views[k];
    snprintf(key, sizeof key, "views[%d]", k);
    if (!cJSON_IsObject(v)) return key_error(cx, ELFM_ERR_FORMAT, key, "not an object");
#define VKEY(name) (snprintf(key, sizeof key, "views[%d]." name, k), key)
    if ((s = get_int(cx, v, "i", VKEY("i"), -L, L, &w->i))) return s;
    if ((s = get_int(cx, v, "j", VKEY("j"), -L, L, &w->j))) return s;
    if ((s = get_number(cx, v, "cx", VKEY("cx"), cx_lo, cx_hi, &w->cx_px))) return s;
    if ((s = get_number(cx, v, "cy", VKEY("cy"), cy_lo, cy_hi, &w->cy_px))) return s;
    if ((s = get_number(cx, v, "dx_px_per_um", VKEY("dx_px_per_um"), -CALIB_MAX_SHIFT_PX_PER_UM,
                        CALIB_MAX_SHIFT_PX_PER_UM, &w->dx_px_per_um)))
      return s;
    if ((s = get_number(cx, v, "dy_px_per_um", VKEY("dy_px_per_um"), -CALIB_MAX_SHIFT_PX_PER_UM,
                        CALIB_MAX_SHIFT_PX_PER_UM, &w->dy_px_per_um)))
      return s;
#undef VKEY
    for (int q = 0; q < k; q++) {
      if (c->views[q].i == w->i && c->views[q].j == w->j) {
        return elfm_error_set(cx->err, ELFM_ERR_FORMAT, cx->path, -1,
                              "key \"views[%d]\": view (i=%d, j=%d) repeats views[%d]", k, w->i,
                              w->j, q);
      }
    }
  }

  if ((s = get_object(cx, root, "z", &z))) return s;
  if ((s = get_number(cx, z, "min_um", "z.min_um", -1e4, 1e4, &c->z_min_um))) return s;
  if ((s = get_number(cx, z, "max_um", "z.max_um", -1e4, 1e4, &c->z_max_um))) return s;
  if ((s = get_number(cx, z, "step_um", "z.step_um", 1e-3, 1e4, &c->z_step_um))) return s;
  static const char *const key[3] = {"z.min_um", "z.max_um", "z.step_um"};
  int which;
  const char *why = planes_problem(c->z_min_um, c->z_max_um, c->z_step_um, &which);
  return why ? key_error(cx, ELFM_ERR_RANGE, key[which], why) : ELFM_OK;
}

elfm_status elfm_calib_parse(const char *text, size_t len, const char *path, elfm_calib *out,
                             elfm_error *err)
{
  calib_ctx cx = {path ? path : "<memory>", err};
  const char *end = NULL;
  cJSON *root = cJSON_ParseWithLengthOpts(text, len, &end, 0);
  if (!root) {
    int64_t off = end ? (int64_t)(end - text) : -1;
    /* `end` rather than cJSON_GetErrorPtr(), which is global state. */
    return elfm_error_set(err, ELFM_ERR_FORMAT, cx.path, off, "invalid JSON");
  }
  elfm_calib c;
  memset(&c, 0, sizeof c);
  elfm_status s = parse_calib(&cx, root, &c);
  cJSON_Delete(root);
  if (s == ELFM_OK) *out = c;
  return s;
}

/* Read a whole (small) text file; *buf is malloc'd, caller frees. */
static elfm_status read_text(const char *path, char **buf, size_t *len, elfm_error *err)
{
  /* 16 MB: a calibration is a few kB; this only bounds a mistaken path. */
  const long max_bytes = 16L << 20;
  FILE *f = fopen(path, "rb");
  if (!f) return elfm_error_set(err, ELFM_ERR_IO, path, -1, "cannot open: %s", strerror(errno));
  char *b = NULL;
  size_t n = 0, cap = 0;
  for (;;) {
    if (n + 4096 > cap) {
      size_t ncap = cap ? cap * 2 : 8192;
      char *nb = realloc(b, ncap);
      if (!nb) {
        free(b);
        fclose(f);
        return elfm_error_set(err, ELFM_ERR_NOMEM, path, -1, "out of memory");
      }
      b = nb;
      cap = ncap;
    }
    size_t got = fread(b + n, 1, cap - n - 1, f);
    n += got;
    if (got == 0) break;
    if ((long)n > max_bytes) {
      free(b);
      fclose(f);
      return elfm_error_set(err, ELFM_ERR_FORMAT, path, max_bytes, "file larger than 16 MB");
    }
  }
  int bad = ferror(f);
  fclose(f);
  if (bad) {
    free(b);
    return elfm_error_set(err, ELFM_ERR_IO, path, (int64_t)n, "read failed");
  }
  b[n] = '\0';
  *buf = b;
  *len = n;
  return ELFM_OK;
}

elfm_status elfm_calib_load(const char *path, elfm_calib *out, elfm_error *err)
{
  char *text = NULL;
  size_t len = 0;
  if (!path || !out) return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "calib_load: NULL argument");
  elfm_status s = read_text(path, &text, &len, err);
  if (s) return s;
  if (len == 0) {
    free(text);
    return elfm_error_set(err, ELFM_ERR_FORMAT, path, 0, "empty file");
  }
  s = elfm_calib_parse(text, len, path, out, err);
  free(text);
  return s;
}

/* ---- saving ---- */

/* Shortest "%.Ng" text that reads back as exactly v. cJSON's own number
 * printer accepts a 15-digit text within one epsilon of the value, which
 * does not round-trip (found by fuzz_calib), so numbers go in as raw JSON. */
static void exact_number(double v, char *buf, size_t n)
{
  for (int digits = 15; digits <= 17; digits++) {
    snprintf(buf, n, "%.*g", digits, v);
    if (strtod(buf, NULL) == v) return;
  }
}

static int add_num(cJSON *o, const char *k, double v)
{
  char buf[40];
  exact_number(v, buf, sizeof buf);
  return cJSON_AddRawToObject(o, k, buf) != NULL;
}

static cJSON *calib_to_json(const elfm_calib *c)
{
  cJSON *root = cJSON_CreateObject();
  if (!root) return NULL;
  int ok = 1;
  cJSON *sensor = cJSON_AddObjectToObject(root, "sensor");
  ok = ok && sensor && add_num(sensor, "width", c->sensor_width_px) &&
       add_num(sensor, "height", c->sensor_height_px) && add_num(sensor, "pixel_um", c->pixel_um);
  if (ok && c->has_optics) {
    const elfm_optics *o = &c->optics;
    cJSON *op = cJSON_AddObjectToObject(root, "optics");
    ok = op && add_num(op, "na", o->na) && add_num(op, "n_medium", o->n_medium) &&
         add_num(op, "magnification", o->magnification) && add_num(op, "f_tube_mm", o->f_tube_mm) &&
         add_num(op, "f_fourier_mm", o->f_fourier_mm) && add_num(op, "f_mla_mm", o->f_mla_mm) &&
         add_num(op, "mla_pitch_um", o->mla_pitch_um) && add_num(op, "relay", o->relay) &&
         add_num(op, "wavelength_um", o->wavelength_um) &&
         add_num(op, "lenslets_per_side", o->lenslets_per_side);
    /* written only when turned, so that aligned calibrations keep their bytes */
    if (ok && o->mla_rotation_deg != 0.0) ok = add_num(op, "mla_rotation_deg", o->mla_rotation_deg);
  }
  ok = ok && add_num(root, "um_per_px", c->um_per_px);
  if (ok) {
    cJSON *vs = cJSON_AddArrayToObject(root, "view_size_px");
    ok = vs != NULL;
    if (ok) {
      cJSON *a = cJSON_CreateNumber(c->view_w_px), *b = cJSON_CreateNumber(c->view_h_px);
      if (a) cJSON_AddItemToArray(vs, a);
      if (b) cJSON_AddItemToArray(vs, b);
      ok = a && b;
    }
  }
  cJSON *views = ok ? cJSON_AddArrayToObject(root, "views") : NULL;
  ok = ok && views;
  for (int k = 0; ok && k < c->n_views; k++) {
    const elfm_view *w = &c->views[k];
    cJSON *v = cJSON_CreateObject();
    if (!v) { ok = 0; break; }
    cJSON_AddItemToArray(views, v);
    ok = add_num(v, "i", w->i) && add_num(v, "j", w->j) && add_num(v, "cx", w->cx_px) &&
         add_num(v, "cy", w->cy_px) && add_num(v, "dx_px_per_um", w->dx_px_per_um) &&
         add_num(v, "dy_px_per_um", w->dy_px_per_um);
  }
  cJSON *z = ok ? cJSON_AddObjectToObject(root, "z") : NULL;
  ok = ok && z && add_num(z, "min_um", c->z_min_um) && add_num(z, "max_um", c->z_max_um) &&
       add_num(z, "step_um", c->z_step_um);
  if (!ok) {
    cJSON_Delete(root);
    return NULL;
  }
  return root;
}

elfm_status elfm_calib_save(const elfm_calib *c, const char *path, elfm_error *err)
{
  if (!c || !path) return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "calib_save: NULL argument");
  if (c->n_views < 1 || c->n_views > ELFM_MAX_VIEWS)
    return elfm_error_set(err, ELFM_ERR_INVALID, path, -1, "calib has %d views", c->n_views);
  cJSON *root = calib_to_json(c);
  char *text = root ? cJSON_Print(root) : NULL;
  cJSON_Delete(root);
  if (!text) return elfm_error_set(err, ELFM_ERR_NOMEM, path, -1, "out of memory building JSON");
  FILE *f = fopen(path, "wb");
  if (!f) {
    cJSON_free(text);
    return elfm_error_set(err, ELFM_ERR_IO, path, -1, "cannot create: %s", strerror(errno));
  }
  size_t len = strlen(text);
  int ok = fwrite(text, 1, len, f) == len && fputc('\n', f) != EOF;
  cJSON_free(text);
  /* fclose reports errors of the final write-back (full disk). */
  if (fclose(f) != 0) ok = 0;
  if (!ok) return elfm_error_set(err, ELFM_ERR_IO, path, -1, "write failed: %s", strerror(errno));
  return ELFM_OK;
}
