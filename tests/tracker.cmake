# Tracker: peaks, linker, smoother, track store and writers, analysis, track command.
elfm_add_test(test_peaks test_peaks.c TIMEOUT 60)
elfm_add_test(test_link test_link.c TIMEOUT 60)
elfm_add_test(test_link_fill test_link_fill.c TIMEOUT 60)
elfm_add_test(test_smooth test_smooth.c TIMEOUT 60)
elfm_add_test(test_analysis test_analysis.c TIMEOUT 60)
elfm_add_test(test_tracks test_tracks.c TIMEOUT 60)
# End to end (simulate -> eventlfm track -> score): short scenes by default,
# the long ones (stage_accel, blink, blink_moving, worm) labelled slow.
elfm_add_test(test_track_e2e test_track_e2e.c TIMEOUT 300)
elfm_add_test(test_track_e2e_slow test_track_e2e.c ARGS slow LABELS slow TIMEOUT 3000)
# The `eventlfm track` shell tests: tests/NAME.sh BINARY, exit 77 = skipped.
function(elfm_add_track_script name)
  add_test(NAME ${name} COMMAND ${CMAKE_SOURCE_DIR}/tests/${name}.sh ${CMAKE_BINARY_DIR}/eventlfm)
  set_tests_properties(${name} PROPERTIES SKIP_RETURN_CODE 77 TIMEOUT 120)
endfunction()
elfm_add_track_script(track_cli)
elfm_add_track_script(track_view_support)
elfm_add_track_script(track_localize)
elfm_add_track_script(track_motion_bias)
elfm_add_track_script(track_fill)
elfm_add_track_script(track_deep)
elfm_add_track_script(track_blink)
elfm_add_track_script(track_integral)
