# vdmap's version for `vdmap --version`: the project version and, when the source is a git
# checkout and git is installed, `git describe --always` of it, taken when CMake configures (never
# at run time). Without git, or outside a checkout, it is the project version alone, silently.
# HEAD and its branch's ref are configure dependencies, so a commit re-runs the configure step and
# the build names the commit it was built from, not the one it was first configured at.
set(VDMAP_GIT_DESCRIBE "")
find_package(Git QUIET)
if(GIT_FOUND)
  execute_process(COMMAND ${GIT_EXECUTABLE} describe --always
                  WORKING_DIRECTORY ${PROJECT_SOURCE_DIR}
                  RESULT_VARIABLE git_result OUTPUT_VARIABLE git_describe ERROR_QUIET
                  OUTPUT_STRIP_TRAILING_WHITESPACE)
  if(git_result EQUAL 0)
    set(VDMAP_GIT_DESCRIBE "${git_describe}")
    execute_process(COMMAND ${GIT_EXECUTABLE} symbolic-ref -q HEAD
                    WORKING_DIRECTORY ${PROJECT_SOURCE_DIR}
                    OUTPUT_VARIABLE git_branch ERROR_QUIET OUTPUT_STRIP_TRAILING_WHITESPACE)
    foreach(ref HEAD ${git_branch} packed-refs)
      execute_process(COMMAND ${GIT_EXECUTABLE} rev-parse --path-format=absolute --git-path ${ref}
                      WORKING_DIRECTORY ${PROJECT_SOURCE_DIR}
                      OUTPUT_VARIABLE git_file ERROR_QUIET OUTPUT_STRIP_TRAILING_WHITESPACE)
      if(git_file AND EXISTS "${git_file}")
        set_property(DIRECTORY ${PROJECT_SOURCE_DIR} APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS "${git_file}")
      endif()
    endforeach()
  endif()
endif()
configure_file(${PROJECT_SOURCE_DIR}/cmake/version.h.in ${PROJECT_BINARY_DIR}/generated/vdmap_version.h @ONLY)
add_library(vdmap_version INTERFACE)
target_include_directories(vdmap_version INTERFACE ${PROJECT_BINARY_DIR}/generated)
