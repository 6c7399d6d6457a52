/* elfm_recon.h — the recon module's public header: events in, volumes out.
 *
 * Include this one header. It gathers the module's parts, each documented in
 * its own section header:
 *   elfm_error.h   status codes and the error object (every call)
 *   elfm_events.h  streaming event-file readers (EVT3/EVT2/EVT2.1/DAT/CSV) and writers
 *   elfm_calib.h   Fourier LFM calibration and calib.json
 *   elfm_volume.h  the volume type
 *   elfm_frames.h  events -> frames (time surfaces, counts), median filter
 *   elfm_refocus.h refocus plan (shift-and-add), ghost suppression
 *   elfm_pipeline.h streaming driver events -> volumes, volume/MIP writers
 */
#ifndef ELFM_RECON_H
#define ELFM_RECON_H

#include "elfm_error.h"
#include "elfm_events.h"
#include "elfm_calib.h"
#include "elfm_volume.h"
#include "elfm_frames.h"
#include "elfm_refocus.h"
#include "elfm_pipeline.h"

#endif
