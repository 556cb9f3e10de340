# find_package(mujoco) for mjtether's build and for its installed package (mjtetherConfig.cmake
# includes this file too, so consumers get the same fix).
#
# Debian 12's mujoco package lists /usr/include/libqhull_r/ among mujoco::mujoco's include
# directories, and no installed package provides it: CMake then refuses every target that links
# mujoco::mujoco ("includes non-existent path"). Drop the directories that do not exist.
if(NOT TARGET mujoco::mujoco)
  if(COMMAND find_dependency)
    find_dependency(mujoco)
  else()
    find_package(mujoco REQUIRED)
  endif()
endif()
if(TARGET mujoco::mujoco)
  get_target_property(_mjtether_mj_inc mujoco::mujoco INTERFACE_INCLUDE_DIRECTORIES)
  if(_mjtether_mj_inc)
    set(_mjtether_mj_kept)
    foreach(_mjtether_dir IN LISTS _mjtether_mj_inc)
      if(EXISTS "${_mjtether_dir}")
        list(APPEND _mjtether_mj_kept "${_mjtether_dir}")
      endif()
    endforeach()
    set_target_properties(mujoco::mujoco PROPERTIES
                          INTERFACE_INCLUDE_DIRECTORIES "${_mjtether_mj_kept}")
  endif()
endif()
