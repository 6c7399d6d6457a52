# Tracker: peaks, linker, smoother, track store and writers, analysis, track command.
elfm_add_test(test_peaks test_peaks.c TIMEOUT 60)
elfm_add_test(test_link test_link.c TIMEOUT 60)
elfm_add_test(test_smooth test_smooth.c TIMEOUT 60)
elfm_add_test(test_analysis test_analysis.c TIMEOUT 60)
elfm_add_test(test_tracks test_tracks.c TIMEOUT 60)
