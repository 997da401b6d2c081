# FAISS (Debian's libfaiss-dev 1.7.3) is a static library built by GCC with OpenMP (libgomp). Its
# package config names OpenMP's target without finding it and links the system's default BLAS; the
# target is pointed at libgomp and at the reference (netlib) BLAS and LAPACK the rest of brittle
# links (FAISS's IVF k-means runs sgemm; CMakeLists.txt says why the reference ones), the same way
# in the main build and in the clang fuzz build.
find_library(BRITTLE_BLAS_LIBRARY blas PATHS /usr/lib/${CMAKE_LIBRARY_ARCHITECTURE}/blas NO_DEFAULT_PATH REQUIRED)
find_library(BRITTLE_LAPACK_LIBRARY lapack PATHS /usr/lib/${CMAKE_LIBRARY_ARCHITECTURE}/lapack NO_DEFAULT_PATH REQUIRED)
find_library(BRITTLE_GOMP_LIBRARY NAMES gomp libgomp.so.1 REQUIRED)
find_package(faiss REQUIRED CONFIG)
set_target_properties(faiss PROPERTIES INTERFACE_LINK_LIBRARIES
  "${BRITTLE_GOMP_LIBRARY};${BRITTLE_LAPACK_LIBRARY};${BRITTLE_BLAS_LIBRARY}")
