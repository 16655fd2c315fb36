# SPDX-License-Identifier: GPL-3.0-or-later
# Flight simulator, dataset conversion and trajectory evaluation tools, and the bag I/O library.

# oefmt_bag_io: image streams in ROS bags (rosbag, sensor_msgs); the only ROS part of the I/O.
add_library(oefmt_bag_io src/ros/bag_io.cpp src/ros/vehicle_messages.cpp)
target_link_libraries(oefmt_bag_io PUBLIC oefmt_io ${catkin_LIBRARIES})
target_include_directories(oefmt_bag_io SYSTEM PUBLIC ${catkin_INCLUDE_DIRS})
install(TARGETS oefmt_bag_io
  ARCHIVE DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  RUNTIME DESTINATION ${CATKIN_GLOBAL_BIN_DESTINATION})

oefmt_add_tool(oefmt_simulate src/tools/simulate_main.cpp)
target_link_libraries(oefmt_simulate oefmt_bag_io)

oefmt_add_tool(oefmt_folder_to_bag src/tools/folder_to_bag_main.cpp)
target_link_libraries(oefmt_folder_to_bag oefmt_bag_io)

# oefmt_evaluate draws its plot with scripts/plot_trajectory.py: installed next to the executable,
# found in the source tree when run from the devel space.
oefmt_add_tool(oefmt_evaluate src/tools/evaluate_main.cpp)
target_compile_definitions(oefmt_evaluate PRIVATE
  OEFMT_SOURCE_PLOT_SCRIPT="${CMAKE_CURRENT_SOURCE_DIR}/scripts/plot_trajectory.py")
catkin_install_python(PROGRAMS scripts/plot_trajectory.py
  DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
