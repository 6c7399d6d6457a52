/* elfm_tracker.h — the tracker module's public header: volumes in, tracks out.
 *
 * Include this one header. Its parts, each documented in its section header:
 *   elfm_table.h     numeric CSV tables (truth.csv, tracks.csv, detections.csv)
 *   elfm_peaks.h     3D peak detection with sub-voxel refinement
 *   elfm_link.h      frame-to-frame linking (FLANN k-d tree, assignment, gap closing)
 *   elfm_smooth.h    Ceres-smoothed trajectories (model choice per track)
 *   elfm_tracks.h    track store and writers (CSV, ISBI 2012 XML, TrackMate)
 *   elfm_analysis.h  stage velocity and resolution (FWHM) analysis
 *   elfm_traces.h    intensity traces per object (tracks, or static clusters of detections)
 *   elfm_score.h     scoring against simulator truth (SPEC §7)
 */
#ifndef ELFM_TRACKER_H
#define ELFM_TRACKER_H

#include "elfm_recon.h"
#include "elfm_table.h"
#include "elfm_peaks.h"
#include "elfm_link.h"
#include "elfm_smooth.h"
#include "elfm_tracks.h"
#include "elfm_analysis.h"
#include "elfm_traces.h"
#include "elfm_score.h"

#endif
