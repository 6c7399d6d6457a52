/* refocus_sparse.c — the event-sparse refocus path: scatter each listed frame
 * pixel onto the planes (the adjoint of the dense bilinear gather, see
 * elfm_refocus.h), touching only the volume rows it reaches.
 *
 * The workspace remembers those rows, so the next call clears only them
 * (a 144 x 144 x 101 volume is 8.4 MB: clearing it whole would cost more
 * than refocusing a typical 1 ms frame).
 */
#include "refocus_internal.h"

#include <stdlib.h>
#include <string.h>

static void sparse_clear(const elfm_refocus_plan *p, elfm_volume *vol, elfm_refocus_workspace *ws)
{
  const size_t W = (size_t)p->w;
  if (ws->dirty_data != vol->data || ws->dirty_all) {
    memset(vol->data, 0, W * p->h * p->nz * sizeof *vol->data);
    if (p->need) {
      memset(ws->vox_cnt, 0, W * p->h * p->nz);
      memset(ws->vox_last, 0, W * p->h * p->nz);
    }
    for (size_t i = 0; i < ws->n_rows; i++) ws->row_dirty[ws->rows[i]] = 0;
  } else {
    for (size_t i = 0; i < ws->n_rows; i++) {
      size_t r = ws->rows[i];
      memset(vol->data + r * W, 0, W * sizeof *vol->data);
      if (p->need) {
        memset(ws->vox_cnt + r * W, 0, W);
        memset(ws->vox_last + r * W, 0, W);
      }
      ws->row_dirty[r] = 0;
    }
  }
  ws->n_rows = 0;
  ws->dirty_data = vol->data;
  ws->dirty_all = 0;
}

/* Pair every listed non-zero pixel with each view whose crop box holds it,
 * grouped by view (the agreement count relies on one view's taps being
 * contiguous). Grows ws->taps only when a frame has more pairs than any before. */
static elfm_status sparse_taps(const elfm_refocus_plan *p, const elfm_frame *frame,
                               elfm_refocus_workspace *ws, elfm_error *err)
{
  ws->n_taps = 0;
  for (int v = 0; v < p->nv; v++) {
    const elfm_refocus_box *b = &p->box[v];
    for (size_t i = 0; i < frame->nnz; i++) {
      uint32_t pix = frame->idx[i];
      float a = frame->data[pix];
      if (a == 0.0f) continue;
      int u = (int)(pix % (uint32_t)p->sw), y = (int)(pix / (uint32_t)p->sw);
      if (u < b->x0 || u >= b->x1 || y < b->y0 || y >= b->y1) continue;
      if (ws->n_taps == ws->cap_taps) {
        size_t cap = ws->cap_taps * 2;
        elfm_refocus_tap *t = realloc(ws->taps, cap * sizeof *t);
        if (!t) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory (%zu taps)", cap);
        ws->taps = t;
        ws->cap_taps = cap;
      }
      elfm_refocus_tap *t = &ws->taps[ws->n_taps++];
      t->u = u;
      t->v = y;
      t->a = a;
      t->view = v;
    }
  }
  return ELFM_OK;
}

static inline void mark_row(elfm_refocus_workspace *ws, uint32_t r)
{
  if (!ws->row_dirty[r]) {
    ws->row_dirty[r] = 1;
    ws->rows[ws->n_rows++] = r;
  }
}

elfm_status elfm_refocus_sparse(const elfm_refocus_plan *p, const elfm_frame *frame,
                                elfm_volume *vol, elfm_refocus_workspace *ws, elfm_error *err)
{
  sparse_clear(p, vol, ws);
  elfm_status st = sparse_taps(p, frame, ws, err);
  if (st) return st;
  const int W = p->w, H = p->h;
  const elfm_refocus_tap *taps = ws->taps;
  const size_t nt = ws->n_taps;
  for (int k = 0; k < p->nz; k++) {
    const elfm_refocus_shift *sk = p->shift + (size_t)k * p->nv;
    float *plane = vol->data + (size_t)k * W * H;
    for (size_t t = 0; t < nt; t++) {
      const elfm_refocus_shift *s = sk + taps[t].view;
      const int X0 = taps[t].u - s->ix, Y0 = taps[t].v - s->iy;
      const float ax0 = taps[t].a * (1.0f - s->fx), ax1 = taps[t].a * s->fx;
      const int okx0 = X0 >= s->xlo && X0 < s->xhi;
      const int okx1 = X0 - 1 >= s->xlo && X0 - 1 < s->xhi;
      for (int dy = 0; dy < 2; dy++) {
        const int Y = Y0 - dy;
        if (Y < s->ylo || Y >= s->yhi) continue;
        const float wy = dy ? s->fy : 1.0f - s->fy;
        const uint32_t r = (uint32_t)k * (uint32_t)H + (uint32_t)Y;
        mark_row(ws, r);
        float *o = plane + (size_t)Y * W;
        float c0 = wy * ax0, c1 = wy * ax1;
        if (okx0) o[X0] += c0;
        if (okx1) o[X0 - 1] += c1;
        if (p->need) {
          uint8_t *cnt = ws->vox_cnt + (size_t)r * W, *last = ws->vox_last + (size_t)r * W;
          const uint8_t id = (uint8_t)(taps[t].view + 1);
          if (okx0 && c0 != 0.0f && last[X0] != id) {
            last[X0] = id;
            cnt[X0]++;
          }
          if (okx1 && c1 != 0.0f && last[X0 - 1] != id) {
            last[X0 - 1] = id;
            cnt[X0 - 1]++;
          }
        }
      }
    }
  }
  for (size_t i = 0; i < ws->n_rows; i++) {
    const size_t r = ws->rows[i];
    float *row = vol->data + r * W;
    const float *inv = p->inv_count + r * W;
    for (int X = 0; X < W; X++) row[X] *= inv[X];
    if (p->need)
      elfm_ghost_agree_row(p, (int)(r / (size_t)H), (int)(r % (size_t)H), row, ws->vox_cnt + r * W);
  }
  elfm_ghost_threshold_apply(p, vol, ws->rows, ws->n_rows);
  return ELFM_OK;
}
