# Calibration (recon/calib.c) and the physics simulator (datasets/).
elfm_add_test(test_calib test_calib.c TIMEOUT 30)
elfm_add_test(test_sim test_sim.c TIMEOUT 120)
elfm_add_test(test_sim_scene test_sim_scene.c TIMEOUT 60)
