# bosfuse_library(NAME [ROOMS ...] [DEPS ...] [TEST_DEPS ...])
#   Builds bosfuse::NAME from the folder's *.cc files, and those of its ROOMS
#   (subfolders that split a large library by subject), tests excluded, and,
#   when they have *_test.cc files, a test binary NAME_test registered with
#   ctest. Tests sit next to the concept they test (foo.h, foo.cc,
#   foo_test.cc); new files are picked up at the next configure.
#   LOCKED_TESTS <gtest filter> <lock>: the tests matching the filter hold
#   that ctest RESOURCE_LOCK, so they never run side by side (a fixed port).
function(bosfuse_library name)
  cmake_parse_arguments(ARG "" "" "ROOMS;DEPS;TEST_DEPS;LOCKED_TESTS" ${ARGN})
  set(sources)
  set(tests)
  foreach(dir . ${ARG_ROOMS})
    file(GLOB dir_sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/${dir}/*.cc)
    file(GLOB dir_tests CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/${dir}/*_test.cc)
    list(APPEND sources ${dir_sources})
    list(APPEND tests ${dir_tests})
  endforeach()
  if(tests)
    list(REMOVE_ITEM sources ${tests})
  endif()
  if(NOT sources)
    return()  # the folder has no code yet
  endif()
  add_library(bosfuse_${name} STATIC ${sources})
  add_library(bosfuse::${name} ALIAS bosfuse_${name})
  target_include_directories(bosfuse_${name} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(bosfuse_${name} PUBLIC ${ARG_DEPS})
  if(tests)
    bosfuse_test(${name}_test SOURCES ${tests} DEPS bosfuse::${name} ${ARG_TEST_DEPS} LOCKED_TESTS ${ARG_LOCKED_TESTS})
  endif()
endfunction()

# bosfuse_test(NAME SOURCES ... DEPS ...): one gtest binary, its tests
# discovered individually so ctest reports each.
function(bosfuse_test name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;LOCKED_TESTS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} GTest::gtest GTest::gmock GTest::gtest_main)
  target_compile_definitions(${name} PRIVATE
    BOSFUSE_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    BOSFUSE_BINARY_DIR="${PROJECT_BINARY_DIR}")
  include(GoogleTest)
  # Names carry the binary (fitting_test.NewtonFit.X) so `ctest -R fitting` selects a library.
  if(ARG_LOCKED_TESTS)
    list(GET ARG_LOCKED_TESTS 0 locked_filter)
    list(GET ARG_LOCKED_TESTS 1 lock)
    gtest_discover_tests(${name} TEST_PREFIX "${name}." DISCOVERY_TIMEOUT 60 TEST_FILTER "-${locked_filter}"
      PROPERTIES TIMEOUT 300)
    gtest_discover_tests(${name} TEST_PREFIX "${name}." DISCOVERY_TIMEOUT 60 TEST_FILTER "${locked_filter}"
      PROPERTIES TIMEOUT 300 RESOURCE_LOCK ${lock})
  else()
    gtest_discover_tests(${name} TEST_PREFIX "${name}." DISCOVERY_TIMEOUT 60 PROPERTIES TIMEOUT 300)
  endif()
endfunction()
