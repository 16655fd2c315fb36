# SPDX-License-Identifier: GPL-3.0-or-later
# Tests that need ROS (bags) or the built tools; the ROS-free unit tests are globbed from
# test/unit into oefmt_unit_tests by CMakeLists.txt.

catkin_add_gtest(oefmt_io_tests test/io/test_bag_io.cpp test/io/test_tools.cpp
                 test/io/test_debug_rendering.cpp test/io/test_frame_source.cpp
                 src/tools/frame_source.cpp test/support/gtest_main.cpp)
if(TARGET oefmt_io_tests)
  target_include_directories(oefmt_io_tests PRIVATE test src/tools)
  target_link_libraries(oefmt_io_tests oefmt_ros oefmt_bag_io oefmt_sim oefmt_core opencv_imgcodecs)
  target_compile_definitions(oefmt_io_tests PRIVATE
    OEFMT_SIMULATE="$<TARGET_FILE:oefmt_simulate>"
    OEFMT_FOLDER_TO_BAG="$<TARGET_FILE:oefmt_folder_to_bag>"
    OEFMT_EVALUATE="$<TARGET_FILE:oefmt_evaluate>"
    OEFMT_OFFLINE="$<TARGET_FILE:oefmt_offline>"
    OEFMT_CORE_LIBRARY="$<TARGET_FILE:oefmt_core>"
    OEFMT_MEASURE_SPEED="${PROJECT_SOURCE_DIR}/scripts/measure_speed.py")
  add_dependencies(oefmt_io_tests oefmt_simulate oefmt_folder_to_bag oefmt_evaluate oefmt_offline)
endif()
