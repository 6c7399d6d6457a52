# Core (error object, volume, CLI table).
elfm_add_test(test_core test_core.c)
add_test(NAME cli_help COMMAND ${CMAKE_SOURCE_DIR}/tests/cli_help.sh ${CMAKE_BINARY_DIR}/eventlfm ${CMAKE_SOURCE_DIR})
elfm_add_test(test_exr_bad test_exr_bad.c)
elfm_add_test(test_exr_roundtrip test_exr_roundtrip.c)
