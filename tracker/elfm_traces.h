/* elfm_traces.h — intensity traces per object: each object's refocused
 * value frame by frame, where the object is, whether or not it was
 * detected in that frame. For blinking beads and spiking neurons the trace
 * is the measurement (a pulse is a step in the trace); for moving objects
 * it is the brightness along the track.
 *
 *   elfm_trace_objects *o;
 *   elfm_trace_objects_from_tracks(tracks, hold, &o, &err);
 *     or elfm_trace_objects_from_detections(dets, radius_um, kz, min, &o, &err)
 *   per frame, in time order (e.g. from an elfm_recon_run with no_refocus):
 *     n = elfm_trace_objects_frame(o, plan, frame, vol, rows);
 *   elfm_trace_objects_free(o);
 *
 * Positions: an object from a track is where its track is, linear in time
 * between the track's points; with `hold`, also before its first point and
 * after its last (at those points): a static sample whose objects were
 * seen only while they flashed. An object from detections (static by
 * assumption: a slice, a fixed preparation) is the mean position of a
 * cluster of detections, held over the whole recording. The value is
 * elfm_refocus_sample at that position: the refocused volume's value
 * without refocusing the frame (8 voxels x the views), so a trace costs
 * little more than reading the events.
 *
 * Memory: the objects' points (the input table's rows), not the recording.
 */
#ifndef ELFM_TRACES_H
#define ELFM_TRACES_H

#include <stddef.h>
#include <stdint.h>

#include "elfm_error.h"
#include "elfm_frames.h"
#include "elfm_refocus.h"
#include "elfm_table.h"
#include "elfm_volume.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct elfm_trace_objects elfm_trace_objects;

typedef struct elfm_trace_object_info {
  int64_t id;                   /* the track's id, or the cluster's number from 0 */
  double x_um, y_um, z_um;      /* mean position of its points */
  size_t n_points;              /* its points (track rows, or clustered detections) */
  size_t n_detected;            /* of them, detections (a track's rows with raw_x_um) */
  int64_t first_t_us, last_t_us;
} elfm_trace_object_info;

typedef struct elfm_trace_row {
  int64_t id;
  double x_um, y_um, z_um;      /* where it was sampled */
  double intensity;             /* elfm_refocus_sample there */
  int detected;                 /* one of its detections lies within half this frame's window */
} elfm_trace_row;

/* Objects from a tracks table (`eventlfm track`'s tracks.csv: columns
 * track_id, t_us, x_um, y_um, z_um and, if present, raw_x_um, whose NaN
 * marks a point that was not a detection). Errors name the table's file:
 * a missing column, a non-finite value (with its line), no memory. */
elfm_status elfm_trace_objects_from_tracks(const elfm_table *tracks, int hold,
                                           elfm_trace_objects **out, elfm_error *err);

/* Static objects from a detections table (columns t_us, x_um, y_um, z_um,
 * intensity): brightest first, each detection joins the nearest cluster
 * whose mean lies within radius_um (distance sqrt(dx^2 + dy^2 + (dz /
 * kz)^2)), else starts one; clusters of fewer than min_detections are
 * dropped. radius_um > 0, kz > 0, min_detections >= 1. */
elfm_status elfm_trace_objects_from_detections(const elfm_table *dets, double radius_um, double kz,
                                               int min_detections, elfm_trace_objects **out,
                                               elfm_error *err);

size_t elfm_trace_objects_count(const elfm_trace_objects *o);
void elfm_trace_objects_info(const elfm_trace_objects *o, size_t i, elfm_trace_object_info *info);

/* The rows of one frame: every object present at frame->t_us (with hold or
 * from detections: every object), in object order, into rows (room for
 * elfm_trace_objects_count rows). `vol` gives the geometry (um <-> voxel),
 * e.g. the volume an elfm_recon_run callback receives. Frames must come in
 * increasing time (the objects keep a cursor). Returns the rows written. */
size_t elfm_trace_objects_frame(elfm_trace_objects *o, const elfm_refocus_plan *plan,
                                const elfm_frame *frame, const elfm_volume *vol,
                                elfm_trace_row *rows);

void elfm_trace_objects_free(elfm_trace_objects *o);

#ifdef __cplusplus
}
#endif

#endif
