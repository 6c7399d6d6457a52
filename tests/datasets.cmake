# Calibration (recon/calib.c) and the physics simulator (datasets/).
elfm_add_test(test_calib test_calib.c TIMEOUT 30)
elfm_add_test(test_sim test_sim.c TIMEOUT 120)
elfm_add_test(test_sim_scene test_sim_scene.c TIMEOUT 60)
add_test(NAME test_sim_cli COMMAND ${CMAKE_SOURCE_DIR}/tests/test_sim_cli.sh ${CMAKE_BINARY_DIR}/eventlfm ${CMAKE_CURRENT_BINARY_DIR})
math(EXPR t "60 * ${ELFM_TIMEOUT_FACTOR}")
set_tests_properties(test_sim_cli PROPERTIES TIMEOUT ${t})
