# recon: frames, median, refocusing, pipeline and outputs (issue 4).
elfm_add_test(test_frames test_frames.c)
elfm_add_test(test_frames_integral test_frames_integral.c)
elfm_add_test(test_frames_deep test_frames_deep.c)
elfm_add_test(test_median test_median.c)
elfm_add_test(test_blur test_blur.c)
elfm_add_test(test_refocus test_refocus.c)
elfm_add_test(test_localize test_localize.c)
# three simulated recordings and ~10 refinements, two with the turn's search
# (27 runs of the pipeline each): 20-28 s; under the sanitizers 176 s alone
# and 310 s beside the other tests in CI (with four more searches then),
# where 120 x 3 was the limit
elfm_add_test(test_calib_refine test_calib_refine.c TIMEOUT 200)
# one simulated z sweep refined on its 900 ms (the integral given, then chosen): ~20 s;
# under the sanitizers beside the other tests in CI 271 s (seventieth session), where
# 120 x 3 was the limit
elfm_add_test(test_calib_still test_calib_still.c TIMEOUT 200)
# frames drawn by hand, then four simulated recordings and seven refinements:
# ~20 s; under the sanitizers 72 s alone (test_calib_refine's took 1.8 x
# that beside the other tests in CI)
elfm_add_test(test_calib_sweep test_calib_sweep.c TIMEOUT 300)
# frames drawn by hand (five sweeps of six beads, one of 25), simulated
# sweeps of five beads and of thirty and their refinements: ~10 s
# (of which ~6 s the simulator's thirty beads)
elfm_add_test(test_calib_sweep_beads test_calib_sweep_beads.c TIMEOUT 120)
# frames drawn by hand (five sweeps), two simulated sweeps refined three
# times, a flow simulated and tracked twice: ~8 s
elfm_add_test(test_calib_sweep_focus test_calib_sweep_focus.c TIMEOUT 120)
# 8,000 random spot lists matched to their patterns twice, one way in full: ~3 s
elfm_add_test(test_calib_pattern test_calib_pattern.c)
elfm_add_test(test_recon_pipeline test_recon_pipeline.c)
elfm_add_test(test_recon_plan test_recon_plan.c)
elfm_add_test(test_mip_png test_mip_png.c TIMEOUT 60)
target_link_libraries(test_recon_pipeline PRIVATE TIFF::TIFF)  # writes a mixed-depth stack
elfm_add_test(test_recon_sim test_recon_sim.c)
elfm_add_test(test_recon_cli test_recon_cli.c)
elfm_add_test(test_fmt_num test_fmt_num.c TIMEOUT 120)
elfm_add_test(test_big_alloc test_big_alloc.c)
