# Every dependency is a Debian 12 package; scripts/bootstrap installs them.
find_package(Threads REQUIRED)
find_package(PkgConfig REQUIRED)
find_package(SQLite3 REQUIRED)
pkg_check_modules(MODBUS REQUIRED IMPORTED_TARGET libmodbus)
pkg_check_modules(HIDAPI REQUIRED IMPORTED_TARGET hidapi-hidraw)
pkg_check_modules(LIBUSB REQUIRED IMPORTED_TARGET libusb-1.0)
# GenICam cameras (acquisition/cameras/genicam_*): Aravis 0.8 (LGPL)
pkg_check_modules(ARAVIS REQUIRED IMPORTED_TARGET aravis-0.8)
pkg_check_modules(UMOCKDEV REQUIRED IMPORTED_TARGET umockdev-1.0)
# Report figures: PLplot's C library; its cairo driver (plplot-driver-cairo)
# provides the pngcairo and svgcairo devices, loaded at run time.
pkg_check_modules(PLPLOT REQUIRED IMPORTED_TARGET plplot)
# Field export (report/field_export.h): HDF5's C library, Debian's serial
# flavour (headers under /usr/include/hdf5/serial). Found through its
# pkg-config file rather than FindHDF5, whose C component would need the C
# language enabled for the whole project just for a test compile.
pkg_check_modules(HDF5 REQUIRED IMPORTED_TARGET hdf5)
find_package(OpenCV REQUIRED COMPONENTS core imgproc imgcodecs videoio video)
# The codecs' own libraries, to read an image's declared size from its header
# before OpenCV decodes it (acquisition/cameras/image_file.h). libopencv-dev brings
# their -dev packages.
find_package(PNG REQUIRED)
find_package(JPEG REQUIRED)
find_package(TIFF REQUIRED)
find_package(Eigen3 REQUIRED NO_MODULE)
find_package(Ceres REQUIRED)
# The temperature field's Poisson solve (fusion/temperature_field.h): CHOLMOD's
# supernodal Cholesky through Eigen's CholmodSupport. Debian's
# libsuitesparse-dev (Ceres' own dependency) has no CMake or pkg-config file
# for it, so the header and the library are found directly; libcholmod.so
# brings AMD, COLAMD, SuiteSparse_config and BLAS/LAPACK as its own needs.
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse REQUIRED)
find_library(CHOLMOD_LIBRARY cholmod REQUIRED)
add_library(bosfuse_cholmod INTERFACE IMPORTED)
set_target_properties(bosfuse_cholmod PROPERTIES INTERFACE_INCLUDE_DIRECTORIES ${CHOLMOD_INCLUDE_DIR}
                                                 INTERFACE_LINK_LIBRARIES ${CHOLMOD_LIBRARY})
find_package(CLI11 REQUIRED CONFIG)
find_package(tomlplusplus REQUIRED)
find_package(nlohmann_json REQUIRED)
find_package(spdlog REQUIRED)
# SIMD kernels (fusion/simd_kernels.h): Google Highway, one source compiled
# for each x86 target and dispatched at run time. Debian ships the shared
# library with a pkg-config file (its flags say the library is shared).
pkg_check_modules(HWY REQUIRED IMPORTED_TARGET libhwy)
# The live page (view/): cpp-httplib, which Debian ships as a compiled
# library with a pkg-config file, and Chart.js, served from Debian's copy so
# the page needs no network. The viewer also checks for the file at start.
pkg_check_modules(HTTPLIB REQUIRED IMPORTED_TARGET cpp-httplib)
set(BOSFUSE_CHARTJS_PATH /usr/share/javascript/chart.js/chart.min.js CACHE FILEPATH "Chart.js (UMD build) the live page serves")
if(NOT EXISTS ${BOSFUSE_CHARTJS_PATH})
  message(FATAL_ERROR "Chart.js not found at ${BOSFUSE_CHARTJS_PATH}: install Debian's libjs-chart.js")
endif()
find_package(GTest REQUIRED)
find_package(benchmark REQUIRED)
