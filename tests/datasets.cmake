# Calibration (recon/calib.c) and the physics simulator (datasets/).
elfm_add_test(test_calib test_calib.c TIMEOUT 30)
