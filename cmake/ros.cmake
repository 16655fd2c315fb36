# SPDX-License-Identifier: GPL-3.0-or-later
# The ROS wrapper: OdometryRos (parameters, subscriptions, worker thread, publishers), the
# nodelet plugin oefmt/OdometryNodelet and the standalone oefmt_node.

add_library(oefmt_ros src/ros/odometry_ros.cpp src/ros/node_parameters.cpp
                      src/ros/parameter_server.cpp src/ros/stamp_guard.cpp
                      src/ros/estimate_messages.cpp src/ros/rectification.cpp)
target_link_libraries(oefmt_ros PUBLIC oefmt_io oefmt_bag_io ${catkin_LIBRARIES})
target_include_directories(oefmt_ros SYSTEM PUBLIC ${catkin_INCLUDE_DIRS})
add_dependencies(oefmt_ros ${PROJECT_NAME}_generate_messages_cpp ${catkin_EXPORTED_TARGETS})

add_library(oefmt_nodelet src/ros/odometry_nodelet.cpp)
target_link_libraries(oefmt_nodelet oefmt_ros)

add_executable(oefmt_node src/ros/odometry_node.cpp)
target_link_libraries(oefmt_node oefmt_ros)

install(TARGETS oefmt_ros oefmt_nodelet oefmt_node
  ARCHIVE DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
install(FILES nodelet_plugins.xml DESTINATION ${CATKIN_PACKAGE_SHARE_DESTINATION})

# oefmt_parameters: the parameter documentation generated from the parameter tables
# (doc/parameters.md, config/default.yaml); the node's table is part of oefmt_ros.
add_executable(oefmt_parameters src/tools/parameters_main.cpp src/tools/parameter_doc.cpp)
target_link_libraries(oefmt_parameters oefmt_ros)
install(TARGETS oefmt_parameters RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
