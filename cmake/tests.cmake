# SPDX-License-Identifier: GPL-3.0-or-later
# Tests of the tools, bags and the ROS wrapper's helpers; the ROS-free unit tests are globbed from
# test/unit into oefmt_unit_tests by CMakeLists.txt.

catkin_add_gtest(oefmt_tool_tests test/tools/test_bag_io.cpp test/tools/test_tools.cpp
                 test/tools/test_debug_rendering.cpp test/tools/test_frame_source.cpp
                 test/tools/test_stamp_guard.cpp test/tools/test_frame_queue.cpp
                 test/tools/test_rectification.cpp test/tools/test_parameter_doc.cpp
                 test/tools/test_diagnostics_doc.cpp src/tools/diagnostics_csv.cpp
                 src/tools/frame_source.cpp src/tools/bag_source.cpp src/tools/parameter_doc.cpp
                 test/support/gtest_main.cpp)
if(TARGET oefmt_tool_tests)
  target_include_directories(oefmt_tool_tests PRIVATE test src/tools)
  target_link_libraries(oefmt_tool_tests oefmt_ros oefmt_bag_io oefmt_sim oefmt_evaluation opencv_imgcodecs)
  target_compile_definitions(oefmt_tool_tests PRIVATE
    OEFMT_SIMULATE="$<TARGET_FILE:oefmt_simulate>"
    OEFMT_FOLDER_TO_BAG="$<TARGET_FILE:oefmt_folder_to_bag>"
    OEFMT_EVALUATE="$<TARGET_FILE:oefmt_evaluate>"
    OEFMT_OFFLINE="$<TARGET_FILE:oefmt_offline>"
    OEFMT_MEASURE_SPEED="${PROJECT_SOURCE_DIR}/scripts/measure_speed.py"
    OEFMT_GENERALIZATION_BENCHMARK="${PROJECT_SOURCE_DIR}/scripts/generalization_benchmark.py")
  add_dependencies(oefmt_tool_tests oefmt_simulate oefmt_folder_to_bag oefmt_evaluate oefmt_offline)
endif()
