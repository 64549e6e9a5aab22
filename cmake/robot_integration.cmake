# Robot integration: which parts this machine can build. Each sets a variable the top-level
# CMakeLists tests; a missing part is reported, never an error (the simulator builds without it).
#
# ROS 1 (Debian's roscpp): SKYTRACE_ROS_FOUND. Message headers are header-only (/usr/include);
# find_package() of a message package or of tf2_ros would pull catkin into this non-catkin build,
# so those are found as plain headers and libraries.
# Gazebo transport (ignition-transport 11, ignition-msgs 8 of Gazebo Fortress): SKYTRACE_GZ_FOUND.
# ROS 2 over DDS (Debian's Cyclone DDS; no ROS 2 install): SKYTRACE_ROS2_FOUND, and for its tests
# the independent peer on Fast DDS 2.9 / Fast CDR: SKYTRACE_FASTDDS_FOUND.

set(SKYTRACE_ROS_FOUND FALSE)
find_package(roscpp QUIET)
if(roscpp_FOUND)
  find_library(SKYTRACE_TF2_ROS_LIBRARY tf2_ros)
  find_library(SKYTRACE_TF2_LIBRARY tf2)
  find_path(SKYTRACE_ROS_MSGS_INCLUDE_DIR
    NAMES sensor_msgs/NavSatFix.h geometry_msgs/TwistWithCovarianceStamped.h nav_msgs/Odometry.h
          visualization_msgs/MarkerArray.h std_msgs/String.h)
  find_path(SKYTRACE_ROS_STD_MSGS_DIR NAMES Header.msg PATHS /usr/share/std_msgs/msg NO_DEFAULT_PATH)
  find_file(SKYTRACE_GENCPP_SCRIPT gen_cpp.py PATHS /usr/lib/gencpp NO_DEFAULT_PATH)
  find_path(SKYTRACE_GENCPP_TEMPLATE_DIR msg.h.template PATHS /usr/share/gencpp NO_DEFAULT_PATH)
  # gencpp lives in Debian's Python (/usr/lib/python3/dist-packages): PYTHON_EXECUTABLE when it can
  # import it, else /usr/bin/python3.
  set(SKYTRACE_ROS_PYTHON "")
  foreach(candidate ${PYTHON_EXECUTABLE} /usr/bin/python3)
    if(candidate AND EXISTS ${candidate} AND NOT SKYTRACE_ROS_PYTHON)
      execute_process(COMMAND ${candidate} -c "import gencpp, genmsg" RESULT_VARIABLE import_failed
                      OUTPUT_QUIET ERROR_QUIET)
      if(NOT import_failed)
        set(SKYTRACE_ROS_PYTHON ${candidate})
      endif()
    endif()
  endforeach()
  set(missing "")
  foreach(var SKYTRACE_TF2_ROS_LIBRARY SKYTRACE_TF2_LIBRARY SKYTRACE_ROS_MSGS_INCLUDE_DIR SKYTRACE_ROS_STD_MSGS_DIR
              SKYTRACE_GENCPP_SCRIPT SKYTRACE_GENCPP_TEMPLATE_DIR SKYTRACE_ROS_PYTHON)
    if(NOT ${var})
      list(APPEND missing ${var})
    endif()
  endforeach()
  if(missing)
    message(STATUS "ROS 1 node not built: roscpp found but not ${missing} (scripts/setup installs them)")
  else()
    set(SKYTRACE_ROS_FOUND TRUE)
    message(STATUS "ROS 1 node: built (roscpp ${roscpp_VERSION}, message generation with ${SKYTRACE_ROS_PYTHON})")
  endif()
else()
  message(STATUS "ROS 1 node not built: roscpp not found (scripts/setup installs it)")
endif()

set(SKYTRACE_GZ_FOUND FALSE)
find_package(ignition-transport11 QUIET)
find_package(ignition-msgs8 QUIET)
if(ignition-transport11_FOUND AND ignition-msgs8_FOUND)
  set(SKYTRACE_GZ_FOUND TRUE)
  message(STATUS "Gazebo transport bridge: built (ignition-transport 11, ignition-msgs 8)")
else()
  message(STATUS "Gazebo transport bridge not built: ignition-transport11 / ignition-msgs8 not found")
endif()

set(SKYTRACE_ROS2_FOUND FALSE)
if(SKYTRACE_ROS2)
  find_package(CycloneDDS QUIET)
  if(CycloneDDS_FOUND)
    set(SKYTRACE_ROS2_FOUND TRUE)
    message(STATUS "ROS 2 node: built (Cyclone DDS ${CycloneDDS_VERSION})")
  else()
    message(STATUS "ROS 2 node not built: Cyclone DDS not found (cyclonedds-dev; scripts/setup installs it)")
  endif()
else()
  message(STATUS "ROS 2 node not built: SKYTRACE_ROS2 is OFF")
endif()
set(SKYTRACE_FASTDDS_FOUND FALSE)
find_package(fastcdr QUIET)
find_package(fastrtps QUIET)
if(fastcdr_FOUND AND fastrtps_FOUND)
  set(SKYTRACE_FASTDDS_FOUND TRUE)
endif()
