# Included at the end of every project() call in a workspace that env/bin/catkin_make
# configures (CMAKE_PROJECT_INCLUDE); it changes no package's files.
#
# catkin asks each package to write
#   add_dependencies(my_node ${${PROJECT_NAME}_EXPORTED_TARGETS} ${catkin_EXPORTED_TARGETS})
# so that its code compiles after the message and service headers it includes
# are generated. Many packages forget; a parallel make then compiles a node
# before its headers exist and fails with "No such file or directory". When
# the package's CMakeLists.txt has been read to its end, this adds those
# dependencies to each of its compiled targets.

if(NOT COMMAND _generated_messages_first)
  function(_generated_messages_targets_in directory out)
    get_property(targets DIRECTORY "${directory}" PROPERTY BUILDSYSTEM_TARGETS)
    get_property(subdirectories DIRECTORY "${directory}" PROPERTY SUBDIRECTORIES)
    foreach(subdirectory IN LISTS subdirectories)
      _generated_messages_targets_in("${subdirectory}" nested)
      list(APPEND targets ${nested})
    endforeach()
    set(${out} ${targets} PARENT_SCOPE)
  endfunction()

  function(_generated_messages_first)
    set(generators "")
    foreach(candidate IN LISTS ${PROJECT_NAME}_EXPORTED_TARGETS catkin_EXPORTED_TARGETS)
      # Only custom targets: message generators compile nothing, so no cycle can form.
      if(TARGET "${candidate}")
        get_target_property(candidate_type "${candidate}" TYPE)
        if(candidate_type STREQUAL "UTILITY")
          list(APPEND generators "${candidate}")
        endif()
      endif()
    endforeach()
    if(TARGET ${PROJECT_NAME}_generate_messages_cpp)
      list(APPEND generators ${PROJECT_NAME}_generate_messages_cpp)
    endif()
    if(NOT generators)
      return()
    endif()
    list(REMOVE_DUPLICATES generators)
    _generated_messages_targets_in("${CMAKE_CURRENT_SOURCE_DIR}" targets)
    foreach(target IN LISTS targets)
      get_target_property(type ${target} TYPE)
      if(type MATCHES "^(EXECUTABLE|STATIC_LIBRARY|SHARED_LIBRARY|MODULE_LIBRARY|OBJECT_LIBRARY)$")
        add_dependencies(${target} ${generators})
      endif()
    endforeach()
  endfunction()
endif()

# The workspace's own top-level project holds no package targets.
if(NOT CMAKE_CURRENT_SOURCE_DIR STREQUAL CMAKE_SOURCE_DIR)
  cmake_language(DEFER CALL _generated_messages_first)
endif()
