/* cmd_track_bias.c — eventlfm track's motion bias: the defaults of the
 * smoother's lead, delay, fade and slow-bead terms for the representation
 * chosen (part of track_opts_derive, cmd_track_defaults.c; the lead that
 * follows the recording's peaks is track_motion_lead_um, cmd_track_volume.c). */
#include <math.h>

#include "cmd_track.h"

/* The mean age (us) of a window's events under the view fit's pixel
 * weights value^P, on an ON time surface whose value falls with an event's
 * age a: exp(-a / tau) (exp) or 1 - a / tau until tau (lin), over a window
 * of dt us in which the events are spread evenly. It is the delay of the
 * motion bias (track's --motion-delay-us, less the measured 150 us):
 * the fit places a moving object where it was that long before the
 * frame's end. exp: with k = P / tau, 1/k - dt e^(-k dt) / (1 - e^(-k dt)).
 * lin, with L = min(dt, tau) and s = 1 - a / tau running from 1 to
 * r = 1 - L / tau: tau (1 - r^(P+1) - (P+1) (1 - r^(P+2)) / (P+2)) /
 * (1 - r^(P+1)); tau / (P + 2) when dt >= tau (a sample: tau 1000 us, P 3:
 * 200 us, against 281 us on the exp surface of the same tau). */
static double surface_mean_age_us(elfm_repr repr, double power, double tau_us, double dt_us)
{
  if (repr == ELFM_REPR_EXP) {
    const double k = power / tau_us, w = dt_us;
    /* A surface that barely decays over the window (k dt -> 0: --tau-us
     * 1e300 gave 1/k - inf): the limit dt / 2, by its series, where the
     * two terms above would cancel to their last digits. */
    if (k * w < 1e-6) return w * (0.5 - k * w / 12.0);
    return 1.0 / k - w * exp(-k * w) / (1.0 - exp(-k * w));
  }
  const double r = 1.0 - (dt_us < tau_us ? dt_us : tau_us) / tau_us;
  const double r1 = pow(r, power + 1.0), r2 = pow(r, power + 2.0);
  return tau_us * (1.0 - r1 - (power + 1.0) * (1.0 - r2) / (power + 2.0)) / (1.0 - r1);
}

