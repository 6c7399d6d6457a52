# Event I/O (recon/ readers and writers, eventlfm info/convert).
elfm_add_test(test_events_ref test_events_ref.c TIMEOUT 120)
elfm_add_test(test_events_roundtrip test_events_roundtrip.c TIMEOUT 120)
elfm_add_test(test_events_bad test_events_bad.c TIMEOUT 120)
elfm_add_test(test_events_reverse test_events_reverse.c TIMEOUT 120)
add_test(NAME events_cli COMMAND ${CMAKE_SOURCE_DIR}/tests/events_cli.sh ${CMAKE_BINARY_DIR}/eventlfm ${ELFM_SHARED_DIR})
math(EXPR t "120 * ${ELFM_TIMEOUT_FACTOR}")
set_tests_properties(events_cli PROPERTIES TIMEOUT ${t})
