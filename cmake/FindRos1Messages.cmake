# Finds Debian's ROS 1 message serialisation (libroscpp-core-dev: ros/serialization.h and
# libroscpp_serialization) and the message headers vdmap decodes (sensor_msgs, tf2_msgs,
# geometry_msgs, nav_msgs, std_msgs), for mapping/ros/ros1_messages.cpp. Debian ships no CMake or
# pkg-config files for them that stand alone, so they are found by their files.
# Defines Ros1Messages_FOUND and the imported target Ros1::messages.
find_path(Ros1Messages_INCLUDE_DIR ros/serialization.h)
find_library(Ros1Messages_SERIALIZATION_LIBRARY roscpp_serialization)
set(Ros1Messages_HEADERS_FOUND TRUE)
foreach(header sensor_msgs/Image.h sensor_msgs/CompressedImage.h sensor_msgs/CameraInfo.h tf2_msgs/TFMessage.h
               geometry_msgs/TransformStamped.h geometry_msgs/PoseStamped.h nav_msgs/Odometry.h std_msgs/Float32.h)
  if(NOT EXISTS "${Ros1Messages_INCLUDE_DIR}/${header}")
    set(Ros1Messages_HEADERS_FOUND FALSE)
    message(STATUS "ROS 1 message header ${header} not found (packages: scripts/install-deps)")
  endif()
endforeach()

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(Ros1Messages
  REQUIRED_VARS Ros1Messages_INCLUDE_DIR Ros1Messages_SERIALIZATION_LIBRARY Ros1Messages_HEADERS_FOUND)

if(Ros1Messages_FOUND AND NOT TARGET Ros1::messages)
  add_library(Ros1::messages UNKNOWN IMPORTED)
  set_target_properties(Ros1::messages PROPERTIES
    IMPORTED_LOCATION "${Ros1Messages_SERIALIZATION_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${Ros1Messages_INCLUDE_DIR}")
endif()
mark_as_advanced(Ros1Messages_INCLUDE_DIR Ros1Messages_SERIALIZATION_LIBRARY)
