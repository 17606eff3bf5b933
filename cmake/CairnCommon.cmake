# Shared CMake settings for every cairn package. Included by each package's CMakeLists.txt (by relative
# path into the source tree), so that colcon's per-package builds and the root superbuild behave the same.
include_guard(GLOBAL)

if(NOT CMAKE_BUILD_TYPE AND NOT CMAKE_CONFIGURATION_TYPES)
  set(CMAKE_BUILD_TYPE Release CACHE STRING "Build type" FORCE)
endif()
set(CMAKE_CXX_STANDARD 20)
set(CMAKE_CXX_STANDARD_REQUIRED ON)
set(CMAKE_CXX_EXTENSIONS OFF)
set(CMAKE_POSITION_INDEPENDENT_CODE ON)
set(CMAKE_EXPORT_COMPILE_COMMANDS ON)

find_program(CAIRN_CCACHE ccache)
if(CAIRN_CCACHE AND NOT CMAKE_CXX_COMPILER_LAUNCHER)
  set(CMAKE_C_COMPILER_LAUNCHER ${CAIRN_CCACHE})
  set(CMAKE_CXX_COMPILER_LAUNCHER ${CAIRN_CCACHE})
endif()

option(CAIRN_WERROR "Treat warnings as errors (CI turns this on)" OFF)
option(CAIRN_BUILD_TESTS "Build cairn tests" ON)
option(CAIRN_BUILD_BENCHMARKS "Build cairn benchmarks" ON)
option(CAIRN_BUILD_FUZZERS "Build libFuzzer targets (needs clang)" OFF)
# -DCAIRN_SANITIZE=address,undefined builds everything (executables, component libraries, tests) with those
# sanitizers, so that the whole test suite can be run under them (docs/CONTRIBUTING.md).
set(CAIRN_SANITIZE "" CACHE STRING "Sanitizers for every target, e.g. address,undefined (empty: none)")
if(CAIRN_SANITIZE)
  # vptr (part of "undefined") is off: components are classes in dlopen'ed libraries whose typeinfo lives only
  # there, and tools that load one and call into it (cairn-log and the LogPlayer) would not link with it.
  add_compile_options(-fsanitize=${CAIRN_SANITIZE} -fno-sanitize=vptr -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_link_options(-fsanitize=${CAIRN_SANITIZE} -fno-sanitize=vptr)
endif()
# Options every test runs with under ThreadSanitizer (test/sanitizers/tsan.supp: Cyclone's own synchronisation).
set(CAIRN_TSAN_OPTIONS "suppressions=${CMAKE_CURRENT_LIST_DIR}/../test/sanitizers/tsan.supp")

# Warnings for cairn's own targets; third-party headers come in as SYSTEM so they stay quiet.
function(cairn_target_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra)
  if(CAIRN_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()

# cmake/include/cairn/strict_number.hpp (the one whole-string number parser) on a target's private include path.
# Build tree only: it is never installed, so no installed header may include it.
function(cairn_use_strict_number)
  foreach(t ${ARGN})
    target_include_directories(${t} PRIVATE ${CMAKE_CURRENT_FUNCTION_LIST_DIR}/include)
  endforeach()
endfunction()

# All executables (cairn, cairn-<verb> tools, tests) of one build tree land in <build>/bin, so that the
# `cairn` front end finds its `cairn-<verb>` tools next to itself.
if(NOT CMAKE_RUNTIME_OUTPUT_DIRECTORY)
  set(CMAKE_RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/bin)
endif()

# Root of the source tree (for data files in tests: ../shared lives next to it).
get_filename_component(CAIRN_SOURCE_ROOT "${CMAKE_CURRENT_LIST_DIR}/.." ABSOLUTE)

# Component libraries land in one directory so that the container finds them (build and install tree).
if(NOT CAIRN_COMPONENT_OUTPUT_DIR)
  set(CAIRN_COMPONENT_OUTPUT_DIR "${CMAKE_BINARY_DIR}/lib/cairn_components")
endif()

if(CAIRN_BUILD_TESTS)
  enable_testing()
  find_package(GTest REQUIRED)
  include(GoogleTest)
endif()

# cairn_add_gtest(name SOURCES a.cpp b.cpp LIBS x y [DDS])
# DDS tests link cairn::testing_main, which confines Cyclone to loopback and a random domain id.
function(cairn_add_gtest name)
  cmake_parse_arguments(ARG "DDS" "TIMEOUT" "SOURCES;LIBS" ${ARGN})
  if(NOT CAIRN_BUILD_TESTS)
    return()
  endif()
  add_executable(${name} ${ARG_SOURCES})
  cairn_target_warnings(${name})
  if(ARG_DDS)
    target_link_libraries(${name} PRIVATE ${ARG_LIBS} cairn::testing_main GTest::gtest)
  else()
    target_link_libraries(${name} PRIVATE ${ARG_LIBS} GTest::gtest_main)
  endif()
  target_compile_definitions(${name} PRIVATE CAIRN_SOURCE_ROOT="${CAIRN_SOURCE_ROOT}")
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 300)
  endif()
  add_test(NAME ${name} COMMAND ${name})
  set_tests_properties(${name} PROPERTIES TIMEOUT ${ARG_TIMEOUT}
    ENVIRONMENT "CAIRN_COMPONENT_PATH=${CAIRN_COMPONENT_OUTPUT_DIR};TSAN_OPTIONS=${CAIRN_TSAN_OPTIONS}")
endfunction()

# Installs a package's exported targets (TARGETS plus components added with cairn_add_component) with a
# <pkg>Config.cmake so that colcon's downstream packages
# can find_package() it.
function(cairn_install_package pkg)
  cmake_parse_arguments(ARG "" "" "TARGETS;DEPENDENCIES" ${ARGN})
  include(GNUInstallDirs)
  if(ARG_TARGETS)
    install(TARGETS ${ARG_TARGETS} EXPORT ${pkg}Targets
      LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
      ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
      RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
      INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  endif()
  install(EXPORT ${pkg}Targets NAMESPACE cairn:: DESTINATION share/${pkg}/cmake)
  set(deps "")
  foreach(d ${ARG_DEPENDENCIES})
    string(APPEND deps "find_dependency(${d})\n")
  endforeach()
  file(WRITE ${CMAKE_CURRENT_BINARY_DIR}/${pkg}Config.cmake
    "include(CMakeFindDependencyMacro)\n${deps}include(\${CMAKE_CURRENT_LIST_DIR}/cmake/${pkg}Targets.cmake)\n")
  install(FILES ${CMAKE_CURRENT_BINARY_DIR}/${pkg}Config.cmake DESTINATION share/${pkg})
endfunction()

# cairn_add_component(target SOURCES ... CLASSES ns::A ns::B LIBS ...)
# A shared library of components plus its index file <lib>.components (one class per line), both in
# lib/cairn_components/ of the build tree and of the install prefix, where the container looks for them.
function(cairn_add_component target)
  cmake_parse_arguments(ARG "" "" "SOURCES;CLASSES;LIBS" ${ARGN})
  add_library(${target} SHARED ${ARG_SOURCES})
  target_link_libraries(${target} PUBLIC ${ARG_LIBS})
  cairn_target_warnings(${target})
  set_target_properties(${target} PROPERTIES LIBRARY_OUTPUT_DIRECTORY ${CAIRN_COMPONENT_OUTPUT_DIR})
  string(REPLACE ";" "\n" _classes "${ARG_CLASSES}")
  file(GENERATE OUTPUT ${CAIRN_COMPONENT_OUTPUT_DIR}/$<TARGET_FILE_NAME:${target}>.components
       CONTENT "${_classes}\n")
  include(GNUInstallDirs)
  install(TARGETS ${target} EXPORT ${PROJECT_NAME}Targets LIBRARY DESTINATION lib/cairn_components)
  install(FILES ${CAIRN_COMPONENT_OUTPUT_DIR}/$<TARGET_FILE_NAME:${target}>.components DESTINATION lib/cairn_components)
endfunction()
