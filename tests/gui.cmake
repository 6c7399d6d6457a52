# gui: the viewer (issue 6). test_gui_core needs no display; test_gui_render
# starts itself under xvfb-run when there is no DISPLAY (skips, exit 77, when
# xvfb-run is not installed). One X server at a time: xvfb-run -a picks its
# display number racily, so the display tests share a lock.
if(ELFM_GUI)
  elfm_add_test(test_gui_core test_gui_core.c TIMEOUT 60)
  target_link_libraries(test_gui_core PRIVATE elfm_gui)
  add_dependencies(test_gui_core eventlfm)
  elfm_add_test(test_gui_render test_gui_render.c TIMEOUT 120)
  target_link_libraries(test_gui_render PRIVATE elfm_gui)
  add_dependencies(test_gui_render eventlfm)
  set_tests_properties(test_gui_render PROPERTIES RESOURCE_LOCK xvfb)
endif()