void track_bias_derive(track_opts *o, const track_given *g)
{
  const int integral = o->recon.framer.repr == ELFM_REPR_INTEGRAL;
  /* The motion bias's two terms are defaults each on its own: a lead or a
   * delay given alone leaves the other at its default (before, either one
   * given set the other to 0, and a delay given alone, lead 0, took flow
   * seeds 1-20 from alpha 0.818 to 0.639). */
  const int bias_default = !o->lag_correct && o->localize_views;
  if (bias_default &&
      (o->recon.framer.repr == ELFM_REPR_EXP || o->recon.framer.repr == ELFM_REPR_LIN) &&
      o->recon.framer.polarity == ELFM_POL_ON) {
    /* The view fit of an ON time surface places a moving object ahead of
     * where it is (ON events fire on its leading half) and where it was a
     * little earlier (the weights value^P favour the newest events, not the
     * frame's end): along its lateral motion v the error is lead - delay x
     * |v|. The delay is the weighted events' mean age in the window (below)
     * + 20 us; 150 us until the simulator's events stopped lagging by half
     * a time step (forty-second session, docs/simulator.md "Time steps").
     * `score --calib` now regresses 326 us (age + 45, flow 100 ms seeds
     * 1-20) with a lead 0.13 um above the one below, which the two trade
     * along the motion; alpha over offsets 0 / 10 / 20 / 45 us: 0.8771 /
     * 0.8780 / 0.8782 / 0.8752 (seeds 1-20), 0.8739 / 0.8746 / 0.8747 /
     * 0.8713 (21-32) (docs/tracker.md "Delay after the simulator's time
     * steps"). (The sixth session's
     * 0.8 um and age + 20 us came from a regression on the lateral speed
     * alone, which beads climbing steeply in z bias low; docs/tracker.md
     * "Motion bias".) The lead belongs to the sample (brighter beads lead
     * further: below), and `eventlfm score` reports it for a simulated
     * scene like the user's. Flow seeds 1-20 alpha 0.8032 ->
     * 0.8043 (0.8 um, age + 20 us against these), held-out seeds 21-24
     * 0.8022 -> 0.8037, stage seeds 1-3 0.741 / 0.807 / 0.723 -> 0.769 /
     * 0.837 / 0.750. */
    const double age_us = surface_mean_age_us(o->recon.framer.repr, o->loc.power,
                                              o->recon.framer.tau_us, (double)o->recon.framer.dt_us);
    if (!g->mdelay)
      o->smooth.motion_delay_us = age_us + 20.0 + (track_led_windows(o) ? TRACK_LED_DELAY_EXTRA_US : 0.0);
    /* Brighter beads lead further, and their in-focus peaks are wider
     * (the arc of ON events reaches further out): flow 100 ms at 0.5 / 1 /
     * 2 / 4 x the beads' flux, lead (score --calib) against the median
     * width of the peaks within 20 um of focus (elfm_detection.width_um),
     * 14 recordings: lead = 1.52 x width, RMS 0.067 um without the dimmest
     * (an affine fit's intercept is 0.03 um). So the lead follows the
     * recording's peaks (track_motion_lead_um); 1.25 um until 50 peaks.
     * Those were a simulation's first 100 ms, where every pixel's
     * reference still lay anywhere in its dead band. Once objects have
     * passed, their OFF events leave it above the background, the leading
     * edge fires later, and dim beads lead much less: flow 1 s at 0.5 / 1 /
     * 2 x the flux, detections after 400 ms, lead = 1.80 x width - 0.37
     * um (12 recordings; RMS 0.125 um against 0.193 for 1.52 x width).
     * A real recording starts in that state (docs/tracker.md "The lead in
     * the sensor's steady state"); --motion stage, whose pixels mostly see
     * a bead pass once, keeps 1.52 x width (track_motion_lead_um). */
    if (!g->mlead) {
      o->smooth.motion_lead_um = 1.25;
      o->motion_lead_auto = 1;
    }
    /* Slow beads lead further than lead - delay x |w| says: the error of
     * the raw detections along the motion, binned by speed (lateral
     * movers, |z| < 40 um, flow 150 ms at 0.6-5 mm/s, seeds 1-2), follows
     * that line from 2.5 to 5 um/ms and bends above it below ~3 um/ms, by
     * +0.38 um at 0.9 um/ms, +0.30 at 1.4, +0.22 at 1.9, +0.15 at 2.25:
     * 0.17 ms x (3 um/ms - |w|). 0.5 ms windows and tau 2 ms bend alike
     * (+0.52 / +0.44 um at 0.9 um/ms); so does the stage at 0.5-1 um/ms.
     * Mean alpha, off -> on: flow 100 ms seeds 1-8 0.8744 -> 0.8763, held-out
     * 9-20 0.8356 -> 0.8374, flow_random 1-10 0.6383 -> 0.6406, flow at
     * 0.6-2.5 mm/s (8 held-out runs) 0.7699 -> 0.7938, stage and stage_accel
     * (16 runs, 0.5-3.5 mm/s) 0.8055 -> 0.8373, blink_moving 1-4 0.8423 ->
     * 0.8538 (docs/tracker.md "The lead of slow beads"). A lead or delay
     * given (eventlfm score's regression on a scene like the sample) stands
     * for the whole line: the bend is then off unless given too. */
    if (!g->mlead && !g->mdelay) {
      if (!g->mslow) o->smooth.motion_slow_lead_ms = 0.17;
      if (!g->mslows) o->smooth.motion_slow_um_per_ms = 3.0;
    }
  } else if (bias_default && integral) {
    /* The integral places a crawling neuron ahead of itself too, by a
     * lead: `eventlfm score --calib --motion-fade-um-per-ms 0.05` on the
     * raw detections, worm 200 ms seeds 1-4 (neurons at 0.12 um/ms, one
     * speed: lead and delay not separable), mean error along the motion
     * +0.168 / +0.215 / +0.261 / +0.170 um. At these speeds the default
     * fade (0.5 um/ms) would keep a quarter of the lead, so the fade is
     * lowered to 0.05 um/ms. Worm seeds 1-4 alpha 0.830 / 0.785 /
     * 0.754 / 0.826 -> 0.833 / 0.791 / 0.760 / 0.830 (lead 0.15 / 0.25:
     * means 0.8043 / 0.8010 against 0.8035 at 0.2; fade 0.5: 0.8018).
     * Twelfth session: most of that lead was the first frames', where an
     * integral started from 0 showed only where each neuron had moved to.
     * Started from its levels (--integral-start-ms) the detections lie
     * +0.068 / +0.105 / +0.122 / +0.052 um ahead (seeds 1-4; 0.10-0.16 on
     * 5-7), and alpha at lead 0 / 0.1 / 0.2 is 0.8690 / 0.8708 / 0.8688
     * (held-out seeds 5-7: 0.858 / 0.860 / 0.860): 0.1. Thirteenth
     * session: with bright levels leaking more slowly (tau_bright_us) the
     * detections lag a little instead: -0.070 / -0.029 / -0.055 / -0.087 /
     * -0.057 / -0.053 / +0.003 um along the motion (seeds 1-7, mean
     * -0.05). Mean alpha over 200 ms seeds 1-4 / 5-7 / 8-12, 150 ms, 500
     * ms at lead 0.1: 0.927 / 0.919 / 0.927 / 0.909 / 0.907; given as
     * --motion-lead-um 0 / -0.05 (which leaves the fade at 0.5): 0.938 /
     * 0.927 / 0.937 / 0.918 / 0.918, 0.938 / 0.928 / 0.938 / 0.919 /
     * 0.919; -0.05 here, with the fade at 0.05: 0.940 / 0.929 / 0.939 /
     * 0.920 / 0.921. */
    if (!g->mlead) o->smooth.motion_lead_um = -0.05;
    if (!g->mdelay) o->smooth.motion_delay_us = 0;
    if (!g->fade) o->smooth.motion_lead_fade_um_per_ms = 0.05;
  }
}
