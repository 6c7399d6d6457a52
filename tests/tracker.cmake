# Tracker: peaks, linker, smoother, track store and writers, analysis, track command.
elfm_add_test(test_peaks test_peaks.c TIMEOUT 60)
elfm_add_test(test_link test_link.c TIMEOUT 60)
elfm_add_test(test_smooth test_smooth.c TIMEOUT 60)
elfm_add_test(test_analysis test_analysis.c TIMEOUT 60)
elfm_add_test(test_tracks test_tracks.c TIMEOUT 60)
# End to end (simulate -> eventlfm track -> score): short scenes by default,
# the long ones (stage_accel, blink, blink_moving, worm) labelled slow.
elfm_add_test(test_track_e2e test_track_e2e.c TIMEOUT 300)
elfm_add_test(test_track_e2e_slow test_track_e2e.c ARGS slow LABELS slow TIMEOUT 3000)
add_test(NAME track_cli COMMAND ${CMAKE_SOURCE_DIR}/tests/track_cli.sh ${CMAKE_BINARY_DIR}/eventlfm)
set_tests_properties(track_cli PROPERTIES SKIP_RETURN_CODE 77 TIMEOUT 120)
add_test(NAME track_view_support COMMAND ${CMAKE_SOURCE_DIR}/tests/track_view_support.sh ${CMAKE_BINARY_DIR}/eventlfm)
set_tests_properties(track_view_support PROPERTIES SKIP_RETURN_CODE 77 TIMEOUT 120)
add_test(NAME track_localize COMMAND ${CMAKE_SOURCE_DIR}/tests/track_localize.sh ${CMAKE_BINARY_DIR}/eventlfm)
set_tests_properties(track_localize PROPERTIES SKIP_RETURN_CODE 77 TIMEOUT 120)
add_test(NAME track_integral COMMAND ${CMAKE_SOURCE_DIR}/tests/track_integral.sh ${CMAKE_BINARY_DIR}/eventlfm)
set_tests_properties(track_integral PROPERTIES SKIP_RETURN_CODE 77 TIMEOUT 120)
