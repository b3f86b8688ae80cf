# Sanitizer and fuzzing builds (docs/RELIABILITY.md, "Always-on checks").
#
#   -DBOSFUSE_SANITIZE=address,undefined   ASan + UBSan on all bosfuse code and tests
#   -DBOSFUSE_SANITIZE=thread              TSan (scripts/check-sanitizers builds only
#                                          the threaded storage/acquisition tests)
#   -DBOSFUSE_FUZZ=ON                      clang-14 only: the libFuzzer targets in fuzz/,
#                                          the libraries instrumented for coverage + ASan/UBSan;
#                                          with BOSFUSE_SANITIZE=address,undefined the same build
#                                          also runs the ASan+UBSan suite (BOSFUSE_ASAN_FUZZ=1)
#
# The flags are added with add_compile_options/add_link_options before any
# bosfuse folder is added, so they reach every library, test and the
# executable; the Debian libraries (OpenCV, Ceres, SQLite, libstdc++) are not
# instrumented, which ASan/UBSan tolerate (TSan may report races inside them:
# see scripts/sanitizers/). -O1 -g keeps the build and the suite fast enough
# for CI while stacks stay readable (BOSFUSE_SANITIZE_OPT).

set(BOSFUSE_SANITIZE "" CACHE STRING "Sanitizers for all bosfuse code: empty, address,undefined, or thread")
set_property(CACHE BOSFUSE_SANITIZE PROPERTY STRINGS "" "address,undefined" "thread")
option(BOSFUSE_FUZZ "Build the libFuzzer targets in fuzz/ (needs clang++-14)" OFF)
# -O0 compiles about twice as fast as -O1 (app/cmd_replay.cc under ASan:
# 5.5 s against 11 s of CPU); -O1 runs the instrumented suite faster.
set(BOSFUSE_SANITIZE_OPT "-O1" CACHE STRING "Optimisation level of sanitizer and fuzzing builds")

# BOSFUSE_FUZZ is ASan+UBSan plus coverage: with BOSFUSE_SANITIZE empty or
# address,undefined (one build for the ASan suite and the fuzz targets).
if(BOSFUSE_FUZZ AND BOSFUSE_SANITIZE AND NOT BOSFUSE_SANITIZE MATCHES "^(address,undefined|undefined,address)$")
  message(FATAL_ERROR "BOSFUSE_FUZZ builds with address,undefined; BOSFUSE_SANITIZE=${BOSFUSE_SANITIZE} cannot join it")
endif()

set(_bosfuse_san_flags "")
if(BOSFUSE_SANITIZE STREQUAL "address,undefined" OR BOSFUSE_SANITIZE STREQUAL "undefined,address")
  # Every UBSan finding is an error (no recover), so a test fails at the first one.
  set(_bosfuse_san_flags -fsanitize=address,undefined -fno-sanitize-recover=undefined)
elseif(BOSFUSE_SANITIZE STREQUAL "thread")
  set(_bosfuse_san_flags -fsanitize=thread)
elseif(BOSFUSE_SANITIZE)
  message(FATAL_ERROR "BOSFUSE_SANITIZE='${BOSFUSE_SANITIZE}': use address,undefined or thread")
endif()

if(_bosfuse_san_flags AND NOT BOSFUSE_FUZZ)
  # -g1 (line tables) is enough for the sanitizers' stack traces and keeps
  # the objects and the links of the test binaries much smaller than -g.
  add_compile_options(${_bosfuse_san_flags} -fno-omit-frame-pointer ${BOSFUSE_SANITIZE_OPT} -g1)
  # Eigen allocates through its own aligned malloc when __SANITIZE_ADDRESS__
  # is defined, but the Debian Ceres library we link was built without it
  # and holds instantiations of the same Eigen templates (sparse orderings)
  # that use plain malloc; mixing the two frees memory the other allocated.
  # glibc's malloc (and ASan's) is 16-byte aligned on x86-64, as Eigen needs
  # there, so every unit uses it, as the Ceres library does.
  add_compile_definitions(EIGEN_MALLOC_ALREADY_ALIGNED=1)
  # What a test reads to know it runs instrumented (gcc defines
  # __SANITIZE_ADDRESS__, clang does not): memory figures mean nothing there.
  add_compile_definitions(BOSFUSE_SANITIZED=1)
  add_link_options(${_bosfuse_san_flags})
  message(STATUS "bosfuse: sanitizers ${BOSFUSE_SANITIZE} (${BOSFUSE_SANITIZE_OPT} -g1)")
endif()

if(BOSFUSE_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "BOSFUSE_FUZZ=ON needs clang (CXX=clang++-14), not ${CMAKE_CXX_COMPILER_ID}")
  endif()
  # Libraries get coverage instrumentation without libFuzzer's main; the
  # targets in fuzz/ link with -fsanitize=fuzzer. The tests and the
  # executable link without it: the coverage hooks have default no-op
  # definitions in the sanitizer runtime, so this one build also runs the
  # ASan+UBSan suite (scripts/check-sanitizers, scripts/fuzz-smoke).
  add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined
                      -fno-omit-frame-pointer ${BOSFUSE_SANITIZE_OPT} -g1)
  add_link_options(-fsanitize=address,undefined)
  add_compile_definitions(EIGEN_MALLOC_ALREADY_ALIGNED=1 BOSFUSE_SANITIZED=1)  # as for BOSFUSE_SANITIZE above
  message(STATUS "bosfuse: libFuzzer targets (fuzz/), libraries with fuzzer-no-link,address,undefined")
endif()

# Highway (fusion/simd_*.cc, one file per kernel family) compiles every kernel once per x86 target
# and picks one at run time; instrumented, that one file took 69 CPU-s with
# all five targets against 36 s with two. The instrumented builds compile
# only the target this machine's CPU runs (what the sanitizers then check,
# the path a release build takes here by default) and the portable baseline
# (BOSFUSE_SIMD=portable); the release build and its suite keep them all.
if(_bosfuse_san_flags OR BOSFUSE_FUZZ)
  try_run(_bosfuse_hwy_run _bosfuse_hwy_built
          SOURCES ${CMAKE_CURRENT_LIST_DIR}/probes/hwy_disabled_targets.cc
          LINK_LIBRARIES PkgConfig::HWY
          CXX_STANDARD 20
          COMPILE_OUTPUT_VARIABLE _bosfuse_hwy_log
          RUN_OUTPUT_VARIABLE _bosfuse_hwy_disabled)
  if(NOT _bosfuse_hwy_built OR NOT _bosfuse_hwy_run EQUAL 0 OR NOT _bosfuse_hwy_disabled MATCHES "^[0-9]+$")
    message(FATAL_ERROR "cmake/probes/hwy_disabled_targets.cc failed (${_bosfuse_hwy_run}): ${_bosfuse_hwy_log}")
  endif()
  # Set on the two files that include Highway (the top CMakeLists.txt), not
  # on every unit, whose commands and so ccache entries stay as they were.
  set(BOSFUSE_HWY_DISABLED_TARGETS ${_bosfuse_hwy_disabled})
  message(STATUS "bosfuse: instrumented Highway kernels for this CPU's best target and the baseline only (HWY_DISABLED_TARGETS=${_bosfuse_hwy_disabled})")
endif()

# Benchmarks of instrumented code measure nothing useful and cost build time.
if(BOSFUSE_SANITIZE OR BOSFUSE_FUZZ)
  set(_bosfuse_bench_default OFF)
else()
  set(_bosfuse_bench_default ON)
endif()
option(BOSFUSE_BENCH "Build the benchmarks in bench/" ${_bosfuse_bench_default})
